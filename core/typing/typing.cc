#include "rdtf/typing.h"

#include <algorithm>
#include <cstdint>
#include <map>

#include "rdtf/completion.h"
#include "rdtf/geometry.h"
#include "rdtf/mesh_carriers.h"
#include "rdtf/robot.h"
#include "rdtf/diagnostic_codes.h"
#include "../robot/scene_nodes.h"

namespace rdtf {
namespace {

// Whether each node has a mesh for typing: its own, unless it is a mesh carrier, or its carrier
// child's (rdtf/mesh_carriers.h): a node and the carrier an encoder gave its mesh type as the node
// with the mesh did.
class MeshOwnership {
 public:
  explicit MeshOwnership(const Json& document) : carrier_(mesh_carrier_nodes(document)), has_(carrier_.size(), 0) {
    const Json& nodes = document["nodes"];
    for (std::size_t i = 0; i < carrier_.size(); ++i) {
      if (nodes[i].contains("mesh") && !carrier_[i]) has_[i] = 1;
    }
    for (std::size_t i = 0; i < carrier_.size(); ++i) {
      if (!nodes[i].contains("children")) continue;
      for (const Json& child : nodes[i]["children"]) {
        if (carrier_[child.get<std::size_t>()]) has_[i] = 1;
      }
    }
    // Once per parent, not once per child: asked for each of a node's leaves, a walk of its
    // children made a node of 40,000 empty children (camera frames) take seconds.
    child_has_.assign(carrier_.size(), 0);
    for (std::size_t i = 0; i < carrier_.size(); ++i) {
      if (!nodes[i].contains("children")) continue;
      for (const Json& child : nodes[i]["children"]) {
        if (has_[child.get<std::size_t>()]) child_has_[i] = 1;
      }
    }
  }
  bool has_mesh(std::size_t node) const { return has_[node] != 0; }
  bool carrier(std::size_t node) const { return carrier_[node] != 0; }
  bool a_child_has_mesh(std::size_t node) const { return child_has_[node] != 0; }

 private:
  std::vector<char> carrier_, has_, child_has_;
};

const Json* node_extras(const Json& node) {
  if (!node.contains("extras") || !node["extras"].is_object()) return nullptr;
  return &node["extras"];
}

bool has_extra(const Json& node, const char* key) {
  const Json* extras = node_extras(node);
  return extras != nullptr && extras->contains(key);
}

std::vector<std::size_t> children_of(const Json& node) {
  std::vector<std::size_t> children;
  if (node.contains("children")) {
    for (const Json& child : node["children"]) children.push_back(child.get<std::size_t>());
  }
  return children;
}

// extras.RDTF.version, "MAJOR.MINOR" (docs/format.md). A minor version adds keys and keeps what the
// others mean, so a later 1.x reads as 1.0 with a warning; another major changes meanings, so
// reading it as 1.0 could give a wrong robot with no error.
void check_format_version(const Json& version, Diagnostics& diag) {
  const std::string pointer = "/extras/RDTF/version";
  const std::string text = version.is_string() ? version.get<std::string>() : std::string();
  std::size_t dot = text.find('.');
  const auto digits = [&](std::size_t from, std::size_t to) {
    return to > from && to - from <= 9 &&
           std::all_of(text.begin() + static_cast<std::ptrdiff_t>(from), text.begin() + static_cast<std::ptrdiff_t>(to),
                       [](char c) { return c >= '0' && c <= '9'; });
  };
  if (dot == std::string::npos || !digits(0, dot) || !digits(dot + 1, text.size())) {
    diag.error(codes::RDTF_INVALID_VALUE, pointer,
               "extras.RDTF.version is " + value_text(version) + ", not a version string such as \"1.0\"");
    return;
  }
  const unsigned long major = std::stoul(text.substr(0, dot));
  const unsigned long minor = std::stoul(text.substr(dot + 1));
  if (major != 1) {
    diag.error(codes::RDTF_INVALID_VALUE, pointer,
               "extras.RDTF.version is " + value_text(version) +
                   ": this rdtf reads RDTF format 1.x; another major version may give its keys other "
                   "meanings, so reading it as 1.0 could give a wrong robot");
  } else if (minor > 0) {
    diag.warning(codes::RDTF_VERSION_NEWER, pointer,
                 "extras.RDTF.version is " + value_text(version) +
                     ", newer than the 1.0 this rdtf reads: its 1.0 keys are read, others are kept unread");
  }
}

// Types the document or its author fixed: extras.RDTF.nodes[].type, then node extras rdtf_type.
void read_authored_types(const Json& document, std::vector<NodeType>& types,
                         std::vector<char>& fixed, Diagnostics& diag) {
  const Json& nodes = document["nodes"];
  if (document.contains("extras") && document["extras"].is_object() &&
      document["extras"].contains("RDTF")) {
    const Json& rdtf = document["extras"]["RDTF"];
    // What the output would silently replace: an RDTF that is no object, nodes that are no list.
    if (!rdtf.is_object()) {
      diag.error(codes::RDTF_INVALID_VALUE, "/extras/RDTF",
                 "extras.RDTF is " + value_text(rdtf) + ", not an object (docs/format.md)");
    } else if (rdtf.contains("nodes") && !rdtf["nodes"].is_array()) {
      diag.error(codes::RDTF_INVALID_VALUE, "/extras/RDTF/nodes",
                 "extras.RDTF.nodes is " + value_text(rdtf["nodes"]) + ", not an array of node entries");
    }
    if (rdtf.is_object() && rdtf.contains("version")) check_format_version(rdtf["version"], diag);
    if (rdtf.is_object() && rdtf.contains("nodes") && rdtf["nodes"].is_array()) {
      const Json& entries = rdtf["nodes"];
      std::map<std::size_t, std::size_t> first_entry;  // Node -> its first entry.
      // A packer that renumbers or removes nodes keeps extras.RDTF as it was: its entries then
      // name other nodes or none, and the error says so and how to recover (s90tools D5: the
      // errors named the index only, and deleting just those entries gave a 0 kg base).
      const auto packer = repacked_by(document);
      const std::string repacked =
          packer ? "; asset.generator is '" + *packer +
                       "', which renumbers or removes nodes (prune, flatten, join) but keeps extras.RDTF as rdtf "
                       "wrote it, so its entries, in range or not, no longer name the nodes they describe: remove "
                       "extras.RDTF (the node extras rdtf writes beside it describe the same robot), or pack "
                       "without those steps"
                 : std::string();
      for (std::size_t i = 0; i < entries.size(); ++i) {
        const std::string pointer = json_pointer("/extras/RDTF/nodes", i);
        const Json& entry = entries[i];
        if (!entry.is_object() || !entry.contains("node") || !entry["node"].is_number_unsigned() ||
            entry["node"].get<std::size_t>() >= nodes.size()) {
          diag.error(codes::RDTF_INVALID_NODE_ENTRY, pointer,
                     std::string("an RDTF node entry needs \"node\": the index of an existing node "
                                 "(0 to ") + std::to_string(nodes.size() - 1) + "); it has " +
                         (entry.is_object() && entry.contains("node") ? value_text(entry["node"])
                                                                      : std::string("none")) +
                         repacked);
          continue;
        }
        const auto listed = entry["node"].get<std::size_t>();
        if (!first_entry.emplace(listed, i).second) {
          diag.error(codes::RDTF_INVALID_NODE_ENTRY, pointer + "/node",
                     node_label(document, listed) + " is listed again (first at " +
                         json_pointer("/extras/RDTF/nodes", first_entry[listed]) +
                         "): one entry per node, or which one holds its type and properties is a guess");
          continue;
        }
        for (const char* key : {"joint", "inertial"}) {
          if (entry.contains(key) && !entry[key].is_object()) {
            diag.error(codes::RDTF_INVALID_VALUE, pointer + "/" + key,
                       "entry for " + node_label(document, listed) + ": " + key + " is " + value_text(entry[key]) +
                           ", not an object (docs/format.md lists its keys)");
          }
        }
        if (!entry.contains("type")) continue;
        const auto type =
            entry["type"].is_string() ? node_type_from_string(entry["type"].get<std::string>())
                                      : std::nullopt;
        if (!type) {
          diag.error(codes::RDTF_INVALID_TYPE, pointer + "/type",
                     "entry for " + node_label(document, entry["node"].get<std::size_t>()) +
                         ": type " + value_text(entry["type"]) +
                         " is not one of link, joint, mesh, visual, inertial");
          continue;
        }
        const auto node = entry["node"].get<std::size_t>();
        types[node] = *type;
        fixed[node] = 1;
      }
    }
  }
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Json* extras = node_extras(nodes[i]);
    if (extras == nullptr || !extras->contains("rdtf_type")) continue;
    const Json& value = (*extras)["rdtf_type"];
    if (fixed[i]) {
      // Typed by extras.RDTF, which takes precedence: a node-extras type that says otherwise (a
      // tool that edited one and not the other) is named, and the output's is rewritten to agree
      // (s90tools D4: it was kept, and the output read otherwise without its extras.RDTF).
      if (!value.is_string() || node_type_from_string(value.get<std::string>()) != types[i]) {
        diag.warning(codes::RDTF_NODE_EXTRAS_IGNORED, json_pointer("/nodes", i) + "/extras/rdtf_type",
                     node_label(document, i) + ": rdtf_type " + value_text(value) + " is not its type in extras.RDTF, '" +
                         to_string(types[i]) +
                         "'; extras.RDTF takes precedence, and the output's node extras are rewritten to agree");
      }
      continue;
    }
    const auto type = value.is_string() ? node_type_from_string(value.get<std::string>()) : std::nullopt;
    if (!type) {
      diag.error(codes::RDTF_INVALID_TYPE, json_pointer("/nodes", i) + "/extras/rdtf_type",
                 node_label(document, i) + ": rdtf_type " + value_text(value) +
                     " is not one of link, joint, mesh, visual, inertial");
      continue;
    }
    types[i] = *type;
    fixed[i] = 1;
  }
}

// Amendment: every joint of a skin used in the scene is a link (an armature is a kinematic tree).
void type_skin_joints(const Json& document, const std::vector<char>& in_scene,
                      std::vector<NodeType>& types, std::vector<char>& fixed) {
  const Json& nodes = document["nodes"];
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (!in_scene[i] || !nodes[i].contains("skin") || !nodes[i].contains("mesh")) continue;
    const Json& skin = document["skins"][nodes[i]["skin"].get<std::size_t>()];
    for (const Json& joint : skin["joints"]) {
      const auto j = joint.get<std::size_t>();
      if (fixed[j]) continue;
      types[j] = NodeType::kLink;
      fixed[j] = 1;
    }
  }
}

// Nodes whose placement an animation drives (a TRS channel, or KHR_animation_pointer at one).
std::vector<char> placed_by_animation(const Json& document) {
  const std::size_t count = document["nodes"].size();
  std::vector<char> out(count, 0);
  if (!document.contains("animations") || !document["animations"].is_array()) return out;
  for (const Json& animation : document["animations"]) {
    if (!animation.is_object() || !animation.contains("channels") || !animation["channels"].is_array()) continue;
    for (const Json& channel : animation["channels"]) {
      if (!channel.is_object() || !channel.contains("target") || !channel["target"].is_object()) continue;
      const auto animated = internal::animated_property(channel["target"]);
      if (!animated || animated->first >= count) continue;
      const std::string& path = animated->second;
      if (path == "translation" || path == "rotation" || path == "scale" || path == "matrix") out[animated->first] = 1;
    }
  }
  return out;
}

// A mesh in a group (its parent an empty, to be a link, that gives its parts rdtf_density or
// rdtf_mass) with only joint empties and frames parented to it: a part of the group, not a link of
// its own. Blender's modeller parents an axle's empty or a camera's frame to the part it sits on,
// inside the group that makes one body (docs/blender.md, "Frames"); typed a link, the part would
// leave the group's density and mass behind. An empty without them only holds the robot (a root
// "my_robot" over "base_link"): its parts keep their links, and their names. completion.cc hangs
// the part's children from the group's link.
bool part_of_group(const Json& nodes, const MeshOwnership& meshes, int parent_index, NodeType parent_type,
                   std::size_t index, const std::vector<std::size_t>& children, bool placed_by_animation) {
  const Json& node = nodes[index];
  if (parent_index < 0 || children.empty() || placed_by_animation || node.contains("skin")) return false;
  // Joint keys say the author meant the part to move (JOINT_TYPE_MISSING when rdtf_joint is not
  // among them): a link.
  for (const char* key : kJointExtrasKeys) {
    if (has_extra(node, key)) return false;
  }
  if (!has_extra(nodes[static_cast<std::size_t>(parent_index)], "rdtf_density") &&
      !has_extra(nodes[static_cast<std::size_t>(parent_index)], "rdtf_mass")) {
    return false;
  }
  // A part with physics of its own (KHR_physics_rigid_bodies) is a body the author made one.
  if (node.contains("extensions") && node["extensions"].is_object() &&
      node["extensions"].contains("KHR_physics_rigid_bodies")) {
    return false;
  }
  const auto parent = static_cast<std::size_t>(parent_index);
  if (meshes.has_mesh(parent) || (parent_type != NodeType::kNone && parent_type != NodeType::kLink)) return false;
  return std::all_of(children.begin(), children.end(), [&](std::size_t child) {
    return !meshes.has_mesh(child) && has_extra(nodes[child], "rdtf_joint");
  });
}

// Algorithm 2, amended: see docs/format.md, "Typing".
NodeType mesh_or_visual(const Json& nodes, const MeshOwnership& meshes, int parent_index,
                        NodeType parent_type, std::size_t index, const std::vector<char>& animated) {
  const Json& node = nodes[index];
  const Json* parent = parent_index < 0 ? nullptr : &nodes[parent_index];
  const auto has_mesh = [&](std::size_t i) { return meshes.has_mesh(i); };
  if (meshes.carrier(index)) return NodeType::kMesh;
  // A carrier child is the node's own mesh moved by an encoder, not a child of the author's: a
  // leaf mesh node whose mesh gltfpack moved into a carrier is still a leaf.
  std::vector<std::size_t> children;
  for (std::size_t child : children_of(node)) {
    if (!meshes.carrier(child)) children.push_back(child);
  }
  if (has_mesh(index)) {
    // A skinned mesh moves with its bones, whose links carry its mass: never a link itself.
    if (node.contains("skin") && children.empty()) return NodeType::kMesh;
    if (part_of_group(nodes, meshes, parent_index, parent_type, index, children, animated[index] != 0)) {
      return NodeType::kMesh;
    }
    // Blender puts an object's mesh on the node that parents other objects; an object parented
    // to a mesh object moves on its own; and an object parented to a joint empty is what that
    // joint moves (an elbow empty under the upper-arm mesh, the forearm under the elbow): all links.
    if (!children.empty() || parent == nullptr || has_mesh(static_cast<std::size_t>(parent_index)) ||
        parent_type == NodeType::kJoint || has_extra(node, "rdtf_joint")) {
      return NodeType::kLink;
    }
    return NodeType::kMesh;
  }
  if (has_extra(node, "rdtf_joint")) {
    // A leaf empty fixed where it is, with nothing below, is a frame the modeller placed (a
    // camera's, a tool's centre point): a massless link of its own on that fixed joint, as URDF
    // keeps sensor frames. A moving joint with nothing below stays a joint node, and the robot
    // says it moves nothing (JOINT_MOVES_NOTHING).
    const Json& kind = (*node_extras(node))["rdtf_joint"];
    if (children.empty() && kind.is_string() && kind.get<std::string>() == "fixed") return NodeType::kLink;
    return NodeType::kJoint;
  }
  if (children.empty()) {
    const bool sibling_has_mesh = parent != nullptr && meshes.a_child_has_mesh(static_cast<std::size_t>(parent_index));
    if (!sibling_has_mesh) return NodeType::kVisual;
  }
  return NodeType::kNone;
}

// KHR_physics_rigid_bodies joint attachment frames: nodes that carry a joint or are a joint's
// connectedNode. As mesh-less leaves they are visual nodes, whatever their siblings (a frame
// beside a mesh would otherwise be typed a link by Algorithm 3).
std::vector<char> khr_attachment_nodes(const Json& nodes) {
  std::vector<char> out(nodes.size(), 0);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Json& node = nodes[i];
    if (!node.contains("extensions") || !node["extensions"].is_object()) continue;
    const Json& ext = node["extensions"];
    if (!ext.contains("KHR_physics_rigid_bodies") || !ext["KHR_physics_rigid_bodies"].is_object()) continue;
    const Json& physics = ext["KHR_physics_rigid_bodies"];
    if (!physics.contains("joint") || !physics["joint"].is_object()) continue;
    out[i] = 1;
    const Json& connected = physics["joint"].value("connectedNode", Json());
    if (connected.is_number_integer() && connected.get<std::int64_t>() >= 0 &&
        static_cast<std::uint64_t>(connected.get<std::int64_t>()) < nodes.size()) {
      out[static_cast<std::size_t>(connected.get<std::int64_t>())] = 1;
    }
  }
  return out;
}

// Algorithm 3.
NodeType joint_or_link(const Json& nodes, const MeshOwnership& meshes, std::size_t index) {
  const auto children = children_of(nodes[index]);
  if (children.size() == 1 && !meshes.has_mesh(children[0]) && !meshes.carrier(children[0])) {
    return NodeType::kJoint;
  }
  return NodeType::kLink;
}

}  // namespace

const char* to_string(NodeType type) {
  switch (type) {
    case NodeType::kLink:
      return "link";
    case NodeType::kJoint:
      return "joint";
    case NodeType::kMesh:
      return "mesh";
    case NodeType::kVisual:
      return "visual";
    case NodeType::kInertial:
      return "inertial";
    case NodeType::kNone:
      break;
  }
  return "none";
}

std::optional<NodeType> node_type_from_string(const std::string& text) {
  for (NodeType type : {NodeType::kLink, NodeType::kJoint, NodeType::kMesh, NodeType::kVisual,
                        NodeType::kInertial}) {
    if (text == to_string(type)) return type;
  }
  return std::nullopt;
}

std::optional<std::size_t> default_scene(const Json& document, Diagnostics& diag) {
  const std::size_t scenes = document.contains("scenes") ? document["scenes"].size() : 0;
  if (document.contains("scene")) return document["scene"].get<std::size_t>();
  if (scenes > 0) return 0;
  diag.error(codes::NO_SCENE, "/scenes", "the model has no scene, so no node tree to convert");
  return std::nullopt;
}

std::vector<NodeType> type_nodes(const Json& document, std::size_t scene, Diagnostics& diag) {
  const std::size_t count = document.contains("nodes") ? document["nodes"].size() : 0;
  std::vector<NodeType> types(count, NodeType::kNone);
  if (count == 0) return types;
  const Json& nodes = document["nodes"];

  // Algorithm 1: walk every root of the scene, parents before children.
  std::vector<std::pair<int, std::size_t>> order;  // (parent, node), pre-order
  std::vector<char> in_scene(count, 0);
  std::vector<std::pair<int, std::size_t>> stack;
  const Json& roots = document["scenes"][scene].value("nodes", Json::array());
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(-1, it->get<std::size_t>());
  while (!stack.empty()) {
    const auto [parent, node] = stack.back();
    stack.pop_back();
    if (in_scene[node]) continue;  // Validated documents have no cycles; stay safe regardless.
    order.emplace_back(parent, node);
    in_scene[node] = 1;
    const auto children = children_of(nodes[node]);
    for (auto it = children.rbegin(); it != children.rend(); ++it) {
      stack.emplace_back(static_cast<int>(node), *it);
    }
  }

  std::vector<char> fixed(count, 0);
  read_authored_types(document, types, fixed, diag);
  type_skin_joints(document, in_scene, types, fixed);
  // Nodes outside the scene get no type, authored ones included: a second Blender scene holding a
  // re-imported rdtf output types its nodes by rdtf_type, and a link typed there, which the robot
  // (built from the scene) never holds, crashed the mass computation.
  for (std::size_t i = 0; i < count; ++i) {
    if (!in_scene[i]) types[i] = NodeType::kNone;
  }
  const MeshOwnership meshes(document);
  const std::vector<char> animated = placed_by_animation(document);
  const auto khr_frames = khr_attachment_nodes(nodes);
  for (const auto& [parent, node] : order) {
    if (fixed[node]) continue;
    if (khr_frames[node] && !meshes.has_mesh(node) && children_of(nodes[node]).empty()) {
      types[node] = NodeType::kVisual;
      continue;
    }
    types[node] = mesh_or_visual(nodes, meshes, parent, parent < 0 ? NodeType::kNone : types[parent], node, animated);
  }
  for (const auto& [parent, node] : order) {
    if (fixed[node] || types[node] != NodeType::kNone) continue;
    types[node] = joint_or_link(nodes, meshes, node);
  }
  return types;
}

}  // namespace rdtf
