// Checks that the converted robot is the one that was modelled: the mistakes a modeller makes
// that still give a valid (but wrong) robot.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>
#include <vector>

#include <Eigen/SVD>

#include "rdtf/utf8.h"
#include "rdtf/completion.h"
#include "rdtf/geometry.h"
#include "rdtf/robot.h"
#include "rdtf/diagnostic_codes.h"
#include "scene_nodes.h"

namespace rdtf {
namespace internal {

// scene_nodes.h says what.
std::vector<char> nodes_placing_the_robot(const Json& document, const std::vector<int>& parents,
                                          std::vector<char>* scene_nodes) {
  const Json& nodes = document["nodes"];
  std::vector<char> in_scene(nodes.size(), 0), placing(nodes.size(), 0);
  if (!document.contains("scenes") || document["scenes"].empty()) return placing;
  std::vector<std::size_t> stack;
  const Json& scene = document["scenes"][document.value("scene", std::size_t{0})];
  for (const Json& root : scene.value("nodes", Json::array())) stack.push_back(root.get<std::size_t>());
  while (!stack.empty()) {
    const std::size_t node = stack.back();
    stack.pop_back();
    if (node >= nodes.size() || in_scene[node]) continue;
    in_scene[node] = 1;
    for (const Json& child : nodes[node].value("children", Json::array())) stack.push_back(child.get<std::size_t>());
  }
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const bool pivot = nodes[i].contains("extras") && nodes[i]["extras"].is_object() &&
                       nodes[i]["extras"].contains("rdtf_joint");
    if (!in_scene[i] || !(nodes[i].contains("mesh") || pivot)) continue;
    for (int up = static_cast<int>(i); up >= 0 && !placing[up]; up = parents[up]) placing[up] = 1;
  }
  if (scene_nodes != nullptr) *scene_nodes = std::move(in_scene);
  return placing;
}

}  // namespace internal

namespace {

using internal::nodes_placing_the_robot;

// Bounds of a plausible robot in metres and kilograms. A model drawn in millimetres and exported
// as metres is 1000 times too long and 1e9 times too heavy: a 0.6 m arm becomes 600 m and 3e10
// kg. The bounds sit well above the largest robots (excavators, gantries: tens of metres, tens of
// tonnes) and far below what the millimetre mistake gives for anything of hand size.
constexpr double kMaxExtent = 100.0;     // m
constexpr double kMaxMass = 1.0e6;       // kg
// Both at once are beyond mobile machines too (a large excavator: 10 m, 50 t).
constexpr double kLargeExtent = 10.0;    // m
constexpr double kLargeMass = 1.0e5;     // kg
constexpr double kMinExtent = 1.0e-3;    // m: smaller than any robot a glTF describes
// Densities of solids: from foams (about 30 kg/m^3) to osmium (22,590). Off by 1000 either way,
// a density typed in g/cm^3 or a mass in grams lands outside.
constexpr double kMinDensity = 30.0;     // kg/m^3
constexpr double kMaxDensity = 25000.0;  // kg/m^3
constexpr double kFullTurn = 2 * 3.14159265358979323846;  // rad
// A slide longer than a hundred times the robot (and 10 m) is a length typed in millimetres.
constexpr double kSlideReach = 100.0;

std::string short_number(double value) { return format_number(value, 3); }

// What a packer does to a robot, and the options that keep it, for the warnings that meet a
// packed file: each tool's own (glTF-Transform keeps node extras; its flatten, join and instance,
// which `optimize` runs by default, move and merge nodes; s90tools D1).
std::string packer_advice(const std::string& packer) {
  if (packer.rfind("glTF-Transform", 0) == 0) {
    return "keeps node extras (custom properties: joints, masses, densities), but whose flatten, join and instance "
           "steps (which optimize runs by default) move parts to the scene's root, merge them or drop their "
           "empties, and whose quantize (run by meshopt and by optimize's default compression) moves a leaf part's "
           "origin: run gltf-transform optimize --flatten false --join false --instance false --compress false, or "
           "pack rdtf's own output (rdtf convert first)";
  }
  if (packer.rfind("gltfpack", 0) == 0) {
    return "drops node extras (custom properties: joints, masses, densities) unless -ke, and merges or renames nodes "
           "(parts, joint empties) unless -kn: pack with gltfpack -kn -ke, or pack rdtf's own output (rdtf convert "
           "first)";
  }
  if (packer.rfind("Open Asset Import Library", 0) == 0) {
    return "drops every node extra (custom properties: joints, masses, densities; measured with assimp 5.2): "
           "export the glTF from the tool that made the model, with its custom properties, and give it to rdtf as "
           "it is";
  }
  return "may have dropped node extras (custom properties: joints, masses, densities) or merged nodes: pack rdtf's "
         "own output instead (rdtf convert first)";
}

// Whether a node's extras hold any rdtf property (rdtf_density, rdtf_joint, ...).
bool has_rdtf_key(const Json& node) {
  if (!node.is_object() || !node.contains("extras") || !node["extras"].is_object()) return false;
  const Json& extras = node["extras"];
  return std::any_of(extras.items().begin(), extras.items().end(),
                     [](const auto& item) { return item.key().rfind("rdtf_", 0) == 0; });
}

// Whether the model says where its joints are: an extras.RDTF (a converted file), or a node with a
// joint key or rdtf_type. Densities and masses alone do not: a Blender export of the parts only
// (the joint empties left out) keeps the densities set on the parts, and its joints are all fixed.
bool any_node_has_joint_keys(const Json& document) {
  if (document.contains("extras") && document["extras"].is_object() &&
      document["extras"].contains("RDTF")) {
    return true;
  }
  for (const Json& node : document["nodes"]) {
    if (!node.contains("extras") || !node["extras"].is_object()) continue;
    const Json& extras = node["extras"];
    if (extras.contains("rdtf_type") || extras.contains("rdtf_axes")) return true;
    for (const char* key : kJointExtrasKeys) {
      if (extras.contains(key)) return true;
    }
  }
  return false;
}

// How large the robot is: the diagonal of the box around its link frames and centres of mass, or
// the edge of a cube of its largest link's volume if that is more (a robot of one link). The
// volume stands in for the parts' own sizes: their bounds would need a pass over every vertex.
struct RobotSize {
  double span = 0;       // m: the box's diagonal
  double part_edge = 0;  // m: the cube's edge
  double extent() const { return std::max(span, part_edge); }
  // The size as the message should state it, saying which of the two it is.
  std::string text() const {
    if (span >= part_edge) return "spans " + short_number(span) + " m (link frames and centres of mass)";
    return "has a part of " + short_number(part_edge * part_edge * part_edge) + " m^3 (a cube " +
           short_number(part_edge) + " m on a side)";
  }
};

RobotSize robot_size(const Robot& robot) {
  Eigen::AlignedBox3d box;
  RobotSize size;
  for (const Link& link : robot.links) {
    box.extend(link.X_SL.translation());
    if (link.inertial.mass > 0) box.extend(link.X_SL * link.inertial.center_of_mass);
    size.part_edge = std::max(size.part_edge, std::cbrt(std::max(0.0, link.inertial.volume)));
  }
  size.span = box.isEmpty() ? 0.0 : box.diagonal().norm();
  return size;
}

double robot_extent(const Robot& robot) { return robot_size(robot).extent(); }

void check_units_of(const Json& document, const Robot& robot, Diagnostics& diag) {
  if (robot.links.empty()) return;
  double mass = 0;
  double volume = 0;
  int heaviest = 0;
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    mass += link.inertial.mass;
    volume += std::max(0.0, link.inertial.volume);
    if (link.inertial.mass > robot.links[heaviest].inertial.mass) heaviest = static_cast<int>(l);
  }
  const RobotSize size = robot_size(robot);
  const double extent = size.extent();
  const Link& link = robot.links[heaviest];
  // Large beyond any robot, or both large and heavy beyond a mobile one (a hand-sized part drawn
  // in millimetres: a 25 mm gripper becomes 25 m and hundreds of tonnes): the lengths are off.
  // Heavy beyond any robot at a plausible size: the masses are (authored ones, as a URDF brings).
  const bool too_large = extent > kMaxExtent || (extent > kLargeExtent && mass > kLargeMass);
  if (!too_large && mass > kMaxMass) {
    diag.warning(codes::UNITS_IMPLAUSIBLE, json_pointer("/nodes", link.node),
                 "the robot " + size.text() + " and weighs " + short_number(mass) + " kg (" +
                     node_label(document, link.node) + " alone " + short_number(link.inertial.mass) + " kg): " +
                     (extent >= kMinExtent ? "its size is plausible in metres but its mass is not"
                                           : "heavier than any robot") +
                     ". Masses are kilograms and densities kg/m^3 (one typed in grams, or g/cm^3 as kg/m^3, is "
                     "1000 times too large)");
  } else if (too_large) {
    diag.warning(codes::UNITS_IMPLAUSIBLE, json_pointer("/nodes", link.node),
                 "the robot " + size.text() + " and weighs " + short_number(mass) + " kg (" + node_label(document, link.node) + " alone " +
                     short_number(link.inertial.mass) +
                     " kg): implausible in metres. glTF lengths are metres; the model was likely drawn in "
                     "millimetres or centimetres: scale it by 0.001 or 0.01 (in Blender the scene's Unit Scale, "
                     "Scene > Units, says which: the exporter ignores it and writes 1 unit as 1 m; select all, "
                     "scale by it, Object > Apply > Scale, set Unit Scale 1) and export again");
  } else if (mass > 0 && volume > 0 && extent < kMinExtent) {
    // (Only with geometry to measure: a robot of one link without meshes, as URDFs without their
    // mesh files give, has no size at all.)
    diag.warning(codes::UNITS_IMPLAUSIBLE, json_pointer("/nodes", link.node),
                 "the robot " + size.text() + " and weighs " + short_number(mass) +
                     " kg: implausibly small in metres. glTF lengths are metres: was the model scaled "
                     "down twice, or drawn in kilometres?");
  }
}

// A link's mass over its volume, for links whose mass comes from their meshes: a density or mass
// typed in another unit (g/cm^3, grams) is off by 1000 and lands outside what solids have.
void check_densities(const Json& document, const Robot& robot, Diagnostics& diag) {
  for (const Link& link : robot.links) {
    if (link.inertial_source != InertialSource::kComputed || link.inertial.volume <= 0 || link.inertial.mass <= 0) {
      continue;
    }
    const double density = link.inertial.mass / link.inertial.volume;
    if (density >= kMinDensity && density <= kMaxDensity) continue;
    diag.warning(codes::DENSITY_IMPLAUSIBLE, json_pointer("/nodes", link.node),
                 node_label(document, static_cast<std::size_t>(link.node)) + ": the link's " +
                     short_number(link.inertial.mass) + " kg over its " + short_number(link.inertial.volume) +
                     " m^3 is " + short_number(density) + " kg/m^3, " +
                     (density < kMinDensity ? "lighter than any solid (foams are about 30)"
                                            : "denser than any material (osmium is 22,600)") +
                     ". Densities are kg/m^3 (2.7 g/cm^3 is 2700 kg/m^3) and masses kg (2500 g is 2.5 kg): "
                     "check rdtf_density and rdtf_mass on the link and its meshes, and --density");
  }
}

// Limits a modeller typed in Blender's custom properties (node extras) in the units Blender shows:
// degrees for an angle, millimetres for a length. Limits from extras.RDTF or a URDF are left
// alone: published robots give multi-turn ranges on purpose.
void check_typed_limits(const Json& document, const Robot& robot, Diagnostics& diag) {
  const double extent = robot_extent(robot);
  for (const Joint& joint : robot.joints) {
    if (joint.source_node < 0 || joint.source_is_entry || !position_limited(joint)) continue;
    // rdtf's own output carries every joint in node extras too, beside rdtf_type (which
    // modellers do not type): those came from extras.RDTF or a URDF, and are left alone.
    const Json& source_node = document["nodes"][static_cast<std::size_t>(joint.source_node)];
    if (source_node.contains("extras") && source_node["extras"].is_object() && source_node["extras"].contains("rdtf_type")) {
      continue;
    }
    const JointLimits& limits = *joint.limits;
    const double reach = std::max(std::abs(limits.lower), std::abs(limits.upper));
    const std::string range = "[" + short_number(limits.lower) + ", " + short_number(limits.upper) + "]";
    const std::string where = json_pointer("/nodes", static_cast<std::size_t>(joint.source_node)) + "/extras";
    const std::string label = node_label(document, static_cast<std::size_t>(joint.source_node));
    if (joint.kind == JointKind::kRevolute && reach > kFullTurn * 1.001) {
      const double to_rad = kFullTurn / 360.0;
      diag.warning(codes::JOINT_LIMITS_IMPLAUSIBLE, where,
                   label + ": joint '" + joint.name + "' limits " + range +
                       " rad reach beyond a full turn. Limits are radians: in degrees they would be [" +
                       short_number(limits.lower * to_rad) + ", " + short_number(limits.upper * to_rad) +
                       "] rad; a joint that turns without end is \"continuous\"");
    } else if (joint.kind == JointKind::kPrismatic && extent > 0 && reach > kSlideReach * std::max(extent, 0.1)) {
      // (A rail of 20 times the robot's length is a real machine; millimetres are 1000 times.)
      diag.warning(codes::JOINT_LIMITS_IMPLAUSIBLE, where,
                   label + ": joint '" + joint.name + "' limits " + range + " m reach " +
                       short_number(reach / extent) + " times the robot's size (" + short_number(extent) +
                       " m). Limits are metres: in millimetres they would be [" + short_number(limits.lower / 1000) +
                       ", " + short_number(limits.upper / 1000) + "] m");
    }
  }
}

// The node-extras keys rdtf reads (docs/format.md, "Node extras").
constexpr const char* kExtrasKeys[] = {"rdtf_joint",   "rdtf_axis",     "rdtf_axes",    "rdtf_lower",
                                       "rdtf_upper",   "rdtf_effort",   "rdtf_velocity", "rdtf_damping",
                                       "rdtf_friction", "rdtf_spring_stiffness", "rdtf_density", "rdtf_mass",
                                       "rdtf_type",    "rdtf_inertial"};

constexpr std::size_t kLongestExtrasKey = 21;  // rdtf_spring_stiffness

// Optimal string alignment distance: insertions, deletions, substitutions and swaps of two
// neighbours, each 1 ("rdft_axis" is 1 from "rdtf_axis").
std::size_t typing_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

// The cosine of the widest non-right angle between the axes of a linear map (0: no shear). TRS
// nodes map their axes to orthogonal ones; a rotation inside a non-uniform scale does not.
double shear_of(const Eigen::Matrix3d& A) {
  double worst = 0;
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      const double norms = A.col(a).norm() * A.col(b).norm();
      if (norms > 0) worst = std::max(worst, std::abs(A.col(a).dot(A.col(b))) / norms);
    }
  }
  return worst;
}

// Nodes whose shape or placement is skewed by a rotation inside an ancestor's non-uniform scale,
// where the skew starts (the parent is not skewed), in the converted scene, with a mesh or joint
// properties at or below them. Such a file is valid glTF, but rarely meant: Blender cannot write
// a child of an object with unapplied non-uniform scale as its scene shows it (glTF has no parent
// inverse and no shear in a TRS), so it writes one askew, and the masses, pivots and axes of all
// below follow.
void check_shear(const Json& document, Diagnostics& diag) {
  const Json& nodes = document["nodes"];
  if (!document.contains("scenes") || document["scenes"].empty()) return;
  const auto parents = node_parents(document);
  const auto world = node_world_transforms(document);
  const std::vector<char> mesh_below = nodes_placing_the_robot(document, parents);
  const auto skewed = [&](int node) {
    // A rotation stored as floats is off by up to about 2.4e-7 rad (2^-24 on each quaternion
    // component); inside a scale whose axes differ by a ratio r that turns axes by up to about
    // 2.4e-7 r from square. Four times that, and never less than the validator's tolerance for an
    // orthogonal matrix (5e-5), is rounding; more is a skew. A scale of 0 flattens rather than
    // skews (MESH_SCALED_TO_NOTHING says so).
    if (node < 0) return 0.0;
    const Eigen::Matrix3d& A = world[static_cast<std::size_t>(node)].linear();
    const double shear = shear_of(A);
    const int parent = parents[static_cast<std::size_t>(node)];
    const Eigen::Vector3d scales =
        parent < 0 ? Eigen::Vector3d::Ones()
                   : Eigen::JacobiSVD<Eigen::Matrix3d>(world[static_cast<std::size_t>(parent)].linear()).singularValues();
    if (!(scales.minCoeff() > 0) || !(A.col(0).norm() > 0 && A.col(1).norm() > 0 && A.col(2).norm() > 0)) return 0.0;
    const double rounding = std::max(5e-5, 1e-6 * scales.maxCoeff() / scales.minCoeff());
    return shear > rounding ? shear : 0.0;
  };
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (!mesh_below[i]) continue;
    const double shear = skewed(static_cast<int>(i));
    if (shear == 0.0 || skewed(parents[i]) > 0.0) continue;
    // The nearest ancestor whose own scale is not uniform.
    std::string scaled = "an ancestor";
    for (int up = parents[i]; up >= 0; up = parents[up]) {
      const Eigen::Matrix3d L = node_local_transform(nodes[up]).linear();
      const Eigen::Vector3d scale(L.col(0).norm(), L.col(1).norm(), L.col(2).norm());
      if (scale.maxCoeff() - scale.minCoeff() > 1e-6 * scale.maxCoeff()) {
        scaled = node_label(document, static_cast<std::size_t>(up)) + " (scale " + short_number(scale.x()) + ", " +
                 short_number(scale.y()) + ", " + short_number(scale.z()) + ")";
        break;
      }
    }
    diag.warning(codes::NODE_SHEARED, json_pointer("/nodes", i),
                 node_label(document, i) + " is skewed: it is turned inside the non-uniform scale of " + scaled +
                     ", so its axes are not at right angles (cosine " + short_number(shear) +
                     ") and the meshes, pivots and axes below it are skewed too. A modeller rarely means this: "
                     "Blender writes a child of an object with unapplied non-uniform scale so. Apply that "
                     "object's scale (Ctrl+A > Scale; Blender refuses it on a mesh several objects share until "
                     "Object > Relations > Make Single User > Object & Data) and export again");
  }
}

// Links or joints that share a name: subscribers tell them apart by name (LINK_STATE, joint
// commands), so the URDF export and rdtfd name all but the first otherwise ("tyre_2").
void check_duplicate_names(const Json& document, const Robot& robot, Diagnostics& diag) {
  const auto report = [&](const char* what, const std::vector<std::pair<std::string, int>>& named) {
    std::map<std::string, std::vector<int>> nodes_by_name;
    for (const auto& [name, node] : named) {
      if (node >= 0) nodes_by_name[name].push_back(node);
    }
    for (const auto& [name, nodes] : nodes_by_name) {
      if (nodes.size() < 2) continue;
      std::string listed;
      for (std::size_t k = 0; k < nodes.size() && k < 4; ++k) listed += (k ? ", " : "") + std::to_string(nodes[k]);
      if (nodes.size() > 4) listed += ", ...";
      diag.warning(codes::DUPLICATE_NAMES, json_pointer("/nodes", static_cast<std::size_t>(nodes[1])),
                   std::to_string(nodes.size()) + " " + what + " are named '" + name + "' (nodes " + listed +
                       "): subscribers and the URDF export tell " + what + " apart by name, so all but the first "
                       "are renamed there ('" + name + "_2', ...). Name them apart (the objects of a Blender "
                       "collection instance keep the collection's names)");
    }
  };
  std::vector<std::pair<std::string, int>> links, joints;
  for (const Link& link : robot.links) links.emplace_back(link.name, link.node);
  // Joints that take the name of an input node (the empty whose properties made them), and those
  // rdtf names after their links ("base_wheel_joint"), unless a link name repeated, which is
  // already reported and repeats theirs. Distinct links can still give one joint name, since "_"
  // joins them: a_b > c and a > b_c both give "a_b_c_joint".
  std::map<std::string, int> link_names;
  for (const Link& link : robot.links) ++link_names[link.name];
  for (const Joint& joint : robot.joints) {
    const Json* node = joint.source_node >= 0 ? &document["nodes"][static_cast<std::size_t>(joint.source_node)] : nullptr;
    if (node != nullptr && node->contains("name") && (*node)["name"].is_string() &&
        (*node)["name"].get<std::string>() == joint.name) {
      joints.emplace_back(joint.name, joint.source_node);
    } else if (joint.parent_link >= 0 && joint.child_link >= 0 &&
               link_names[robot.links[joint.parent_link].name] == 1 && link_names[robot.links[joint.child_link].name] == 1) {
      joints.emplace_back(joint.name, joint.node);
    }
  }
  report("links", links);
  report("joints", joints);
}

}  // namespace

void check_extras_keys(const Json& document, Diagnostics& diag) {
  // rdtf keys on a mesh: Blender exports the Object Data tab's custom properties as the mesh's
  // extras, shared by every object that uses the mesh; rdtf reads the object's (node's) only.
  if (document.contains("meshes") && document["meshes"].is_array()) {
    for (std::size_t m = 0; m < document["meshes"].size(); ++m) {
      const Json& mesh = document["meshes"][m];
      if (!mesh.is_object() || !mesh.contains("extras") || !mesh["extras"].is_object()) continue;
      for (const auto& [key, value] : mesh["extras"].items()) {
        std::string lower = key.substr(0, 4);
        for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        if (lower != "rdtf" && lower != "rdft") continue;
        const std::string name = mesh.contains("name") && mesh["name"].is_string() ? " " + value_text(mesh["name"]) : "";
        diag.warning(codes::RDTF_UNKNOWN_KEY, json_pointer(json_pointer("/meshes", m) + "/extras", key),
                     "mesh " + std::to_string(m) + name + ": custom property " + value_text(Json(key)) +
                         " is on the mesh data (in Blender, the Object Data tab), where rdtf does not read it, so "
                         "it is ignored; set it on the object (the Object tab)");
      }
    }
  }
  if (!document.contains("nodes") || !document["nodes"].is_array()) return;
  for (std::size_t i = 0; i < document["nodes"].size(); ++i) {
    const Json& node = document["nodes"][i];
    if (!node.is_object() || !node.contains("extras")) continue;
    if (!node["extras"].is_object()) {
      // glTF allows extras of any type, and custom properties are an object's keys: rdtf's written
      // as text or in an array were dropped without a word (a revolute elbow became fixed).
      const Json& extras = node["extras"];
      std::string text = extras.dump(-1, ' ', false, Json::error_handler_t::replace);
      std::string lower = text;
      for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (extras.is_null() || (lower.find("rdtf") == std::string::npos && lower.find("rdft") == std::string::npos)) {
        continue;
      }
      if (text.size() > 60) text = text.substr(0, 57) + "...";
      diag.warning(codes::RDTF_UNKNOWN_KEY, json_pointer("/nodes", i) + "/extras",
                   node_label(document, i) + ": extras is " +
                       (extras.is_string() ? "text" : extras.is_array() ? "an array" : "a " + std::string(extras.type_name())) +
                       " (" + escape_for_terminal(text) + "), not an object, so the rdtf properties in it are not "
                       "read: custom properties are an object's keys, {\"rdtf_joint\": \"revolute\"}");
      continue;
    }
    for (const auto& [key, value] : node["extras"].items()) {
      if (std::find(std::begin(kExtrasKeys), std::end(kExtrasKeys), key) != std::end(kExtrasKeys)) continue;
      std::string lower = key;
      for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      const char* nearest = nullptr;
      std::size_t distance = std::numeric_limits<std::size_t>::max();
      // Two edits from a key of at most 21 characters: a longer key is nobody's typo of one (and a
      // key of megabytes costs nothing here).
      if (lower.size() <= kLongestExtrasKey + 2) {
        for (const char* known : kExtrasKeys) {
          const std::size_t d = typing_distance(lower, known);
          if (d < distance) distance = d, nearest = known;
        }
      }
      const bool rdtf_like = lower.rfind("rdtf", 0) == 0 || lower.rfind("rdft", 0) == 0;
      if (distance > 2 && !rdtf_like) continue;  // Somebody else's property.
      diag.warning(codes::RDTF_UNKNOWN_KEY, json_pointer(json_pointer("/nodes", i) + "/extras", key),
                   node_label(document, i) + ": custom property " + value_text(Json(key)) +
                       " is no property rdtf reads, so it is ignored" +
                       (distance <= 2 ? ": did you mean '" + std::string(nearest) + "'?"
                                      : " (docs/format.md, \"Node extras\", lists them)"));
    }
  }
}


void check_missing_properties(const Json& document, const std::vector<NodeType>& types,
                              Diagnostics& diag) {
  if (!document.contains("nodes") || any_node_has_joint_keys(document)) return;
  const auto packer = repacked_by(document);
  std::vector<char> is_child(document["nodes"].size(), 0);
  for (const Json& node : document["nodes"]) {
    for (const Json& child : node.value("children", Json::array())) {
      if (child.is_number_unsigned() && child.get<std::size_t>() < is_child.size()) {
        is_child[child.get<std::size_t>()] = 1;
      }
    }
  }
  // Bones are reported as the armature, not one by one.
  std::vector<char> bone(document["nodes"].size(), 0);
  if (document.contains("skins") && document["skins"].is_array()) {
    for (const Json& skin : document["skins"]) {
      for (const Json& joint : skin.value("joints", Json::array())) {
        if (joint.is_number_unsigned() && joint.get<std::size_t>() < bone.size()) bone[joint.get<std::size_t>()] = 1;
      }
    }
  }
  std::vector<std::size_t> empties;
  // An armature: a skinned mesh, or bones without one (parts parented to bones).
  bool bones = document.contains("skins") && document["skins"].is_array() && !document["skins"].empty();
  std::size_t links = 0, links_parented = 0;
  for (std::size_t i = 0; i < types.size() && i < document["nodes"].size(); ++i) {
    const Json& node = document["nodes"][i];
    if (types[i] == NodeType::kNone) continue;
    if (node.contains("skin")) bones = true;
    if (types[i] == NodeType::kLink) {
      ++links;
      links_parented += is_child[i] ? 1 : 0;
    }
    const bool has_children = node.contains("children") && !node["children"].empty();
    if (!node.contains("mesh") && has_children && is_child[i] && !bone[i] &&
        (types[i] == NodeType::kJoint || types[i] == NodeType::kLink)) {
      empties.push_back(i);
    }
  }
  // Parts parented to parts and nothing else, from Blender: the joint empties were probably left
  // out (Limit to > Selected Objects with only the meshes selected).
  // Blender's exports, and packed files (which may be Blender's without their properties).
  // A packed file that still has rdtf properties (densities, masses) kept its extras: the packer
  // dropped nothing, and the robot is as its source had it (glTF-Transform's copy of an all-fixed
  // robot was warned about, its source not).
  const bool any_rdtf_key = std::any_of(document["nodes"].begin(), document["nodes"].end(), has_rdtf_key);
  const bool parts_only =
      empties.empty() && !bones && links > 1 && (written_by_blender(document) || (packer && !any_rdtf_key));
  if (empties.empty() && !bones && !parts_only) return;
  std::string names;
  for (std::size_t k = 0; k < empties.size() && k < 4; ++k) {
    names += (k ? ", " : "") + node_label(document, empties[k]);
  }
  if (empties.size() > 4) names += ", ...";
  diag.warning(codes::NO_RDTF_PROPERTIES, "/nodes",
               std::string("no node has a joint property (rdtf_joint, rdtf_axis, ...), so every joint is fixed and the "
                           "robot is one rigid body") +
                   (names.empty() ? std::string() : "; these empties look like joints: " + names) +
                   (bones ? std::string("; the model has an armature") : std::string()) +
                   (parts_only ? "; its " + std::to_string(links) +
                                     (links_parented > 0 ? std::string(" parts are parented to one another with no empty "
                                                                       "between them")
                                                         : std::string(" parts lie side by side at the scene's root, "
                                                                       "none parented to another")) +
                                     (packer ? std::string()
                                             : std::string(" (were the joint empties left out of the export, by "
                                                           "Include > Limit to > Selected Objects with only the "
                                                           "meshes selected, or by Limit to > Visible Objects with "
                                                           "the empties hidden?)"))
                               : std::string()) +
                   (packer ? std::string(". The file was packed by '") + *packer + "', which " + packer_advice(*packer) +
                                 " (if the file it packed had no joint properties either: a Blender export needs "
                                 "Include > Custom Properties ticked)"
                           : std::string(". In Blender, tick File > Export > glTF 2.0 > Include > Custom Properties "
                                         "(export_extras=True): it is off by default; on an armature set the "
                                         "properties on the Bone (Bone tab, edit or object mode), not on the pose "
                                         "bone, whose properties are never exported")));
}

namespace {

// Whether every primitive of `mesh` has positions quantized as glTF-Transform's quantize leaves a
// leaf node's (KHR_mesh_quantization): normalized signed integers whose box is centred on the
// node's origin and spans the whole range on its longest axis (the node's translation and scale
// hold the dequantization).
bool positions_centred_by_a_quantizer(const Json& document, const Json& mesh_index) {
  if (!mesh_index.is_number_unsigned() || !document.contains("meshes") ||
      mesh_index.get<std::size_t>() >= document["meshes"].size()) {
    return false;
  }
  const Json& primitives = document["meshes"][mesh_index.get<std::size_t>()].value("primitives", Json::array());
  if (!primitives.is_array() || primitives.empty()) return false;
  for (const Json& primitive : primitives) {
    const Json* attributes = primitive.contains("attributes") ? &primitive["attributes"] : nullptr;
    if (attributes == nullptr || !attributes->contains("POSITION") || !(*attributes)["POSITION"].is_number_unsigned()) {
      return false;
    }
    const std::size_t index = (*attributes)["POSITION"].get<std::size_t>();
    if (!document.contains("accessors") || index >= document["accessors"].size()) return false;
    const Json& accessor = document["accessors"][index];
    const int type = accessor.value("componentType", 0);
    const double full = type == 5120 ? 127.0 : type == 5122 ? 32767.0 : 0.0;  // BYTE, SHORT
    if (full == 0 || !accessor.value("normalized", false) || !accessor.contains("min") || !accessor.contains("max") ||
        !accessor["min"].is_array() || !accessor["max"].is_array() || accessor["min"].size() != 3 ||
        accessor["max"].size() != 3) {
      return false;
    }
    double reach = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      if (!accessor["min"][k].is_number() || !accessor["max"][k].is_number()) return false;
      const double lo = accessor["min"][k].get<double>(), hi = accessor["max"][k].get<double>();
      if (lo != -hi) return false;
      reach = std::max(reach, hi);
    }
    if (reach != full) return false;
  }
  return true;
}

}  // namespace

// glTF-Transform's quantize (run by its meshopt and by optimize's default compression) folds a
// leaf mesh node's dequantization into that node's translation and scale: the node's origin moves
// to its mesh's centre. Where that node's own frame is a joint's (the part carries its joint
// keys, or is a fixed frame), the joint moves with it, and nothing in the file says where it was
// (a forearm's elbow moved 0.2 m, without a word, in a sweep of packers).
void check_quantized_joint_origins(const Json& document, const std::vector<NodeType>& types, Diagnostics& diag) {
  if (!document.contains("nodes") || !document["nodes"].is_array()) return;
  const std::vector<int> parents = node_parents(document);
  for (std::size_t n = 0; n < document["nodes"].size() && n < types.size(); ++n) {
    const Json& node = document["nodes"][n];
    if (types[n] != NodeType::kLink || parents[n] < 0 || !node.is_object() || !node.contains("mesh") ||
        !node.contains("scale") || (node.contains("children") && !node["children"].empty())) {
      continue;
    }
    const Json* extras = node.contains("extras") && node["extras"].is_object() ? &node["extras"] : nullptr;
    // Under a joint empty the joint turns about the empty's origin, which the quantizer left alone
    // (the layout this warning's advice asks for), unless the part types a joint of its own.
    const bool own_joint = extras != nullptr && extras->contains("rdtf_joint");
    if (types[static_cast<std::size_t>(parents[n])] == NodeType::kJoint && !own_joint) continue;
    if (!positions_centred_by_a_quantizer(document, node["mesh"])) continue;
    const std::string joint = own_joint
                                  ? "carries its own joint (rdtf_joint " + value_text((*extras)["rdtf_joint"]) +
                                        "), which turns about the node's origin"
                                  : std::string("is a link whose frame, and the origin of its joint, is the node's origin");
    diag.warning(codes::JOINT_ORIGIN_QUANTIZED, json_pointer("/nodes", n),
                 node_label(document, n) + " " + joint +
                     ", but its mesh is quantized (KHR_mesh_quantization) and centred on that origin, with the "
                     "dequantization in the node's translation and scale: what glTF-Transform's quantize (also run "
                     "by its meshopt and optimize) does to a leaf part, moving its origin to its mesh's centre, and "
                     "the joint with it. If the joint was elsewhere when modelled, quantize rdtf's output instead "
                     "(rdtf convert first: its parts' meshes hang from their link nodes), or set the joint on an "
                     "empty above the part");
  }
}

void check_other_scenes(const Json& document, std::size_t scene, const std::vector<NodeType>& types,
                        Diagnostics& diag) {
  if (!document.contains("scenes") || !document["scenes"].is_array() || document["scenes"].size() < 2 ||
      !document.contains("nodes") || !document["nodes"].is_array()) {
    return;
  }
  const Json& nodes = document["nodes"];
  // The nodes outside the converted scene with rdtf keys, each with its root: found once, walking
  // up each chain only to the first node already answered (a chain of 20,000 nodes in 100 scenes
  // took 34 s walked per node and scene).
  const std::vector<int> parents = node_parents(document);
  const std::size_t count = std::min(nodes.size(), types.size());
  std::vector<int> root_of(count, -1);
  std::vector<std::size_t> path;
  for (std::size_t n = 0; n < count; ++n) {
    int at = static_cast<int>(n);
    path.clear();
    while (root_of[static_cast<std::size_t>(at)] < 0 && parents[static_cast<std::size_t>(at)] >= 0) {
      path.push_back(static_cast<std::size_t>(at));
      at = parents[static_cast<std::size_t>(at)];
    }
    const int root = root_of[static_cast<std::size_t>(at)] >= 0 ? root_of[static_cast<std::size_t>(at)] : at;
    root_of[static_cast<std::size_t>(at)] = root;
    for (const std::size_t p : path) root_of[p] = root;
  }
  std::vector<std::size_t> keyed;
  for (std::size_t n = 0; n < count; ++n) {
    if (types[n] == NodeType::kNone && has_rdtf_key(nodes[n])) keyed.push_back(n);
  }
  if (keyed.empty()) return;
  std::vector<char> is_root(count, 0);
  for (std::size_t other = 0; other < document["scenes"].size(); ++other) {
    if (other == scene || !document["scenes"][other].is_object()) continue;
    const Json& roots = document["scenes"][other].value("nodes", Json::array());
    if (!roots.is_array()) continue;
    std::fill(is_root.begin(), is_root.end(), 0);
    for (const Json& root : roots) {
      if (root.is_number_unsigned() && root.get<std::size_t>() < count) is_root[root.get<std::size_t>()] = 1;
    }
    std::vector<std::size_t> found;
    for (const std::size_t n : keyed) {
      if (is_root[static_cast<std::size_t>(root_of[n])]) found.push_back(n);
    }
    if (found.empty()) continue;
    std::string names;
    for (std::size_t k = 0; k < found.size() && k < 3; ++k) names += (k ? ", " : "") + node_label(document, found[k]);
    if (found.size() > 3) names += ", ...";
    const Json& converted = document["scenes"][scene];
    const std::string converted_name = converted.is_object() && converted.contains("name") && converted["name"].is_string()
                                           ? " " + value_text(converted["name"])
                                           : "";
    const Json& that = document["scenes"][other];
    const std::string other_name =
        that.contains("name") && that["name"].is_string() ? " " + value_text(that["name"]) : "";
    diag.warning(codes::SCENE_NOT_CONVERTED, json_pointer("/scenes", other),
                 "scene " + std::to_string(other) + other_name + " holds " + std::to_string(found.size()) +
                     " node(s) with rdtf properties (" + names + "), but rdtf converts one scene, scene " +
                     std::to_string(scene) + converted_name +
                     (document.contains("scene") ? " (the document's 'scene')" : " (the first: the document names none)") +
                     ": set the document's 'scene' to " + std::to_string(other) +
                     " to convert that one (in Blender, export with that scene active, or one scene only)");
  }
}

void check_units(const Json& document, const Robot& robot, Diagnostics& diag) {
  if (!document.contains("nodes")) return;
  if (robot.root_links.size() > 1) {
    std::string names;
    for (std::size_t k = 0; k < robot.root_links.size(); ++k) {
      if (k == 4) {
        names += ", ...";
        break;
      }
      names += (k ? ", '" : "'") + robot.links[robot.root_links[k]].name + "'";
    }
    const Link& second = robot.links[robot.root_links[1]];
    const auto packer = repacked_by(document);
    diag.warning(codes::MULTIPLE_ROOT_LINKS, json_pointer("/nodes", second.node),
                 std::to_string(robot.root_links.size()) + " root links (" + names +
                     "): a robot has one, so the others are bodies of their own (rdtf validate refuses "
                     "this; a URDF export holds them all by fixed joints). Parent them to the robot, or "
                     "leave them out of the export: Blender exports hidden objects, and the objects of "
                     "a collection excluded from the view layer, unless Include > Limit to > Visible "
                     "Objects is ticked" +
                     (packer ? ". The file was packed by '" + *packer + "', which " + packer_advice(*packer) : std::string()));
  }
  check_units_of(document, robot, diag);
  check_densities(document, robot, diag);
  check_typed_limits(document, robot, diag);
  check_shear(document, diag);
  check_duplicate_names(document, robot, diag);
}

bool check_finite_inertials(const Json& document, const Robot& robot, Diagnostics& diag) {
  bool finite = true;
  for (const Link& link : robot.links) {
    const MassProperties& m = link.inertial;
    const auto report = [&](const char* code, const std::string& what) {
      finite = false;
      diag.error(code, json_pointer("/nodes", link.node),
                 "link " + node_label(document, static_cast<std::size_t>(link.node)) + ": its " + what +
                     " is not finite: its meshes' scales or the density overflow double precision; give "
                     "the model sizes in metres and densities in kg/m^3");
    };
    if (!std::isfinite(m.mass) || !std::isfinite(m.volume)) {
      report(codes::LINK_MASS_NOT_FINITE, "mass (" + short_number(m.mass) + " kg, volume " + short_number(m.volume) + " m^3)");
    } else if (!m.center_of_mass.allFinite()) {
      report(codes::LINK_COM_NOT_FINITE, "centre of mass");
    } else if (!m.inertia.allFinite()) {
      report(codes::LINK_INERTIA_NOT_FINITE, "inertia");
    }
  }
  return finite;
}

}  // namespace rdtf
