#include "rdtf/robot.h"

#include <cmath>

#include "rdtf/completion.h"
#include "rdtf/geometry.h"

namespace rdtf {
namespace {

// Where a joint's properties were found, and the frame its axis is expressed in.
struct JointSource {
  const Json* values = nullptr;  // Object holding the keys.
  std::string pointer;           // JSON pointer of that object.
  bool rdtf_entry = false;       // extras.RDTF joint object (keys without the "rdtf_" prefix).
  int frame_node = -1;           // Node whose frame a node-extras axis is in.
};

std::string key_for(const JointSource& source, const std::string& rdtf_key,
                    const std::string& extras_key) {
  return source.rdtf_entry ? rdtf_key : extras_key;
}

std::optional<double> read_number(const JointSource& source, const std::string& key,
                                  Diagnostics& diag) {
  if (!source.values->contains(key)) return std::nullopt;
  const Json& value = (*source.values)[key];
  if (!value.is_number() || !std::isfinite(value.get<double>())) {
    diag.error("RDTF_INVALID_VALUE", json_pointer(source.pointer, key), key + " must be a finite number");
    return std::nullopt;
  }
  return value.get<double>();
}

// The extras.RDTF entry for each node that has one.
std::vector<const Json*> rdtf_entries(const Json& document, std::vector<std::string>& pointers) {
  const std::size_t count = document["nodes"].size();
  std::vector<const Json*> entries(count, nullptr);
  pointers.assign(count, "");
  if (!document.contains("extras") || !document["extras"].is_object()) return entries;
  const Json& extras = document["extras"];
  if (!extras.contains("RDTF") || !extras["RDTF"].is_object()) return entries;
  const Json& rdtf = extras["RDTF"];
  if (!rdtf.contains("nodes") || !rdtf["nodes"].is_array()) return entries;
  for (std::size_t i = 0; i < rdtf["nodes"].size(); ++i) {
    const Json& entry = rdtf["nodes"][i];
    if (!entry.is_object() || !entry.contains("node") || !entry["node"].is_number_unsigned()) continue;
    const auto node = entry["node"].get<std::size_t>();
    if (node < count) {
      entries[node] = &entry;
      pointers[node] = json_pointer("/extras/RDTF/nodes", i);
    }
  }
  return entries;
}

const Json* node_extras(const Json& document, std::size_t node) {
  const Json& n = document["nodes"][node];
  if (!n.contains("extras") || !n["extras"].is_object()) return nullptr;
  return &n["extras"];
}

bool has_joint_keys(const Json& extras) {
  for (const char* key : {"rdtf_joint", "rdtf_axis", "rdtf_lower", "rdtf_upper", "rdtf_damping",
                          "rdtf_friction", "rdtf_spring_stiffness", "rdtf_effort", "rdtf_velocity"}) {
    if (extras.contains(key)) return true;
  }
  return false;
}

void read_joint_properties(const JointSource& source, const Eigen::Affine3d& X_SF,
                           const Eigen::Isometry3d& X_SC, Joint& joint, Diagnostics& diag) {
  const std::string kind_key = key_for(source, "type", "rdtf_joint");
  if (source.values->contains(kind_key)) {
    const Json& value = (*source.values)[kind_key];
    const auto kind = value.is_string() ? joint_kind_from_string(value.get<std::string>()) : std::nullopt;
    if (!kind) {
      diag.error("RDTF_INVALID_JOINT_TYPE", json_pointer(source.pointer, kind_key),
                 "joint type must be one of fixed, revolute, continuous, prismatic, floating, "
                 "planar, ball");
    } else {
      joint.kind = *kind;
    }
  }
  const std::string axis_key = key_for(source, "axis", "rdtf_axis");
  if (source.values->contains(axis_key)) {
    const Json& value = (*source.values)[axis_key];
    const std::string pointer = json_pointer(source.pointer, axis_key);
    bool valid = value.is_array() && value.size() == 3;
    for (std::size_t i = 0; valid && i < 3; ++i) {
      valid = value[i].is_number() && std::isfinite(value[i].get<double>());
    }
    if (!valid) {
      diag.error("RDTF_INVALID_VALUE", pointer, "axis must be three finite numbers");
    } else {
      Eigen::Vector3d axis(value[0].get<double>(), value[1].get<double>(), value[2].get<double>());
      // A node-extras axis is a direction in that node's frame; map it into the child link frame.
      if (!source.rdtf_entry) axis = X_SC.linear().transpose() * (X_SF.linear() * axis);
      if (axis.norm() == 0.0) {
        diag.error("JOINT_AXIS_ZERO", pointer, "the joint axis is the zero vector");
      } else {
        joint.axis = axis.normalized();
      }
    }
  }
  const auto lower = read_number(source, key_for(source, "lower", "rdtf_lower"), diag);
  const auto upper = read_number(source, key_for(source, "upper", "rdtf_upper"), diag);
  const auto effort = read_number(source, key_for(source, "effort", "rdtf_effort"), diag);
  const auto velocity = read_number(source, key_for(source, "velocity", "rdtf_velocity"), diag);
  if (lower || upper || effort || velocity) {
    JointLimits limits;
    limits.lower = lower.value_or(0.0);
    limits.upper = upper.value_or(0.0);
    limits.effort = effort.value_or(0.0);
    limits.velocity = velocity.value_or(0.0);
    if (limits.lower > limits.upper) {
      diag.error("JOINT_LIMITS_INVERTED", source.pointer,
                 "lower limit " + std::to_string(limits.lower) + " is above upper limit " +
                     std::to_string(limits.upper));
    }
    joint.limits = limits;
  }
  joint.damping = read_number(source, key_for(source, "damping", "rdtf_damping"), diag).value_or(0);
  joint.friction = read_number(source, key_for(source, "friction", "rdtf_friction"), diag).value_or(0);
  joint.spring_stiffness =
      read_number(source, key_for(source, "springStiffness", "rdtf_spring_stiffness"), diag)
          .value_or(0);
}

}  // namespace

const char* to_string(JointKind kind) {
  switch (kind) {
    case JointKind::kFixed:
      return "fixed";
    case JointKind::kRevolute:
      return "revolute";
    case JointKind::kContinuous:
      return "continuous";
    case JointKind::kPrismatic:
      return "prismatic";
    case JointKind::kFloating:
      return "floating";
    case JointKind::kPlanar:
      return "planar";
    case JointKind::kBall:
      return "ball";
  }
  return "fixed";
}

std::optional<JointKind> joint_kind_from_string(const std::string& text) {
  for (JointKind kind : {JointKind::kFixed, JointKind::kRevolute, JointKind::kContinuous,
                         JointKind::kPrismatic, JointKind::kFloating, JointKind::kPlanar,
                         JointKind::kBall}) {
    if (text == to_string(kind)) return kind;
  }
  return std::nullopt;
}

Robot build_robot(const Json& document, const std::vector<NodeType>& types, std::size_t scene,
                  Diagnostics& diag) {
  Robot robot;
  const Json& scene_json = document["scenes"][scene];
  if (!document.contains("nodes")) return robot;
  const auto parents = node_parents(document);
  const auto world = node_world_transforms(document);
  std::vector<std::string> entry_pointers;
  const auto entries = rdtf_entries(document, entry_pointers);

  // Links in pre-order of the scene, so parents come before children.
  std::vector<int> link_of_node(types.size(), -1);
  std::vector<std::size_t> stack;
  const Json roots = scene_json.value("nodes", Json::array());
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back(it->get<std::size_t>());
  std::vector<char> seen(types.size(), 0);
  while (!stack.empty()) {
    const std::size_t node = stack.back();
    stack.pop_back();
    if (seen[node]) continue;
    seen[node] = 1;
    if (types[node] == NodeType::kLink) {
      Link link;
      link.name = node_name(document, node);
      link.node = static_cast<int>(node);
      link.X_SL = rigid_part(world[node]);
      link_of_node[node] = static_cast<int>(robot.links.size());
      robot.links.push_back(std::move(link));
    }
    const Json children = document["nodes"][node].value("children", Json::array());
    for (auto it = children.rbegin(); it != children.rend(); ++it) stack.push_back(it->get<std::size_t>());
  }

  for (std::size_t c = 0; c < robot.links.size(); ++c) {
    Link& child = robot.links[c];
    // Walk up to the parent link, remembering the joint-typed nodes passed on the way.
    std::vector<int> joint_nodes;
    int up = parents[child.node];
    while (up >= 0 && types[up] != NodeType::kLink) {
      if (types[up] == NodeType::kJoint) joint_nodes.push_back(up);
      up = parents[up];
    }
    if (up < 0) {
      robot.root_links.push_back(static_cast<int>(c));
      continue;
    }
    Joint joint;
    joint.parent_link = link_of_node[up];
    joint.child_link = static_cast<int>(c);
    const Link& parent = robot.links[joint.parent_link];
    joint.node = joint_nodes.empty() ? -1 : joint_nodes.front();
    joint.name = joint.node >= 0 ? node_name(document, joint.node)
                                 : parent.name + "_" + child.name + "_joint";
    if (joint_nodes.size() > 1) {
      diag.info("JOINT_CHAIN", json_pointer("/nodes", joint_nodes.front()),
                std::to_string(joint_nodes.size()) + " joint nodes between links '" + parent.name +
                    "' and '" + child.name + "': they make one joint");
    }
    joint.X_PJ = parent.X_SL.inverse() * child.X_SL;

    // Sources of properties, first found wins: the RDTF entry of a joint node, then node extras
    // of the joint nodes (nearest the child first), then of the child link node.
    std::optional<JointSource> source;
    for (int node : joint_nodes) {
      const Json* entry = entries[node];
      if (entry != nullptr && entry->contains("joint") && (*entry)["joint"].is_object()) {
        source = JointSource{&(*entry)["joint"], entry_pointers[node] + "/joint", true, node};
        break;
      }
    }
    std::vector<int> extras_nodes = joint_nodes;
    extras_nodes.push_back(child.node);
    for (std::size_t i = 0; !source && i < extras_nodes.size(); ++i) {
      const Json* extras = node_extras(document, extras_nodes[i]);
      if (extras != nullptr && has_joint_keys(*extras)) {
        source = JointSource{extras, json_pointer("/nodes", extras_nodes[i]) + "/extras", false,
                             extras_nodes[i]};
      }
    }
    if (source) read_joint_properties(*source, world[source->frame_node], child.X_SL, joint, diag);
    child.parent_joint = static_cast<int>(robot.joints.size());
    robot.links[joint.parent_link].child_joints.push_back(child.parent_joint);
    robot.joints.push_back(std::move(joint));
  }
  if (robot.links.empty()) {
    diag.warning("NO_LINKS", "/scenes/" + std::to_string(scene),
                 "the scene has no link: nothing in it carries a mesh or children");
  }
  return robot;
}

}  // namespace rdtf
