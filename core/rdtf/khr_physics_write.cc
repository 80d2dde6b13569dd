// Writing KHR_physics_rigid_bodies: motion on link nodes, joints through attachment nodes.
#include <algorithm>
#include <cmath>
#include <optional>

#include <Eigen/Eigenvalues>

#include "khr_physics_frames.h"
#include "rdtf/completion.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/geometry.h"
#include "rdtf/khr_physics.h"
#include "rdtf/rdtf_extras.h"

namespace rdtf {
namespace {

// Moments closer than this (relative to the largest) are one repeated moment, whose eigenvectors
// the solver may turn anywhere in their plane: a fixed basis is chosen instead. The tensor it
// gives differs from the input by at most this times the largest moment.
constexpr double kRepeatedMoment = 1e-14;

// Column signed so that its largest component is positive (ties: the first).
Eigen::Vector3d canonical_sign(const Eigen::Vector3d& v) {
  Eigen::Index largest = 0;
  v.cwiseAbs().maxCoeff(&largest);
  return v(largest) < 0 ? Eigen::Vector3d(-v) : v;
}

// A unit vector perpendicular to `a`, from the coordinate axis least aligned with it.
Eigen::Vector3d perpendicular(const Eigen::Vector3d& a) {
  Eigen::Index least = 0;
  a.cwiseAbs().minCoeff(&least);
  const Eigen::Vector3d e = Eigen::Vector3d::Unit(least);
  return (e - e.dot(a) * a).normalized();
}

Json quaternion_to_json(const Eigen::Quaterniond& q) { return Json::array({q.x(), q.y(), q.z(), q.w()}); }

Json limit(const char* axes_key, std::initializer_list<unsigned> axes, double min, double max) {
  Json list = Json::array();
  for (unsigned a : axes) list.push_back(a);
  return Json{{axes_key, std::move(list)}, {"min", min}, {"max", max}};
}

// The draft's composition of a joint from limits on the attachment frame's axes; the joint axis is
// the frame's X (axis 0).
Json physics_joint(const Joint& joint) {
  Json limits = Json::array();
  const bool limited = position_limited(joint);  // A continuous joint, or effort alone: free.
  switch (joint.kind) {
    case JointKind::kFixed:
      limits.push_back(limit("linearAxes", {0, 1, 2}, 0, 0));
      limits.push_back(limit("angularAxes", {0, 1, 2}, 0, 0));
      break;
    case JointKind::kRevolute:
    case JointKind::kContinuous:
      limits.push_back(limit("linearAxes", {0, 1, 2}, 0, 0));
      limits.push_back(limit("angularAxes", {1, 2}, 0, 0));
      if (limited) limits.push_back(limit("angularAxes", {0}, joint.limits->lower, joint.limits->upper));
      break;
    case JointKind::kPrismatic:
      limits.push_back(limit("linearAxes", {1, 2}, 0, 0));
      limits.push_back(limit("angularAxes", {0, 1, 2}, 0, 0));
      if (limited) limits.push_back(limit("linearAxes", {0}, joint.limits->lower, joint.limits->upper));
      break;
    case JointKind::kPlanar:  // The axis is the plane's normal: no motion along it, turning about it.
      limits.push_back(limit("linearAxes", {0}, 0, 0));
      limits.push_back(limit("angularAxes", {1, 2}, 0, 0));
      break;
    case JointKind::kBall:
      limits.push_back(limit("linearAxes", {0, 1, 2}, 0, 0));
      break;
    case JointKind::kFloating:
      break;
  }
  Json out{{"limits", std::move(limits)}};
  const bool moves = joint.kind == JointKind::kRevolute || joint.kind == JointKind::kContinuous ||
                     joint.kind == JointKind::kPrismatic;
  if (moves && (joint.damping != 0 || joint.spring_stiffness != 0)) {
    Json drive{{"type", joint.kind == JointKind::kPrismatic ? "linear" : "angular"},
               {"mode", "force"},
               {"axis", 0u},
               {"positionTarget", 0.0},
               {"velocityTarget", 0.0},
               {"stiffness", joint.spring_stiffness},
               {"damping", joint.damping}};
    if (joint.limits && joint.limits->effort > 0) drive["maxForce"] = joint.limits->effort;
    out["drives"] = Json::array({std::move(drive)});
  }
  return out;
}

// The node's KHR_physics_rigid_bodies object, made when absent; nothing when something else is
// in its place (left alone).
Json* node_physics(Json& node) {
  if (!node.contains("extensions")) node["extensions"] = Json::object();
  if (!node["extensions"].is_object()) return nullptr;
  Json& ext = node["extensions"];
  if (!ext.contains(kKhrPhysics)) ext[kKhrPhysics] = Json::object();
  return ext[kKhrPhysics].is_object() ? &ext[kKhrPhysics] : nullptr;
}

// An attachment node's local transform under a node at X_SP for the frame X_SA in the scene:
// translation exact; rotation the one whose frame, scale removed (rigid_part, as RDTF's link
// frames), is X_SA's. That holds under any parent scale (polar(S polar(S^-1 Q)) = Q); the check
// guards against rounding. Nothing when it fails: such a joint gets no KHR joint rather than one
// whose frames disagree.
std::optional<Eigen::Isometry3d> attachment_local(const Eigen::Affine3d& X_SP, const Eigen::Isometry3d& X_SA) {
  // Under a mirror a node of translation and rotation is mirrored too, and a KHR reader takes a
  // joint's frame as the node's: its angles would turn the other way.
  if (X_SP.linear().determinant() < 0) return std::nullopt;
  const Eigen::Affine3d X_PS = X_SP.inverse();
  Eigen::Isometry3d X_PA = Eigen::Isometry3d::Identity();
  X_PA.translation() = X_PS * X_SA.translation();
  X_PA.linear() = rigid_part(Eigen::Affine3d(Eigen::Matrix3d(X_PS.linear() * X_SA.linear()))).linear();
  const Eigen::Isometry3d reached = rigid_part(X_SP * Eigen::Affine3d(X_PA.matrix()));
  const double length = std::max(1.0, X_SA.translation().norm());
  if ((reached.translation() - X_SA.translation()).norm() > 1e-12 * length ||
      (reached.linear() - X_SA.linear()).cwiseAbs().maxCoeff() > 1e-12) {
    return std::nullopt;
  }
  return X_PA;
}

std::size_t append_attachment(Json& document, std::vector<NodeType>& types, int parent, const std::string& name,
                              const Eigen::Isometry3d& X_PA) {
  Eigen::Quaterniond q(X_PA.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  Json node{{"name", name}};
  if (!X_PA.translation().isZero(0)) node["translation"] = vector_to_json(X_PA.translation());
  if (!q.isApprox(Eigen::Quaterniond::Identity(), 0)) node["rotation"] = quaternion_to_json(q);
  Json& nodes = document["nodes"];
  nodes.push_back(std::move(node));
  const std::size_t index = nodes.size() - 1;
  Json& parent_node = nodes[static_cast<std::size_t>(parent)];
  if (!parent_node.contains("children")) parent_node["children"] = Json::array();
  parent_node["children"].push_back(index);
  types.push_back(NodeType::kVisual);
  return index;
}

}  // namespace

PrincipalInertia principal_inertia(const Eigen::Matrix3d& inertia) {
  const Eigen::Matrix3d I = 0.5 * (inertia + inertia.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(I);
  PrincipalInertia out;
  out.moments = solver.eigenvalues();  // Ascending.
  Eigen::Matrix3d V = solver.eigenvectors();
  const double scale = std::max(out.moments.cwiseAbs().maxCoeff(), 1e-300);
  const bool low_pair = out.moments(1) - out.moments(0) <= kRepeatedMoment * scale;
  const bool high_pair = out.moments(2) - out.moments(1) <= kRepeatedMoment * scale;
  if (low_pair && high_pair) {
    V.setIdentity();
  } else if (low_pair) {
    // The single moment's axis is well defined; the pair's plane gets a fixed basis in it.
    const Eigen::Vector3d a = canonical_sign(V.col(2));
    V.col(0) = perpendicular(a);
    V.col(1) = a.cross(V.col(0));
  } else if (high_pair) {
    const Eigen::Vector3d a = canonical_sign(V.col(0));
    V.col(0) = a;
    V.col(1) = perpendicular(a);
  } else {
    V.col(0) = canonical_sign(V.col(0));
    V.col(1) = canonical_sign(V.col(1));
  }
  // A proper rotation: the third column follows from the first two.
  V.col(2) = V.col(0).cross(V.col(1));
  out.rotation = Eigen::Quaterniond(V);
  out.rotation.normalize();
  if (out.rotation.w() < 0) out.rotation.coeffs() = -out.rotation.coeffs();
  return out;
}

Eigen::Matrix3d inertia_from_principal(const Eigen::Vector3d& moments, const Eigen::Quaterniond& rotation) {
  const Eigen::Matrix3d R = rotation.normalized().toRotationMatrix();
  return R * moments.asDiagonal() * R.transpose();
}

void write_khr_physics(Json& document, std::vector<NodeType>& types, const Robot& robot, Diagnostics& diag) {
  if (!document.contains("nodes") || robot.links.empty()) return;
  if (document.contains("extensions") && !document["extensions"].is_object()) return;
  const auto existing = khr_joints_of_robot(document, types, robot);
  const auto world = node_world_transforms(document);

  for (const Link& link : robot.links) {
    Json* physics = node_physics(document["nodes"][static_cast<std::size_t>(link.node)]);
    if (physics == nullptr) continue;
    Json& motion = (*physics)["motion"];
    if (!motion.is_object()) motion = Json::object();
    for (const char* key : {"mass", "centerOfMass", "inertiaDiagonal", "inertiaOrientation"}) motion.erase(key);
    // A mass of zero means infinite in the draft: a massless link gets none (the reader's default).
    if (!(link.inertial.mass > 0)) continue;
    const MotionFrame frame = motion_frame(world, link);
    motion["mass"] = link.inertial.mass;
    motion["centerOfMass"] = vector_to_json(frame.X_NL * link.inertial.center_of_mass);
    const PrincipalInertia principal = principal_inertia(frame.R_NL * link.inertial.inertia * frame.R_NL.transpose());
    // A zero moment would read as infinite: a tensor with one is left to the reader.
    if (principal.moments.minCoeff() > 0) {
      motion["inertiaDiagonal"] = vector_to_json(principal.moments);
      motion["inertiaOrientation"] = quaternion_to_json(principal.rotation);
    }
  }

  Json& extension = document["extensions"][kKhrPhysics];
  if (!extension.is_object()) extension = Json::object();
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    if (existing[j]) continue;  // An authored KHR joint for it is kept (read_khr_physics compared it).
    const Joint& joint = robot.joints[j];
    const Link& parent = robot.links[static_cast<std::size_t>(joint.parent_link)];
    const Link& child = robot.links[static_cast<std::size_t>(joint.child_link)];
    // The attachment frame: the joint frame (the child link frame) turned so that X is the axis.
    Eigen::Matrix3d R_LA = Eigen::Matrix3d::Identity();
    if (joint.kind != JointKind::kFixed && joint.kind != JointKind::kFloating && joint.kind != JointKind::kBall) {
      const Eigen::Vector3d a = joint.axis.normalized();
      const Eigen::Vector3d u = perpendicular(a);
      R_LA.col(0) = a;
      R_LA.col(1) = u;
      R_LA.col(2) = a.cross(u);
    }
    Eigen::Isometry3d X_SA = child.X_SL;
    X_SA.linear() = child.X_SL.linear() * R_LA;
    const auto X_PA = attachment_local(world[static_cast<std::size_t>(parent.node)], X_SA);
    const auto X_CA = attachment_local(world[static_cast<std::size_t>(child.node)], X_SA);
    if (!X_PA || !X_CA) {
      // Under a mirror (a negative scale) a node of translation and rotation has a mirrored frame,
      // which no KHR joint frame may be. The joint is in extras.RDTF and the URDF; a tool reading
      // KHR physics alone sees its two bodies unjoined, so say so.
      // A scale of 0 (on an axis) leaves no frame at all: that, not a mirror, is then the reason.
      const Link& mirrored = X_PA ? child : parent;
      const double det = world[static_cast<std::size_t>(mirrored.node)].linear().determinant();
      const std::string why = det < 0    ? "is mirrored (a negative scale on its node or above)"
                              : det == 0 ? "is scaled to nothing on an axis (a scale of 0 on its node or above)"
                                         : "has a scale on its node or above under which its joint frame cannot be "
                                           "placed to within rounding";
      diag.warning(codes::KHR_JOINT_NOT_WRITTEN, "/nodes/" + std::to_string(joint.node),
                   "joint '" + joint.name + "' (" + to_string(joint.kind) + "): no KHR_physics_rigid_bodies joint is "
                   "written for it: link '" + mirrored.name + "' " + why +
                   ", and no attachment node of translation and rotation has a proper joint frame there. extras.RDTF "
                   "and the URDF have the joint; a tool reading only KHR physics sees its two bodies unjoined. " +
                       (det == 0 ? std::string("Give the node a scale other than 0 to keep it")
                                 : std::string("Apply the scale (Blender: Ctrl+A > Scale; for a mesh several objects "
                                               "share, a linked duplicate, first Object > Relations > Make Single "
                                               "User > Object & Data) to keep it")));
      continue;
    }
    if (!extension.contains("physicsJoints") || !extension["physicsJoints"].is_array()) {
      extension["physicsJoints"] = Json::array();
    }
    extension["physicsJoints"].push_back(physics_joint(joint));
    const std::size_t definition = extension["physicsJoints"].size() - 1;
    // On the parent's side, so that the connected (child) node's position in the joint frame is
    // the joint position with RDTF's sign.
    const std::size_t on_parent = append_attachment(document, types, parent.node, joint.name + "_khr_parent", *X_PA);
    const std::size_t on_child = append_attachment(document, types, child.node, joint.name + "_khr_child", *X_CA);
    Json* physics = node_physics(document["nodes"][on_parent]);
    (*physics)["joint"] = Json{{"connectedNode", on_child}, {"joint", definition}};
  }
  if (extension.empty()) document["extensions"].erase(kKhrPhysics);
  if (document["extensions"].empty()) document.erase("extensions");

  if (!document.contains("extensionsUsed") || !document["extensionsUsed"].is_array()) {
    document["extensionsUsed"] = Json::array();
  }
  Json& used = document["extensionsUsed"];
  if (std::find(used.begin(), used.end(), Json(kKhrPhysics)) == used.end()) used.push_back(kKhrPhysics);
}

}  // namespace rdtf
