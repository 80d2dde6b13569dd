// Reading KHR_physics_rigid_bodies: authored motion and joints, checked, with the precedence of
// docs/format.md ("KHR_physics_rigid_bodies").
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>

#include "khr_physics_frames.h"
#include "rdtf/completion.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/geometry.h"
#include "rdtf/khr_physics.h"
#include "rdtf/rdtf_extras.h"

namespace rdtf {
namespace {

// Attachment frames must coincide at rest within this (m, and rad as the largest column
// difference), the precision of float transforms a few metres from the origin. Positions are
// compared relative to their distance from the origin beyond 1 m (position_tolerance): two frames
// composed through different node chains round apart in proportion to how far out they are.
constexpr double kFrameTolerance = 1e-6;
// KHR values that equal the RDTF ones within this (relative) are the same (rdtf's own output).
constexpr double kAgree = 1e-9;
// |q| must be 1 within this (glTF's tolerance for node rotations is of this order).
constexpr double kUnitTolerance = 1e-6;

// The distance within which two points at p and q are the same point (m).
double position_tolerance(const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  return kFrameTolerance * std::max({1.0, p.norm(), q.norm()});
}

const Json* physics_of(const Json& node) {
  if (!node.is_object() || !node.contains("extensions") || !node["extensions"].is_object()) return nullptr;
  const Json& ext = node["extensions"];
  return ext.contains(kKhrPhysics) && ext[kKhrPhysics].is_object() ? &ext[kKhrPhysics] : nullptr;
}

std::string where(const Json& document, std::size_t node) { return node_label(document, node); }

// The link whose body holds each node (-1: none): the link owning it (owning_link_nodes).
std::vector<int> bodies(const Json& document, const std::vector<NodeType>& types, const Robot& robot) {
  const std::size_t count = document["nodes"].size();
  std::vector<int> link_of_node(count, -1);
  for (std::size_t l = 0; l < robot.links.size(); ++l) link_of_node[static_cast<std::size_t>(robot.links[l].node)] = static_cast<int>(l);
  const std::vector<int> owners = owning_link_nodes(document, types);
  std::vector<int> body(count, -1);
  for (std::size_t n = 0; n < owners.size(); ++n) {
    if (owners[n] >= 0) body[n] = link_of_node[static_cast<std::size_t>(owners[n])];
  }
  return body;
}

// A non-negative integer below `size` (parsed JSON holds them unsigned, a document built in
// memory may hold them signed).
std::optional<std::size_t> index_in(const Json& value, std::size_t size) {
  if (!value.is_number_integer() || value.get<std::int64_t>() < 0 ||
      static_cast<std::uint64_t>(value.get<std::int64_t>()) >= size) {
    return std::nullopt;
  }
  return static_cast<std::size_t>(value.get<std::int64_t>());
}

// Reads `count` finite numbers at key; nothing (and an error) when the value is not that.
template <int N>
std::optional<Eigen::Matrix<double, N, 1>> numbers(const Json& object, const char* key, const std::string& pointer,
                                                   const std::string& label, Diagnostics& diag) {
  const Json& value = object[key];
  bool ok = value.is_array() && value.size() == static_cast<std::size_t>(N);
  Eigen::Matrix<double, N, 1> out;
  for (int i = 0; ok && i < N; ++i) {
    ok = value[static_cast<std::size_t>(i)].is_number() && std::isfinite(value[static_cast<std::size_t>(i)].get<double>());
    if (ok) out(i) = value[static_cast<std::size_t>(i)].get<double>();
  }
  if (!ok) {
    diag.error(codes::KHR_PHYSICS_INVALID, json_pointer(pointer, key),
               label + ": " + key + " " + value_text(value) + " is not " + std::to_string(N) + " finite numbers");
    return std::nullopt;
  }
  return out;
}

bool close(double a, double b, double scale) { return std::abs(a - b) <= kAgree * std::max(scale, 1e-300); }

struct Motion {
  std::optional<double> mass;
  std::optional<Eigen::Vector3d> center;      // node space
  std::optional<Eigen::Vector3d> moments;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

std::optional<Motion> parse_motion(const Json& motion, const std::string& pointer, const std::string& label,
                                   Diagnostics& diag) {
  Motion out;
  bool ok = true;
  if (motion.contains("mass")) {
    const Json& m = motion["mass"];
    if (!m.is_number() || !std::isfinite(m.get<double>()) || m.get<double>() < 0) {
      diag.error(codes::KHR_PHYSICS_INVALID, pointer + "/mass",
                 label + ": mass " + value_text(m) + " is not a number >= 0 (kg)");
      ok = false;
    } else {
      out.mass = m.get<double>();
    }
  }
  if (motion.contains("centerOfMass")) {
    out.center = numbers<3>(motion, "centerOfMass", pointer, label, diag);
    ok &= out.center.has_value();
  }
  if (motion.contains("inertiaDiagonal")) {
    out.moments = numbers<3>(motion, "inertiaDiagonal", pointer, label, diag);
    if (out.moments && out.moments->minCoeff() < 0) {
      diag.error(codes::KHR_PHYSICS_INVALID, pointer + "/inertiaDiagonal",
                 label + ": inertiaDiagonal " + value_text(motion["inertiaDiagonal"]) + " has a negative moment");
      out.moments.reset();
    }
    ok &= out.moments.has_value();
  }
  if (motion.contains("inertiaOrientation")) {
    const auto q = numbers<4>(motion, "inertiaOrientation", pointer, label, diag);
    if (q && std::abs(q->norm() - 1) > kUnitTolerance) {
      diag.error(codes::KHR_PHYSICS_INVALID, pointer + "/inertiaOrientation",
                 label + ": inertiaOrientation " + value_text(motion["inertiaOrientation"]) +
                     " is not a unit quaternion (norm " + std::to_string(q->norm()) + ")");
      ok = false;
    } else if (q) {
      out.rotation = Eigen::Quaterniond((*q)(3), (*q)(0), (*q)(1), (*q)(2)).normalized();
    } else {
      ok = false;
    }
  }
  if (!ok) return std::nullopt;
  return out;
}

// True when RDTF describes the link's mass itself: an inertial in extras.RDTF or rdtf_inertial
// (computed or authored), or rdtf_mass / rdtf_density on the link node or its meshes.
bool rdtf_describes_mass(const Json& document, const Link& link) {
  const Json& nodes = document["nodes"];
  if (link.inertial_source == InertialSource::kAuthored) return true;
  const auto has_extra = [&](int node, const char* key) {
    const Json& n = nodes[static_cast<std::size_t>(node)];
    return n.contains("extras") && n["extras"].is_object() && n["extras"].contains(key);
  };
  if (link.inertial_node >= 0) {
    if (has_extra(link.inertial_node, "rdtf_inertial")) return true;
    if (document.contains("extras") && document["extras"].is_object() && document["extras"].contains("RDTF") &&
        document["extras"]["RDTF"].is_object() && document["extras"]["RDTF"].contains("nodes") &&
        document["extras"]["RDTF"]["nodes"].is_array()) {
      for (const Json& entry : document["extras"]["RDTF"]["nodes"]) {
        if (entry.is_object() && entry.contains("inertial") && entry.value("node", Json()) == Json(link.inertial_node)) {
          return true;
        }
      }
    }
  }
  if (has_extra(link.node, "rdtf_mass") || has_extra(link.node, "rdtf_density")) return true;
  return std::any_of(link.meshes.begin(), link.meshes.end(), [&](const LinkMesh& mesh) {
    return has_extra(mesh.node, "rdtf_mass") || has_extra(mesh.node, "rdtf_density");
  });
}

void read_motion(const Json& document, const std::vector<Eigen::Affine3d>& world, Link& link, Diagnostics& diag) {
  const Json* physics = physics_of(document["nodes"][static_cast<std::size_t>(link.node)]);
  if (physics == nullptr || !physics->contains("motion")) return;
  const std::string pointer = json_pointer("/nodes", static_cast<std::size_t>(link.node)) + "/extensions/" + kKhrPhysics + "/motion";
  const std::string label = where(document, static_cast<std::size_t>(link.node));
  if (!(*physics)["motion"].is_object()) {
    diag.error(codes::KHR_PHYSICS_INVALID, pointer, label + ": motion " + value_text((*physics)["motion"]) + " is not an object");
    return;
  }
  const auto motion = parse_motion((*physics)["motion"], pointer, label, diag);
  if (!motion || (!motion->mass && !motion->center && !motion->moments)) return;
  if ((motion->mass && *motion->mass == 0) || (motion->moments && motion->moments->minCoeff() == 0)) {
    diag.warning(codes::KHR_PHYSICS_IGNORED, pointer,
                 label + ": a mass or principal moment of 0 means infinite in KHR_physics_rigid_bodies, which a "
                         "robot link cannot have; the motion is ignored and the link's mass computed");
    return;
  }
  const MotionFrame frame = motion_frame(world, link);
  MassProperties khr = link.inertial;
  if (motion->mass) {
    // Mass alone scales the computed body (as rdtf_mass on a link node does).
    const double factor = link.inertial.mass > 0 ? *motion->mass / link.inertial.mass : 1.0;
    khr.mass = *motion->mass;
    khr.inertia = link.inertial.inertia * factor;
  }
  if (motion->center) khr.center_of_mass = frame.X_NL.inverse() * *motion->center;
  if (motion->moments) {
    const Eigen::Matrix3d I = frame.R_NL.transpose() * inertia_from_principal(*motion->moments, motion->rotation) * frame.R_NL;
    // Symmetric to the bit, as the six numbers RDTF writes will read back.
    khr.inertia = 0.5 * (I + I.transpose());
  }
  if (rdtf_describes_mass(document, link)) {
    const MassProperties& own = link.inertial;
    const double length = std::max(1.0, own.center_of_mass.norm());
    // Each quantity that differs, with both values (two equal masses were printed when only the
    // tensor differed: s90urdf D10).
    std::vector<std::string> differ;
    if (motion->mass && !close(khr.mass, own.mass, own.mass)) {
      differ.push_back("mass " + format_number(khr.mass, 10) + " kg against " + format_number(own.mass, 10) + " kg");
    }
    if (motion->center && (khr.center_of_mass - own.center_of_mass).norm() > kAgree * length) {
      differ.push_back("centre of mass " + vector_to_json(khr.center_of_mass).dump() + " m against " +
                       vector_to_json(own.center_of_mass).dump() + " m (link frame)");
    }
    if (motion->moments && (khr.inertia - own.inertia).cwiseAbs().maxCoeff() >
                               kAgree * std::max(own.inertia.cwiseAbs().maxCoeff(), 1e-300)) {
      const Eigen::Matrix3d& a = khr.inertia;
      const Eigen::Matrix3d& b = own.inertia;
      const auto six = [](const Eigen::Matrix3d& I) {
        return Json::array({I(0, 0), I(0, 1), I(0, 2), I(1, 1), I(1, 2), I(2, 2)}).dump();
      };
      differ.push_back("inertia [ixx, ixy, ixz, iyy, iyz, izz] " + six(a) + " against " + six(b) + " kg m^2");
    }
    if (!differ.empty()) {
      std::string text;
      for (std::size_t k = 0; k < differ.size(); ++k) text += (k ? "; " : "") + differ[k];
      diag.warning(codes::KHR_PHYSICS_IGNORED, pointer,
                   label + ": the KHR motion differs from the link's RDTF mass properties, which take precedence: " +
                       text);
    }
    return;
  }
  link.inertial = khr;
  link.inertial_source = InertialSource::kAuthored;
}

// One DOF's state in a KHR joint definition.
enum class Dof { kFree, kLocked, kLimited };

struct ParsedJoint {
  std::array<Dof, 6> dofs{};  // linear x, y, z, angular x, y, z
  std::array<double, 6> lower{}, upper{};
  std::array<double, 6> stiffness{}, damping{}, max_force{};
};

std::optional<ParsedJoint> parse_definition(const Json& definition, const std::string& pointer, Diagnostics& diag) {
  ParsedJoint out;
  out.dofs.fill(Dof::kFree);
  const auto bad = [&](const std::string& at, const std::string& what) {
    diag.error(codes::KHR_PHYSICS_INVALID, at, what);
    return std::nullopt;
  };
  if (!definition.is_object()) return bad(pointer, "physics joint " + value_text(definition) + " is not an object");
  const Json limits = definition.value("limits", Json::array());
  if (!limits.is_array()) return bad(pointer + "/limits", "limits " + value_text(limits) + " is not an array");
  for (std::size_t i = 0; i < limits.size(); ++i) {
    const Json& limit = limits[i];
    const std::string at = json_pointer(pointer + "/limits", i);
    if (!limit.is_object()) return bad(at, "limit " + value_text(limit) + " is not an object");
    const bool linear = limit.contains("linearAxes");
    if (linear == limit.contains("angularAxes")) return bad(at, "a limit needs exactly one of linearAxes, angularAxes");
    const Json& axes = limit[linear ? "linearAxes" : "angularAxes"];
    std::set<int> seen;
    if (!axes.is_array() || axes.empty() || axes.size() > 3) return bad(at, "axes " + value_text(axes) + " are not 1 to 3 indices");
    for (const Json& a : axes) {
      const auto axis = index_in(a, 3);
      if (!axis || !seen.insert(static_cast<int>(*axis)).second) {
        return bad(at, "axes " + value_text(axes) + " are not distinct indices 0, 1, 2");
      }
    }
    double lo = -INFINITY, hi = INFINITY;
    for (const auto& [key, value] : {std::pair{"min", &lo}, {"max", &hi}}) {
      if (!limit.contains(key)) continue;
      if (!limit[key].is_number()) return bad(at + "/" + key, std::string(key) + " " + value_text(limit[key]) + " is not a number");
      *value = limit[key].get<double>();
    }
    if (lo > hi) return bad(at, "min " + value_text(limit["min"]) + " is above max " + value_text(limit["max"]));
    const bool lock = lo == 0 && hi == 0;
    if (!lock && seen.size() > 1) {
      diag.warning(codes::KHR_PHYSICS_UNSUPPORTED, at,
                   "a " + std::to_string(seen.size()) + "-axis limit with a range (a cone or a distance) has no RDTF joint type");
      return std::nullopt;
    }
    for (int a : seen) {
      const std::size_t d = static_cast<std::size_t>(a + (linear ? 0 : 3));
      out.dofs[d] = lock ? Dof::kLocked : Dof::kLimited;
      out.lower[d] = lo;
      out.upper[d] = hi;
    }
  }
  const Json drives = definition.value("drives", Json::array());
  if (!drives.is_array()) return bad(pointer + "/drives", "drives " + value_text(drives) + " is not an array");
  for (std::size_t i = 0; i < drives.size(); ++i) {
    const Json& drive = drives[i];
    const std::string at = json_pointer(pointer + "/drives", i);
    if (!drive.is_object() || !drive.contains("axis") || !index_in(drive["axis"], 3) ||
        !drive.contains("type") || (drive["type"] != "linear" && drive["type"] != "angular")) {
      return bad(at, "drive " + value_text(drive) + " needs type linear or angular and axis 0, 1 or 2");
    }
    const std::size_t d = *index_in(drive["axis"], 3) + (drive["type"] == "linear" ? 0 : 3);
    for (const auto& [key, value] : {std::pair{"stiffness", &out.stiffness[d]}, {"damping", &out.damping[d]}, {"maxForce", &out.max_force[d]}}) {
      if (!drive.contains(key)) continue;
      if (!drive[key].is_number() || drive[key].get<double>() < 0) {
        return bad(at + "/" + key, std::string(key) + " " + value_text(drive[key]) + " is not a number >= 0");
      }
      *value = drive[key].get<double>();
    }
  }
  return out;
}

struct KhrJoint {
  JointKind kind = JointKind::kFixed;
  int dof = -1;  // The moving or normal DOF (0-5), -1 for none.
};

std::optional<KhrJoint> classify(const ParsedJoint& joint) {
  const auto count = [&](int from, Dof state) {
    return std::count(joint.dofs.begin() + from, joint.dofs.begin() + from + 3, state);
  };
  const auto single = [&](int from, Dof not_state) {
    for (int d = from; d < from + 3; ++d) {
      if (joint.dofs[static_cast<std::size_t>(d)] != not_state) return d;
    }
    return -1;
  };
  const long lin_locked = count(0, Dof::kLocked), ang_locked = count(3, Dof::kLocked);
  const long limited = count(0, Dof::kLimited) + count(3, Dof::kLimited);
  if (lin_locked == 3 && ang_locked == 3) return KhrJoint{JointKind::kFixed, -1};
  if (lin_locked == 3 && ang_locked == 2) {
    const int d = single(3, Dof::kLocked);
    return KhrJoint{joint.dofs[static_cast<std::size_t>(d)] == Dof::kLimited ? JointKind::kRevolute : JointKind::kContinuous, d};
  }
  if (ang_locked == 3 && lin_locked == 2) return KhrJoint{JointKind::kPrismatic, single(0, Dof::kLocked)};
  if (limited != 0) return std::nullopt;
  if (lin_locked == 0 && ang_locked == 0) return KhrJoint{JointKind::kFloating, -1};
  if (lin_locked == 3 && ang_locked == 0) return KhrJoint{JointKind::kBall, -1};
  if (lin_locked == 1 && ang_locked == 2) {
    const int normal = single(0, Dof::kFree);
    if (joint.dofs[static_cast<std::size_t>(normal + 3)] == Dof::kFree) return KhrJoint{JointKind::kPlanar, normal};
  }
  return std::nullopt;
}

// The robot joint a KHR joint gives, or nothing (and a diagnostic).
std::optional<Joint> joint_from_khr(const Json& document, const std::vector<Eigen::Affine3d>& world, const Robot& robot,
                                    const Joint& rdtf, const KhrJointRef& ref, bool parent_side, Diagnostics& diag) {
  const std::string pointer = json_pointer("/nodes", static_cast<std::size_t>(ref.node)) + "/extensions/" + kKhrPhysics + "/joint";
  const std::string label = where(document, static_cast<std::size_t>(ref.node));
  const Eigen::Isometry3d X_SA = rigid_part(world[static_cast<std::size_t>(ref.node)]);
  const Eigen::Isometry3d X_SB = rigid_part(world[static_cast<std::size_t>(ref.connected)]);
  const double offset = (X_SA.translation() - X_SB.translation()).norm();
  const double turn = (X_SA.linear() - X_SB.linear()).cwiseAbs().maxCoeff();
  if (offset > position_tolerance(X_SA.translation(), X_SB.translation()) || turn > kFrameTolerance) {
    diag.error(codes::KHR_JOINT_FRAMES_DISAGREE, pointer,
               label + ": its frame and that of its connectedNode " + where(document, static_cast<std::size_t>(ref.connected)) +
                   " differ at rest (" + std::to_string(offset) + " m apart, axes differing by up to " + std::to_string(turn) +
                   "): the draft requires them to coincide");
    return std::nullopt;
  }
  const std::string def_pointer = json_pointer(std::string("/extensions/") + kKhrPhysics + "/physicsJoints", static_cast<std::size_t>(ref.definition));
  const auto parsed = parse_definition(document["extensions"][kKhrPhysics]["physicsJoints"][static_cast<std::size_t>(ref.definition)], def_pointer, diag);
  if (!parsed) return std::nullopt;
  const auto kind = classify(*parsed);
  if (!kind) {
    diag.warning(codes::KHR_PHYSICS_UNSUPPORTED, def_pointer,
                 label + ": the limits of its physics joint make no RDTF joint type (fixed, revolute, continuous, "
                         "prismatic, planar, ball, floating); the joint is left as RDTF gives it");
    return std::nullopt;
  }
  Joint out = rdtf;
  out.kind = kind->kind;
  out.limits.reset();
  out.damping = out.spring_stiffness = out.friction = 0;
  const Link& child = robot.links[static_cast<std::size_t>(rdtf.child_link)];
  if (kind->dof >= 0) {
    const std::size_t d = static_cast<std::size_t>(kind->dof);
    // The connected node moves relative to the joint's node: from the parent's side that is the
    // child's motion; from the child's side its opposite.
    const double sign = parent_side ? 1.0 : -1.0;
    const Eigen::Vector3d a_S = sign * X_SA.linear().col(static_cast<Eigen::Index>(d % 3));
    out.axis = (child.X_SL.linear().transpose() * a_S).normalized();
    const bool turns = kind->kind == JointKind::kRevolute || kind->kind == JointKind::kContinuous;
    if (turns) {
      // Turning about a line through the attachment frame's origin: RDTF turns about the joint
      // frame's origin, so that origin must be on the line.
      const Eigen::Vector3d r = X_SA.translation() - child.X_SL.translation();
      const double off_axis = (r - r.dot(a_S) * a_S).norm();
      if (off_axis > position_tolerance(X_SA.translation(), child.X_SL.translation())) {
        diag.warning(codes::KHR_PHYSICS_UNSUPPORTED, pointer,
                     label + ": its pivot is " + std::to_string(off_axis) + " m off the axis through the RDTF joint frame " +
                         where(document, static_cast<std::size_t>(rdtf.frame_node)) +
                         "; put the joint node (or the child link's origin) at the pivot. The joint is left as RDTF gives it");
        return std::nullopt;
      }
    }
    if (parsed->dofs[d] == Dof::kLimited) {
      JointLimits limits;
      limits.lower = parent_side ? parsed->lower[d] : -parsed->upper[d];
      limits.upper = parent_side ? parsed->upper[d] : -parsed->lower[d];
      limits.effort = parsed->max_force[d];
      if (!std::isfinite(limits.lower) || !std::isfinite(limits.upper)) {
        diag.warning(codes::KHR_PHYSICS_UNSUPPORTED, def_pointer,
                     label + ": a one-sided limit has no RDTF form (lower and upper are both needed); the joint is left as RDTF gives it");
        return std::nullopt;
      }
      out.limits = limits;
    } else if (parsed->max_force[d] > 0) {  // A free axis with a drive's maxForce: effort alone.
      JointLimits limits;
      limits.effort = parsed->max_force[d];
      limits.position = false;
      out.limits = limits;
    }
    out.damping = parsed->damping[d];
    out.spring_stiffness = parsed->stiffness[d];
  }
  return out;
}

// The draft has one form for joints that move alike: a revolute joint without lower and upper
// turns as a continuous one does (no limit on the angular axis), and a revolute or prismatic joint
// with the range [0, 0] is as locked as a fixed one (its axis limited to 0, as the others).
JointKind motion_kind(const Joint& joint) {
  if (joint.kind == JointKind::kRevolute && !position_limited(joint)) return JointKind::kContinuous;
  if (position_limited(joint) && joint.limits->lower == 0 && joint.limits->upper == 0) return JointKind::kFixed;
  return joint.kind;
}

std::string limits_text(const Joint& joint) {
  return position_limited(joint) ? "[" + value_text(joint.limits->lower) + ", " + value_text(joint.limits->upper) + "]"
                                 : std::string("none");
}

// How the KHR joint `khr` differs from the RDTF joint `rdtf`, in words; nothing when they agree.
std::optional<std::string> joint_difference(const Joint& khr, const Joint& rdtf) {
  const JointKind kind = motion_kind(rdtf);
  if (motion_kind(khr) != kind) {
    // Same kinds, other motions (a [0, 0] range locks a revolute joint): the limits say why
    // ("type revolute against revolute" said nothing: s90urdf D7).
    if (khr.kind == rdtf.kind) return "limits " + limits_text(khr) + " against " + limits_text(rdtf);
    return std::string("type ") + to_string(khr.kind) + " against " + to_string(rdtf.kind);
  }
  if (kind == JointKind::kFixed) return std::nullopt;  // Nothing moves: no axis, range or drive.
  if (position_limited(khr) != position_limited(rdtf) ||
      (position_limited(khr) &&
       (!close(khr.limits->lower, rdtf.limits->lower, std::max(1.0, std::abs(rdtf.limits->lower))) ||
        !close(khr.limits->upper, rdtf.limits->upper, std::max(1.0, std::abs(rdtf.limits->upper)))))) {
    return "limits " + limits_text(khr) + " against " + limits_text(rdtf);
  }
  const bool has_axis = rdtf.kind != JointKind::kFixed && rdtf.kind != JointKind::kFloating && rdtf.kind != JointKind::kBall;
  if (has_axis && (khr.axis - rdtf.axis).norm() > kAgree) {
    return "axis " + vector_to_json(khr.axis).dump() + " against " + vector_to_json(rdtf.axis).dump();
  }
  if (!close(khr.damping, rdtf.damping, std::max(1.0, rdtf.damping))) {
    return "damping " + value_text(khr.damping) + " against " + value_text(rdtf.damping);
  }
  if (!close(khr.spring_stiffness, rdtf.spring_stiffness, std::max(1.0, rdtf.spring_stiffness))) {
    return "spring stiffness " + value_text(khr.spring_stiffness) + " against " + value_text(rdtf.spring_stiffness);
  }
  return std::nullopt;
}

}  // namespace

std::vector<std::optional<KhrJointRef>> khr_joints_of_robot(const Json& document, const std::vector<NodeType>& types,
                                                            const Robot& robot) {
  std::vector<std::optional<KhrJointRef>> out(robot.joints.size());
  if (!document.contains("nodes")) return out;
  const Json& nodes = document["nodes"];
  std::size_t definitions = 0;
  if (document.contains("extensions") && document["extensions"].is_object() && document["extensions"].contains(kKhrPhysics) &&
      document["extensions"][kKhrPhysics].is_object() && document["extensions"][kKhrPhysics].contains("physicsJoints") &&
      document["extensions"][kKhrPhysics]["physicsJoints"].is_array()) {
    definitions = document["extensions"][kKhrPhysics]["physicsJoints"].size();
  }
  const auto body = bodies(document, types, robot);
  std::map<std::pair<int, int>, std::size_t> joint_of_links;
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    joint_of_links[{robot.joints[j].parent_link, robot.joints[j].child_link}] = j;
  }
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    const Json* physics = physics_of(nodes[n]);
    if (physics == nullptr || !physics->contains("joint") || !(*physics)["joint"].is_object()) continue;
    const Json& joint = (*physics)["joint"];
    const auto connected = index_in(joint.value("connectedNode", Json()), nodes.size());
    const auto definition = index_in(joint.value("joint", Json()), definitions);
    if (!connected || !definition || n >= body.size() || *connected >= body.size()) continue;
    const int a = body[n], b = body[*connected];
    for (const auto& key : {std::pair{a, b}, std::pair{b, a}}) {
      const auto found = joint_of_links.find(key);
      if (found != joint_of_links.end() && !out[found->second]) {
        out[found->second] = KhrJointRef{static_cast<int>(n), static_cast<int>(*connected), static_cast<int>(*definition)};
      }
    }
  }
  return out;
}

void read_khr_physics(const Json& document, const std::vector<NodeType>& types, Robot& robot, Diagnostics& diag) {
  if (!document.contains("nodes") || robot.links.empty()) return;
  const Json& nodes = document["nodes"];
  const auto world = node_world_transforms(document);
  for (Link& link : robot.links) read_motion(document, world, link, diag);

  // Every KHR joint's references, so that a broken one is named even when it joins no robot joint.
  std::size_t definitions = 0;
  const bool has_top = document.contains("extensions") && document["extensions"].is_object() &&
                       document["extensions"].contains(kKhrPhysics) && document["extensions"][kKhrPhysics].is_object();
  if (has_top && document["extensions"][kKhrPhysics].contains("physicsJoints")) {
    const Json& list = document["extensions"][kKhrPhysics]["physicsJoints"];
    if (list.is_array()) {
      definitions = list.size();
    } else {
      diag.error(codes::KHR_PHYSICS_INVALID, std::string("/extensions/") + kKhrPhysics + "/physicsJoints",
                 "physicsJoints " + value_text(list) + " is not an array");
    }
  }
  const auto body = bodies(document, types, robot);
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    const Json* physics = physics_of(nodes[n]);
    if (physics == nullptr || !physics->contains("joint")) continue;
    const std::string pointer = json_pointer("/nodes", n) + "/extensions/" + kKhrPhysics + "/joint";
    const Json& joint = (*physics)["joint"];
    const std::string label = where(document, n);
    if (!joint.is_object()) {
      diag.error(codes::KHR_PHYSICS_INVALID, pointer, label + ": joint " + value_text(joint) + " is not an object");
      continue;
    }
    const auto connected = index_in(joint.value("connectedNode", Json()), nodes.size());
    if (!connected || *connected == n) {
      diag.error(codes::KHR_PHYSICS_INVALID, pointer + "/connectedNode",
                 label + ": connectedNode " + value_text(joint.value("connectedNode", Json())) + " is not another node's index (" +
                     std::to_string(nodes.size()) + " nodes)");
    }
    if (!index_in(joint.value("joint", Json()), definitions)) {
      diag.error(codes::KHR_PHYSICS_INVALID, pointer + "/joint",
                 label + ": joint " + value_text(joint.value("joint", Json())) + " is not an index into physicsJoints (" +
                     std::to_string(definitions) + " of them)");
    }
    if (!connected || n >= body.size() || *connected >= body.size()) continue;
    const int a = body[n], b = body[*connected];
    const bool joins = std::any_of(robot.joints.begin(), robot.joints.end(), [&](const Joint& j) {
      return (j.parent_link == a && j.child_link == b) || (j.parent_link == b && j.child_link == a);
    });
    if (!joins) {
      diag.warning(codes::KHR_PHYSICS_UNSUPPORTED, pointer,
                   label + " and its connectedNode " + where(document, *connected) +
                       " are not in a parent link and its child link of the node tree; rdtf reads KHR joints only "
                       "where the tree has a joint (a robot is a tree), so this one is not read");
    }
  }
  if (diag.has_errors()) return;

  const auto refs = khr_joints_of_robot(document, types, robot);
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    if (!refs[j]) continue;
    Joint& joint = robot.joints[j];
    const bool parent_side = body[static_cast<std::size_t>(refs[j]->node)] == joint.parent_link;
    const auto khr = joint_from_khr(document, world, robot, joint, *refs[j], parent_side, diag);
    if (!khr) continue;
    if (joint.source_node < 0) {
      joint = *khr;  // No RDTF properties: the KHR joint is the joint.
    } else if (const auto difference = joint_difference(*khr, joint)) {
      diag.warning(codes::KHR_PHYSICS_IGNORED, json_pointer("/nodes", static_cast<std::size_t>(refs[j]->node)) + "/extensions/" + kKhrPhysics + "/joint",
                   where(document, static_cast<std::size_t>(refs[j]->node)) + ": the KHR joint (" + to_string(khr->kind) +
                       ") differs from joint '" + joint.name + "' as RDTF describes it (" + to_string(joint.kind) +
                       ", from " + where(document, static_cast<std::size_t>(joint.source_node)) + "): " + *difference +
                       "; RDTF's takes precedence");
    }
  }
}

}  // namespace rdtf
