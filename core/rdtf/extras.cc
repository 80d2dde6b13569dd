#include <map>

#include "rdtf/rdtf_extras.h"

namespace rdtf {
namespace {

Json joint_to_json(const Joint& joint) {
  Json out = {{"type", to_string(joint.kind)}};
  if (joint.kind != JointKind::kFixed && joint.kind != JointKind::kFloating &&
      joint.kind != JointKind::kBall) {
    out["axis"] = vector_to_json(joint.axis);
  }
  if (joint.limits) {
    out["lower"] = joint.limits->lower;
    out["upper"] = joint.limits->upper;
    if (joint.limits->effort > 0) out["effort"] = joint.limits->effort;
    if (joint.limits->velocity > 0) out["velocity"] = joint.limits->velocity;
  }
  out["friction"] = joint.friction;
  out["damping"] = joint.damping;
  out["springStiffness"] = joint.spring_stiffness;
  return out;
}

Json inertial_to_json(const MassProperties& inertial) {
  return {{"mass", inertial.mass},
          {"gravityCenter", vector_to_json(inertial.center_of_mass)},
          {"inertia", inertia_to_json(inertial.inertia)},
          {"volume", inertial.volume},
          {"frame", "link"},
          {"source", "computed"}};
}

}  // namespace

Json inertia_to_json(const Eigen::Matrix3d& I) {
  return Json::array({I(0, 0), I(0, 1), I(0, 2), I(1, 1), I(1, 2), I(2, 2)});
}

Json vector_to_json(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

bool write_rdtf_extras(Json& document, const std::vector<NodeType>& types, const Robot& robot,
                       Diagnostics& diag) {
  if (document.contains("extras") && !document["extras"].is_object()) {
    diag.error("EXTRAS_NOT_OBJECT", "/extras",
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
  std::map<int, const Joint*> joint_of_node;
  for (const Joint& joint : robot.joints) {
    if (joint.node >= 0) joint_of_node[joint.node] = &joint;
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
    if (types[i] == NodeType::kJoint && !entry.contains("joint")) {
      if (const auto joint = joint_of_node.find(static_cast<int>(i)); joint != joint_of_node.end()) {
        entry["joint"] = joint_to_json(*joint->second);
      }
    }
    if (types[i] == NodeType::kInertial) {
      const auto link = link_of_inertial.find(static_cast<int>(i));
      const bool authored = link != link_of_inertial.end() &&
                            link->second->inertial_source == InertialSource::kAuthored;
      if (link != link_of_inertial.end() && !authored) {
        entry["inertial"] = inertial_to_json(link->second->inertial);
      }
    }
    nodes.push_back(std::move(entry));
  }
  if (!rdtf.contains("version")) rdtf["version"] = "1.0";
  rdtf["nodes"] = std::move(nodes);
  return true;
}

}  // namespace rdtf
