// RDTF -> URDF with urdfdom's own model types and exporter. docs/urdf.md describes the mapping.
#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <set>

#include <urdf_parser/urdf_parser.h>

#include "rdtf/atomic_file.h"
#include "rdtf/urdf.h"
#include "rdtf/urdf_names.h"
#include "urdf_check.h"
#include "urdf_internal.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

using namespace urdf_internal;

urdf::Vector3 to_urdf(const Eigen::Vector3d& v) { return urdf::Vector3(v.x(), v.y(), v.z()); }

std::string node_pointer(int node) { return node >= 0 ? json_pointer("/nodes", node) : ""; }

// URDF's <limit> requires effort and velocity, and tools read 0 as "cannot move" (Gazebo,
// ros2_control, PyBullet). A joint that authored neither gets these instead: far above what any
// robot modelled for rdtf applies (1 MN m, 1000 rad/s), so they never bind; docs/urdf.md.
constexpr double kUnsetEffort = 1.0e6;    // N m or N
constexpr double kUnsetVelocity = 1.0e3;  // rad/s or m/s

// The joint type in URDF, or nothing (and an error) when URDF cannot say it.
// `parent_is_root`: the joint's parent link is a root; `below_world`: a root named "world", which
// MuJoCo's URDF reader takes as its world body, so the child is a top-level body.
std::optional<int> urdf_joint_type(const Joint& joint, const std::string& name, bool parent_is_root, bool below_world,
                                   Diagnostics& diag) {
  const std::string pointer = node_pointer(joint.node);
  switch (joint.kind) {
    case JointKind::kFixed:
      return urdf::Joint::FIXED;
    case JointKind::kContinuous:
      return urdf::Joint::CONTINUOUS;
    case JointKind::kFloating:
      // Valid URDF, which check_urdf and urdfdom accept, but every URDF joint hangs below a link:
      // MuJoCo makes it a free joint of a nested body and refuses the file, and ROS's
      // robot_state_publisher publishes no transform for it.
      // Below a root named "world" MuJoCo takes the child as a top-level body and loads the file.
      if (below_world) {
        diag.warning(codes::URDF_FLOATING_JOINT, pointer,
                     "floating joint '" + name + "' is written as URDF says it; below the root link 'world' "
                     "MuJoCo makes it a free joint, but robot_state_publisher ignores it (publish its pose "
                     "yourself, or use a fixed joint)");
        return urdf::Joint::FLOATING;
      }
      diag.warning(codes::URDF_FLOATING_JOINT, pointer,
                   "floating joint '" + name + "' is written as URDF says it, but MuJoCo refuses the file " +
                       (parent_is_root ? "(a free joint must belong to a top-level body: name the root link "
                                         "'world' for MuJoCo to take it as its world)"
                                       : "(a free joint must belong to a top-level body, and its parent is not "
                                         "the root)") +
                       " and robot_state_publisher ignores it; for those tools make the child a separate model "
                       "or use a fixed joint");
      return urdf::Joint::FLOATING;
    case JointKind::kPlanar:
      return urdf::Joint::PLANAR;
    case JointKind::kRevolute:
      if (position_limited(joint)) return urdf::Joint::REVOLUTE;
      diag.warning(codes::URDF_REVOLUTE_WITHOUT_LIMITS, pointer,
                   "revolute joint '" + name + "' has no lower and upper limits, which URDF requires: it turns "
                   "without end, so it is written as a continuous joint");
      return urdf::Joint::CONTINUOUS;
    case JointKind::kPrismatic:
      if (position_limited(joint)) return urdf::Joint::PRISMATIC;
      diag.error(codes::URDF_PRISMATIC_WITHOUT_LIMITS, pointer,
                 "prismatic joint '" + name + "' has no lower and upper limits, which URDF requires and which "
                 "have no neutral value: set rdtf_lower and rdtf_upper (m) on it");
      return std::nullopt;
    case JointKind::kBall:
      diag.error(codes::URDF_BALL_JOINT, pointer,
                 "ball joint '" + name + "' has no URDF equivalent (URDF joints are fixed, "
                 "revolute, continuous, prismatic, floating or planar)");
      return std::nullopt;
  }
  return std::nullopt;
}

void set_origin(urdf::Pose& pose, const Eigen::Isometry3d& X, Eigen::Vector3d& rpy) {
  pose.position = to_urdf(X.translation());
  rpy = rpy_from_rotation(X.linear());
  pose.rotation.setFromRPY(rpy.x(), rpy.y(), rpy.z());
}

urdf::LinkSharedPtr make_link(const std::string& name, const Link* link, const LinkSurface* surface,
                              const Eigen::Matrix3d& C, const std::string& mesh_uri) {
  auto out = std::make_shared<urdf::Link>();
  out->name = name;
  if (link == nullptr) return out;
  const MassProperties& m = link->inertial;
  if (m.mass != 0 || !m.inertia.isZero(0)) {
    auto inertial = std::make_shared<urdf::Inertial>();
    inertial->mass = m.mass;
    inertial->origin.position = to_urdf(C * m.center_of_mass);
    const Eigen::Matrix3d I = C * m.inertia * C.transpose();
    inertial->ixx = I(0, 0);
    inertial->ixy = I(0, 1);
    inertial->ixz = I(0, 2);
    inertial->iyy = I(1, 1);
    inertial->iyz = I(1, 2);
    inertial->izz = I(2, 2);
    out->inertial = inertial;
  }
  if (surface != nullptr && !surface->mesh.triangles.empty()) {
    auto mesh = std::make_shared<urdf::Mesh>();
    mesh->filename = mesh_uri;
    auto visual = std::make_shared<urdf::Visual>();
    visual->geometry = mesh;
    out->visual = visual;
    out->visual_array.push_back(visual);
    if (surface->closed) {
      auto collision = std::make_shared<urdf::Collision>();
      collision->geometry = mesh;
      out->collision = collision;
      out->collision_array.push_back(collision);
    }
  }
  return out;
}

// A 64-bit FNV-1a digest of `text`, in 16 hex digits.
std::string digest_hex(const std::string& text) {
  std::uint64_t digest = 14695981039346656037ull;
  for (const char c : text) {
    digest ^= static_cast<unsigned char>(c);
    digest *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(digest));
  return hex;
}

// A link's name as a file stem: whole when it is short; a name too long for a file system (255
// bytes a name on Linux; a link named with 200 accented letters is valid glTF) keeps its first 120
// bytes, cut between characters, and a digest of the whole name, so that two long names that
// start alike still name two files. A name that starts with '.' ("." or "..": valid URDF names)
// gets a '_' before it, or its file would be hidden from `cp meshes/*` and file browsers.
std::string mesh_file_stem(const std::string& link) {
  constexpr std::size_t kKept = 120;
  const std::string shown = !link.empty() && link[0] == '.' ? "_" + link : link;
  if (shown.size() <= kKept + 20) return shown;
  std::size_t cut = kKept;
  while (cut > 0 && (static_cast<unsigned char>(shown[cut]) & 0xC0) == 0x80) --cut;  // Not inside a character.
  return shown.substr(0, cut) + "~" + digest_hex(link);
}

// Stems unique without regard to case: links "Arm", "arm" and "ARM" wrote three files that are
// one on a case-insensitive file system (macOS, Windows, a copy there), and every link showed
// the last one written (s90urdf D13). The first keeps its stem, the others get the digest of
// their whole name.
class MeshStems {
 public:
  std::string operator()(const std::string& link) {
    std::string stem = mesh_file_stem(link);
    if (!taken_.insert(folded(stem)).second) {
      stem += "~" + digest_hex(link);
      taken_.insert(folded(stem));
    }
    return stem;
  }

 private:
  static std::string folded(std::string text) {
    for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return text;
  }
  std::set<std::string> taken_;
};

std::string mesh_file_name(const std::string& stem, std::span<const std::uint8_t> stl, const UrdfOptions& options) {
  return options.mesh_digest ? content_addressed_name(stem, ".stl", stl, options.mesh_digest) : stem + ".stl";
}

void collect_mesh_filenames(const TiXmlElement* element, std::vector<std::string>& names) {
  for (; element != nullptr; element = element->NextSiblingElement()) {
    if (element->ValueStr() == "mesh" && element->Attribute("filename") != nullptr) {
      names.emplace_back(element->Attribute("filename"));
    }
    collect_mesh_filenames(element->FirstChildElement(), names);
  }
}

// The file names (without folder) of the meshes the URDF in `path` refers to; none without one.
std::set<std::string> mesh_names_referenced_by(const std::filesystem::path& path) {
  std::set<std::string> names;
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return names;
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const auto& filename : urdf_mesh_filenames(text)) {
    names.insert(std::filesystem::path(filename).filename().string());
  }
  return names;
}

// Writes the meshes into `dir`; `created` receives those that were not there before.
// Atomically and durably, or into a stage that its commit makes durable (UrdfOptions::staged_for).
bool put_file(const std::filesystem::path& path, std::span<const std::uint8_t> bytes, const UrdfOptions& options,
              std::string& why) {
  const std::span<const std::span<const std::uint8_t>> pieces(&bytes, 1);
  return options.staged_for.empty() ? write_file_atomically(path, pieces, why) : write_staged_file(path, pieces, why);
}

bool write_meshes(const UrdfExport& exported, const std::filesystem::path& dir, const UrdfOptions& options,
                  Diagnostics& diag, std::vector<std::filesystem::path>& created) {
  std::string why;
  for (const UrdfMeshFile& mesh : exported.meshes) {
    const auto target = dir / mesh.path;
    const std::span<const std::uint8_t> bytes(mesh.bytes);
    // Already where the stage's commit would put it, byte for byte: nothing to write, sync or move.
    if (!options.staged_for.empty() &&
        file_holds(options.staged_for / mesh.path, std::span<const std::span<const std::uint8_t>>(&bytes, 1))) {
      continue;
    }
    std::error_code error;
    const bool existed = std::filesystem::exists(target, error);
    if (!put_file(target, bytes, options, why)) {
      diag.error(codes::WRITE_FAILED, "", "cannot write " + target.string() + ": " + why);
      return false;
    }
    if (!existed) created.push_back(target);
  }
  return true;
}

// After robot.urdf's rename: meshes that neither it nor the URDF it replaced names go. After a
// failure: the meshes this write created go, since no URDF names them.
void tidy_meshes(const std::filesystem::path& meshes, bool committed, const UrdfExport& exported,
                 std::set<std::string> keep, const std::vector<std::filesystem::path>& created) {
  if (!committed) {
    remove_created(created);
    return;
  }
  for (const UrdfMeshFile& mesh : exported.meshes) keep.insert(std::filesystem::path(mesh.path).filename().string());
  remove_unreferenced(meshes, keep);
}

std::string vector_text(const urdf::Vector3& v) {
  return exact_number(v.x) + " " + exact_number(v.y) + " " + exact_number(v.z);
}

std::string vector_text(const Eigen::Vector3d& v) {
  return exact_number(v.x()) + " " + exact_number(v.y()) + " " + exact_number(v.z());
}

// urdfdom prints six significant digits: print every number of the model again, exactly.
void fix_precision(TiXmlElement* robot, const urdf::ModelInterface& model,
                   const std::map<std::string, Eigen::Vector3d>& joint_rpy) {
  for (TiXmlElement* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    const auto link = model.getLink(e->Attribute("name") ? e->Attribute("name") : "");
    if (!link) continue;
    if (TiXmlElement* inertial = e->FirstChildElement("inertial"); inertial && link->inertial) {
      const urdf::Inertial& in = *link->inertial;
      if (TiXmlElement* mass = inertial->FirstChildElement("mass")) mass->SetAttribute("value", exact_number(in.mass));
      if (TiXmlElement* origin = inertial->FirstChildElement("origin")) {
        origin->SetAttribute("xyz", vector_text(in.origin.position));
        origin->SetAttribute("rpy", "0 0 0");
      }
      if (TiXmlElement* I = inertial->FirstChildElement("inertia")) {
        I->SetAttribute("ixx", exact_number(in.ixx));
        I->SetAttribute("ixy", exact_number(in.ixy));
        I->SetAttribute("ixz", exact_number(in.ixz));
        I->SetAttribute("iyy", exact_number(in.iyy));
        I->SetAttribute("iyz", exact_number(in.iyz));
        I->SetAttribute("izz", exact_number(in.izz));
      }
    }
    for (const char* kind : {"visual", "collision"}) {
      for (TiXmlElement* v = e->FirstChildElement(kind); v; v = v->NextSiblingElement(kind)) {
        if (TiXmlElement* origin = v->FirstChildElement("origin")) {
          origin->SetAttribute("xyz", "0 0 0");
          origin->SetAttribute("rpy", "0 0 0");
        }
      }
    }
  }
  for (TiXmlElement* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    const std::string name = e->Attribute("name") ? e->Attribute("name") : "";
    const auto joint = model.getJoint(name);
    if (!joint) continue;
    if (TiXmlElement* origin = e->FirstChildElement("origin")) {
      origin->SetAttribute("xyz", vector_text(joint->parent_to_joint_origin_transform.position));
      origin->SetAttribute("rpy", vector_text(joint_rpy.at(name)));
    }
    if (TiXmlElement* axis = e->FirstChildElement("axis")) {
      // urdfdom's writer gives every joint an axis; a fixed or floating one has none to give (a
      // zero axis is what an import refuses on a moving joint; docs/urdf.md: s90urdf D5).
      if (joint->type == urdf::Joint::FIXED || joint->type == urdf::Joint::FLOATING) {
        e->RemoveChild(axis);
      } else {
        axis->SetAttribute("xyz", vector_text(joint->axis));
      }
    }
    if (TiXmlElement* limit = e->FirstChildElement("limit"); limit && joint->limits) {
      if (joint->type == urdf::Joint::CONTINUOUS) {  // URDF reads no range on a continuous joint.
        limit->RemoveAttribute("lower");
        limit->RemoveAttribute("upper");
      } else {
        limit->SetAttribute("lower", exact_number(joint->limits->lower));
        limit->SetAttribute("upper", exact_number(joint->limits->upper));
      }
      limit->SetAttribute("effort", exact_number(joint->limits->effort));
      limit->SetAttribute("velocity", exact_number(joint->limits->velocity));
    }
    if (TiXmlElement* dynamics = e->FirstChildElement("dynamics"); dynamics && joint->dynamics) {
      dynamics->SetAttribute("damping", exact_number(joint->dynamics->damping));
      dynamics->SetAttribute("friction", exact_number(joint->dynamics->friction));
    }
  }
}

}  // namespace

std::optional<UrdfExport> export_urdf(const Conversion& conversion, const UrdfOptions& options,
                                      Diagnostics& diag) {
  const Robot& robot = conversion.robot;
  if (robot.links.empty()) {
    diag.error(codes::URDF_NO_LINKS, "", "the model has no link, and a URDF needs at least one");
    return std::nullopt;
  }
  const Eigen::Matrix3d C = options.y_up ? Eigen::Matrix3d::Identity() : y_up_to_z_up();
  UrdfExport result;
  // The names rdtfd's states and inertia tables carry too (urdf_names.h).
  UrdfNames names = urdf_names(robot, &diag);
  result.link_names = std::move(names.links);
  result.joint_names = std::move(names.joints);
  // Names of the added root link and joints must not take one of these.
  std::vector<std::string> taken_links = result.link_names, taken_joints = result.joint_names;
  auto surfaces = link_surfaces(conversion.asset, robot);
  // The meshes in the URDF's axes, as the inertials and joints are (p -> C p; C is a rotation, so
  // the faces stay wound outward). They were written in glTF's Y-up link frame: with the default
  // Z-up, every link's mesh lay turned 90 degrees about x from its inertial and joints (review
  // s70rev D2: forearm's solid centroid at (0, 0.232, 0), its <inertial> origin at (0, 0, 0.232)).
  for (LinkSurface& surface : surfaces) {
    for (Eigen::Vector3d& p : surface.mesh.positions) p = C * p;
  }

  auto model = std::make_shared<urdf::ModelInterface>();
  const urdf_internal::FlatRelease flat_release(model);
  // The robot's name as given (spaces and all), but no control character: XML 1.0 has no way to
  // write most of them (expat and libxml2 refused "arm&#x01;"), and urdfdom cut a name at a
  // newline (s90urdf D2).
  model->name_ = robot.name.empty() ? "robot" : robot.name;
  if (std::any_of(model->name_.begin(), model->name_.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; })) {
    std::string first;
    for (std::size_t k = 0; k < model->name_.size(); ++k) {
      const auto c = static_cast<unsigned char>(model->name_[k]);
      if (c >= 0x20 && c != 0x7f) continue;
      if (first.empty()) {
        char code[48];
        std::snprintf(code, sizeof(code), "byte 0x%02X at position %zu", c, k);
        first = code;
      }
      model->name_[k] = '_';
    }
    diag.warning(codes::URDF_NAME_CHANGED, "/extras/RDTF/name",
                 "the robot's name holds control characters (the first: " + first + "); it is '" + model->name_ +
                     "' in the URDF, since XML 1.0 cannot carry them");
  }
  // The prefix names the folder DIR is copied to: "package://my_robot/urdf" without its slash
  // must not become "package://my_robot/urdfmeshes/..." (a path no resolver finds, and no error
  // until RViz draws nothing).
  std::string mesh_prefix = options.mesh_uri_prefix;
  if (!mesh_prefix.empty() && mesh_prefix.back() != '/') mesh_prefix += '/';
  MeshStems stems;
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    const std::string& name = result.link_names[l];
    auto bytes = surfaces[l].mesh.triangles.empty() ? std::vector<std::uint8_t>{}
                                                     : stl_bytes(surfaces[l].mesh, "rdtf: link " + name);
    const std::string file = "meshes/" + mesh_file_name(stems(name), bytes, options);
    model->links_[name] = make_link(name, &link, &surfaces[l], C, mesh_prefix + file);
    if (!surfaces[l].mesh.triangles.empty()) {
      result.meshes.push_back({file, std::move(bytes)});
      if (!surfaces[l].closed) {
        diag.info(codes::URDF_VISUAL_ONLY, node_pointer(link.node),
                  "link '" + name + "': a mesh of it is open or has no volume, so it is visual "
                  "geometry only (no <collision>; MuJoCo refuses collision meshes without volume)");
      }
    }
  }

  bool ok = true;
  std::map<std::string, Eigen::Vector3d> joint_rpy;
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    const Joint& joint = robot.joints[j];
    const std::string& name = result.joint_names[j];
    const Link& parent = robot.links[joint.parent_link];
    const bool parent_is_root = parent.parent_joint < 0;
    const bool below_world = parent_is_root && result.link_names[joint.parent_link] == "world";
    const auto type = urdf_joint_type(joint, name, parent_is_root, below_world, diag);
    if (!type) {
      ok = false;
      continue;
    }
    auto out = std::make_shared<urdf::Joint>();
    out->name = name;
    out->type = static_cast<decltype(out->type)>(*type);
    out->parent_link_name = result.link_names[joint.parent_link];
    out->child_link_name = result.link_names[joint.child_link];
    set_origin(out->parent_to_joint_origin_transform, conjugate(C, joint.X_PJ), joint_rpy[name]);
    if (*type != urdf::Joint::FIXED && *type != urdf::Joint::FLOATING) {
      out->axis = to_urdf(C * joint.axis);
      out->dynamics = std::make_shared<urdf::JointDynamics>();
      out->dynamics->damping = joint.damping;
      out->dynamics->friction = joint.friction;
    }
    if (joint.limits && *type != urdf::Joint::FIXED && *type != urdf::Joint::FLOATING &&
        *type != urdf::Joint::PLANAR) {
      out->limits = std::make_shared<urdf::JointLimits>();
      // A continuous joint's range is none (urdfdom reads 0 and 0 where the file has nothing).
      const bool bounded = *type == urdf::Joint::REVOLUTE || *type == urdf::Joint::PRISMATIC;
      out->limits->lower = bounded ? joint.limits->lower : 0.0;
      out->limits->upper = bounded ? joint.limits->upper : 0.0;
      out->limits->effort = joint.limits->effort > 0 ? joint.limits->effort : kUnsetEffort;
      out->limits->velocity = joint.limits->velocity > 0 ? joint.limits->velocity : kUnsetVelocity;
      if (joint.limits->effort <= 0 || joint.limits->velocity <= 0) {
        diag.info(codes::URDF_LIMIT_DEFAULTED, node_pointer(joint.node),
                  "joint '" + name + "' has no " +
                      (joint.limits->effort <= 0 && joint.limits->velocity <= 0
                           ? std::string("rdtf_effort or rdtf_velocity")
                           : joint.limits->effort <= 0 ? std::string("rdtf_effort") : std::string("rdtf_velocity")) +
                      ": the URDF's <limit> (which requires both) says effort " +
                      exact_number(out->limits->effort) + " and velocity " +
                      exact_number(out->limits->velocity) + ", which never bind; set them to the real limits");
      }
    }
    if (joint.spring_stiffness != 0) {
      diag.warning(codes::URDF_SPRING_DROPPED, node_pointer(joint.node),
                   "joint '" + name + "': URDF has no spring, its stiffness is not exported");
    }
    const Link& child = robot.links[joint.child_link];
    if (*type != urdf::Joint::FIXED && child.inertial.mass <= 0) {
      diag.warning(codes::URDF_MASSLESS_MOVING_LINK, node_pointer(child.node),
                   "link '" + result.link_names[joint.child_link] + "' moves on joint '" + name +
                       "' but has no mass: simulators (MuJoCo among them) refuse it");
    }
    model->joints_[name] = out;
  }
  if (!ok) return std::nullopt;

  // One root: with several root links, an empty link "root" (the scene frame) holds them all.
  if (robot.root_links.size() > 1) {
    const std::string root = unique_name("root", taken_links);
    model->links_[root] = make_link(root, nullptr, nullptr, C, "");
    for (int l : robot.root_links) {
      const std::string name = unique_name(root + "_" + result.link_names[l] + "_joint", taken_joints);
      auto joint = std::make_shared<urdf::Joint>();
      joint->name = name;
      joint->type = urdf::Joint::FIXED;
      joint->parent_link_name = root;
      joint->child_link_name = result.link_names[l];
      set_origin(joint->parent_to_joint_origin_transform, conjugate(C, robot.links[l].X_SL), joint_rpy[name]);
      model->joints_[name] = joint;
    }
    diag.info(codes::URDF_ROOT_ADDED, "",
              std::to_string(robot.root_links.size()) + " root links: the URDF's root is a new "
              "empty link '" + root + "' (the scene frame) holding each of them by a fixed joint");
  }

  std::string text;
  std::string failure;
  const std::string messages = urdf_internal::with_console_captured([&] {
    try {
      std::map<std::string, std::string> parent_of;
      model->initTree(parent_of);
      model->initRoot(parent_of);
    } catch (const std::exception& error) {
      failure = error.what();
      return;
    }
    std::unique_ptr<TiXmlDocument> document(urdf::exportURDF(*model));
    if (!document || !document->RootElement()) {
      failure = "urdfdom's exporter returned no document";
      return;
    }
    TiXmlElement* root = document->RootElement();
    fix_precision(root, *model, joint_rpy);
    if (options.mujoco_compiler) {
      TiXmlElement mujoco("mujoco");
      TiXmlElement compiler("compiler");
      compiler.SetAttribute("meshdir", "meshes");
      compiler.SetAttribute("fusestatic", "false");
      compiler.SetAttribute("inertiafromgeom", "false");
      mujoco.InsertEndChild(compiler);
      if (root->FirstChild()) {
        root->InsertBeforeChild(root->FirstChild(), mujoco);
      } else {
        root->InsertEndChild(mujoco);
      }
    }
    document->InsertBeforeChild(document->FirstChild(), TiXmlDeclaration("1.0", "UTF-8", ""));
    TiXmlPrinter printer;
    printer.SetIndent("  ");
    document->Accept(&printer);
    text = printer.Str();
  });
  if (!failure.empty()) {
    diag.error(codes::URDF_EXPORT_FAILED, "", "urdfdom refused the model: " + failure + (messages.empty() ? "" : " (" + messages + ")"));
    return std::nullopt;
  }
  // The check: urdfdom reads it back, with every number exactly as we meant it.
  std::string mismatch;
  if (!urdf_internal::reads_back_exactly(text, *model, mismatch)) {
    diag.error(codes::URDF_SELF_CHECK_FAILED, "", "the URDF written does not read back: " + mismatch);
    return std::nullopt;
  }
  result.text = std::move(text);
  return result;
}

std::vector<std::string> urdf_mesh_filenames(const std::string& urdf_text) {
  std::vector<std::string> names;
  TiXmlDocument document;
  document.Parse(urdf_text.c_str());
  if (!document.Error()) collect_mesh_filenames(document.RootElement(), names);
  return names;
}

bool write_urdf(const Conversion& conversion, const std::filesystem::path& dir,
                const UrdfOptions& options, Diagnostics& diag, std::string* urdf_text) {
  auto exported = export_urdf(conversion, options, diag);
  if (!exported) return false;
  std::error_code error;
  std::filesystem::create_directories(dir / "meshes", error);
  if (error) {
    diag.error(codes::WRITE_FAILED, "", "cannot create " + (dir / "meshes").string() + ": " + error.message());
    return false;
  }
  const bool addressed = static_cast<bool>(options.mesh_digest);
  const auto urdf = dir / "robot.urdf";
  std::vector<std::filesystem::path> created;
  // Meshes first: the URDF refers to them.
  bool ok = write_meshes(*exported, dir, options, diag, created);
  // Read before the URDF is replaced: its meshes stay for a reader that has just opened it.
  const auto previous = addressed ? mesh_names_referenced_by(urdf) : std::set<std::string>{};
  std::string why;
  const std::span<const std::uint8_t> urdf_bytes(reinterpret_cast<const std::uint8_t*>(exported->text.data()),
                                                 exported->text.size());
  if (ok && !put_file(urdf, urdf_bytes, options, why)) {
    diag.error(codes::WRITE_FAILED, "", "cannot write " + urdf.string() + ": " + why);
    ok = false;
  }
  if (addressed) tidy_meshes(dir / "meshes", ok, *exported, previous, created);
  if (!ok) return false;
  if (urdf_text != nullptr) *urdf_text = std::move(exported->text);
  return true;
}

}  // namespace rdtf
