#include <initializer_list>
#include <map>
#include <optional>

#include "rdtf/rdtf_extras.h"

#include "rdtf/geometry.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

Json joint_to_json(const Joint& joint) {
  Json out = {{"type", to_string(joint.kind)}};
  if (joint.kind != JointKind::kFixed && joint.kind != JointKind::kFloating &&
      joint.kind != JointKind::kBall) {
    out["axis"] = vector_to_json(joint.axis);
  }
  if (joint.limits) {
    if (joint.limits->position) {
      out["lower"] = joint.limits->lower;
      out["upper"] = joint.limits->upper;
    }
    // 0 is "not given". A negative value (only a robot built in code has one: the readers refuse it)
    // is kept as given, for the dynamics check to refuse.
    if (joint.limits->effort != 0) out["effort"] = joint.limits->effort;
    if (joint.limits->velocity != 0) out["velocity"] = joint.limits->velocity;
  }
  out["friction"] = joint.friction;
  out["damping"] = joint.damping;
  out["springStiffness"] = joint.spring_stiffness;
  return out;
}

Json authored_inertial_json(const MassProperties& inertial) {
  return {{"mass", inertial.mass},
          {"gravityCenter", vector_to_json(inertial.center_of_mass)},
          {"inertia", inertia_to_json(inertial.inertia)},
          {"frame", "link"}};
}

Json inertial_to_json(const MassProperties& inertial) {
  return {{"mass", inertial.mass},
          {"gravityCenter", vector_to_json(inertial.center_of_mass)},
          {"inertia", inertia_to_json(inertial.inertia)},
          {"volume", inertial.volume},
          {"frame", "link"},
          {"source", "computed"}};
}

// The node's extras object, made when absent; nothing when it holds something else (left alone).
Json* extras_object(Json& node) {
  if (!node.contains("extras")) node["extras"] = Json::object();
  return node["extras"].is_object() ? &node["extras"] : nullptr;
}

bool has_any(const Json& extras, std::initializer_list<const char*> keys) {
  for (const char* key : keys) {
    if (extras.contains(key)) return true;
  }
  return false;
}

// The joint as Blender custom properties on its frame node, the axis in that node's frame.
void joint_to_extras(const Joint& joint, const Eigen::Matrix3d& R_FJ, Json& extras) {
  const Json values = joint_to_json(joint);
  extras["rdtf_joint"] = values["type"];
  if (values.contains("axis")) {
    extras["rdtf_axis"] = vector_to_json((R_FJ * joint.axis).normalized());
    extras["rdtf_axes"] = "gltf";
  }
  for (const auto& [key, name] : {std::pair{"lower", "rdtf_lower"}, {"upper", "rdtf_upper"},
                                  {"effort", "rdtf_effort"}, {"velocity", "rdtf_velocity"}}) {
    if (values.contains(key)) extras[name] = values[key];
  }
  if (joint.friction != 0) extras["rdtf_friction"] = joint.friction;
  if (joint.damping != 0) extras["rdtf_damping"] = joint.damping;
  if (joint.spring_stiffness != 0) extras["rdtf_spring_stiffness"] = joint.spring_stiffness;
}

// A positive number under `key` in a node's extras.
std::optional<double> positive_extra(const Json& node, const char* key) {
  if (!node.contains("extras") || !node["extras"].is_object() || !node["extras"].contains(key)) return std::nullopt;
  const Json& value = node["extras"][key];
  if (!value.is_number() || !(value.get<double>() > 0)) return std::nullopt;
  return value.get<double>();
}

// The factor by which the link's rdtf_mass scaled its meshes' densities: 1 without one; 0 when no
// mesh tells it (none has an authored density or mass).
double density_factor(const Json& nodes, const Link& link) {
  if (!positive_extra(nodes[static_cast<std::size_t>(link.node)], "rdtf_mass")) return 1;
  for (const LinkMesh& mesh : link.meshes) {
    const Json& node = nodes[static_cast<std::size_t>(mesh.node)];
    if (const auto density = positive_extra(node, "rdtf_density")) return mesh.density / *density;
    if (const auto mass = positive_extra(node, "rdtf_mass"); mass && mesh.volume > 0) return mesh.density * mesh.volume / *mass;
  }
  return 0;
}

}  // namespace

void write_node_extras(Json& document, const std::vector<NodeType>& types, const Robot& robot) {
  if (!document.contains("nodes")) return;
  Json& nodes = document["nodes"];
  const auto world = node_world_transforms(document);
  for (std::size_t i = 0; i < types.size() && i < nodes.size(); ++i) {
    if (types[i] == NodeType::kNone) continue;
    Json* extras = extras_object(nodes[i]);
    // Always the type the robot was built with: an authored one that extras.RDTF overrode would
    // read as another robot without extras.RDTF (typing warns RDTF_NODE_EXTRAS_IGNORED).
    if (extras != nullptr) (*extras)["rdtf_type"] = to_string(types[i]);
  }
  // Joints whose properties were not in node extras: written on the joint's frame node, where
  // they are read again (joint properties make a node a pivot, and this one is already the pivot).
  std::map<int, int> frames_shared;
  for (const Joint& joint : robot.joints) ++frames_shared[joint.frame_node];
  for (const Joint& joint : robot.joints) {
    if (joint.source_node >= 0 && !joint.source_is_entry) {
      // Kept as the author typed them. Which axes an rdtf_axis is in depends on the generator,
      // which encoders replace (gltfpack): say it on the node, where it survives them.
      Json& extras = nodes[joint.source_node]["extras"];
      if (extras.contains("rdtf_axis") && !extras.contains("rdtf_axes")) {
        extras["rdtf_axes"] = node_extras_in_blender_axes(document, joint.source_node) ? "blender" : "gltf";
      }
      continue;
    }
    // Node-extras keys that said otherwise than extras.RDTF (build_robot warned) go, wherever
    // they are: the joint's keys are written again on its frame node below.
    if (joint.ignored_extras_node >= 0 && nodes[joint.ignored_extras_node].contains("extras") &&
        nodes[joint.ignored_extras_node]["extras"].is_object()) {
      Json& stale = nodes[joint.ignored_extras_node]["extras"];
      for (const char* key : kJointExtrasKeys) stale.erase(key);
      stale.erase("rdtf_axes");
    }
    // On the frame node, unless other joints share it (a grouping joint node with a transform of
    // its own): joint keys there would make it one moving part when read again. The child link
    // node is read as a source too.
    const int target = frames_shared[joint.frame_node] > 1 ? robot.links[joint.child_link].node : joint.frame_node;
    Json* extras = extras_object(nodes[target]);
    if (extras == nullptr) continue;
    bool has_joint_keys = false;
    for (const char* key : kJointExtrasKeys) has_joint_keys |= extras->contains(key);
    if (has_joint_keys) continue;  // They agree with extras.RDTF: kept as they are.
    // The axis is in the child link frame (the frame node's, scale removed); as a node-extras
    // vector it is read in the node's frame with its scale: R_FJ undoes that.
    const Eigen::Matrix3d R_FJ = world[target].linear().inverse() * robot.links[joint.child_link].X_SL.linear();
    joint_to_extras(joint, R_FJ, *extras);
  }
  // Inertials and densities, so that a tool that keeps node extras only (Blender's importer drops
  // the document's extras) still gives the same masses.
  for (const Link& link : robot.links) {
    if (link.inertial_node >= 0) {
      Json* extras = extras_object(nodes[link.inertial_node]);
      // A computed one already there is an earlier output's, which this conversion computed again
      // (a part moved or rescaled since): it is never read as a source, and left as it was it
      // would tell a reader of node extras the old body (s101fmt D6).
      const bool stale = extras != nullptr && extras->contains("rdtf_inertial") &&
                         (*extras)["rdtf_inertial"].is_object() &&
                         (*extras)["rdtf_inertial"].value("source", Json()) == Json("computed");
      if (extras != nullptr && (!extras->contains("rdtf_inertial") || link.ignored_inertial_extras || stale)) {
        (*extras)["rdtf_inertial"] = link.inertial_source == InertialSource::kComputed
                                         ? inertial_to_json(link.inertial)
                                         : authored_inertial_json(link.inertial);
      }
    }
    if (link.inertial_source != InertialSource::kComputed) continue;
    // A link whose rdtf_mass scaled its meshes' densities by one factor gets them written as they
    // were before it: read again, the link's rdtf_mass scales them alike once more. A scaled
    // density written beside an authored one changed their ratio, and so the centre of mass
    // (s101fmt D1); none written, a mesh of the default density took another --density when read
    // again (s102rev D3). The factor is what scaled a mesh whose own density or mass is authored;
    // with none, every density is the default or inherited one, whose ratios no reading changes.
    const double factor = density_factor(nodes, link);
    if (!(factor > 0)) continue;
    for (const LinkMesh& mesh : link.meshes) {
      Json* extras = extras_object(nodes[mesh.node]);
      if (extras == nullptr || has_any(*extras, {"rdtf_density", "rdtf_mass"}) || mesh.density <= 0) continue;
      (*extras)["rdtf_density"] = mesh.density / factor;
    }
  }
}

Json inertia_to_json(const Eigen::Matrix3d& I) {
  return Json::array({I(0, 0), I(0, 1), I(0, 2), I(1, 1), I(1, 2), I(2, 2)});
}

Json vector_to_json(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

bool write_rdtf_extras(Json& document, const std::vector<NodeType>& types, const Robot& robot,
                       Diagnostics& diag) {
  // "extras": null says there are none (the validator accepts it): extras.RDTF takes its place.
  if (document.contains("extras") && document["extras"].is_null()) document.erase("extras");
  if (document.contains("extras") && !document["extras"].is_object()) {
    diag.error(codes::EXTRAS_NOT_OBJECT, "/extras",
               "the document's extras is not an object, so extras.RDTF cannot be added to it");
    return false;
  }
  Json& rdtf = document["extras"]["RDTF"];
  if (!rdtf.is_object()) rdtf = Json::object();
  std::map<std::size_t, Json> existing;
  if (rdtf.contains("nodes") && rdtf["nodes"].is_array()) {
    for (const Json& entry : rdtf["nodes"]) {
      if (entry.is_object() && entry.contains("node") && entry["node"].is_number_unsigned()) {
        existing[entry["node"].get<std::size_t>()] = entry;
      }
    }
  }
  // A joint node shared by several joints (the paper's node grouping a link's child links) gets
  // no "joint" in its entry: one entry cannot hold them all, and a joint node with properties is
  // one moving part when read again (docs/format.md, "Links and joints"). Their properties are in
  // node extras (write_node_extras).
  std::map<int, const Joint*> joint_of_node;
  std::map<int, int> joints_on_node;
  for (const Joint& joint : robot.joints) {
    if (joint.node < 0) continue;
    joint_of_node[joint.node] = &joint;
    ++joints_on_node[joint.node];
  }
  for (const auto& [node, count] : joints_on_node) {
    if (count > 1) joint_of_node.erase(node);
  }
  std::map<int, const Link*> link_of_inertial;
  for (const Link& link : robot.links) {
    if (link.inertial_node >= 0) link_of_inertial[link.inertial_node] = &link;
  }

  Json nodes = Json::array();
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (types[i] == NodeType::kNone) continue;
    const auto found = existing.find(i);
    Json entry = found != existing.end() ? found->second : Json{{"node", i}};
    entry["type"] = to_string(types[i]);
    if (types[i] == NodeType::kJoint) {
      const auto joint = joint_of_node.find(static_cast<int>(i));
      if (!entry.contains("joint")) {
        if (joint != joint_of_node.end()) entry["joint"] = joint_to_json(*joint->second);
      } else if (joint != joint_of_node.end() && joint->second->source_is_entry && entry["joint"].is_object() &&
                 entry["joint"].contains("axis") && entry["joint"]["axis"].is_array()) {
        // An authored vector axis goes out as the unit vector it was read as (a named axis is kept
        // as written): [0, 2, 0] read back by a tool taking q * axis as the motion doubled it. The
        // entry's axis is in the child link frame, as the joint's.
        entry["joint"]["axis"] = vector_to_json(joint->second->axis);
      }
    }
    if (types[i] == NodeType::kInertial) {
      // Every link's inertial, authored ones too (from KHR motion or node extras, which a reader
      // of extras.RDTF alone would not see: s101fmt D5); an authored one goes out without a
      // source, so it reads back as authored.
      const auto link = link_of_inertial.find(static_cast<int>(i));
      if (link != link_of_inertial.end()) {
        if (link->second->inertial_source != InertialSource::kAuthored) {
          entry["inertial"] = inertial_to_json(link->second->inertial);
        } else if (!entry.contains("inertial")) {
          entry["inertial"] = authored_inertial_json(link->second->inertial);
        }
      }
    }
    nodes.push_back(std::move(entry));
  }
  if (!rdtf.contains("version")) rdtf["version"] = "1.0";
  rdtf["nodes"] = std::move(nodes);
  write_node_extras(document, types, robot);
  return true;
}

}  // namespace rdtf
