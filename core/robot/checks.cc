// Checks that the converted robot is the one that was modelled: the mistakes a modeller makes
// that still give a valid (but wrong) robot.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "rdtf/completion.h"
#include "rdtf/robot.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

// Bounds of a plausible robot in metres and kilograms. A model drawn in millimetres and exported
// as metres is 1000 times too long and 1e9 times too heavy: a 0.6 m arm becomes 600 m and 3e10
// kg. The bounds sit well above the largest robots (excavators, gantries: tens of metres, tens of
// tonnes) and far below what the millimetre mistake gives for anything of hand size.
constexpr double kMaxExtent = 100.0;     // m
constexpr double kMaxMass = 1.0e6;       // kg

std::string short_number(double value) {
  std::ostringstream out;
  out.precision(3);
  out << value;
  return out.str();
}

bool has_rdtf_keys(const Json& document) {
  if (document.contains("extras") && document["extras"].is_object() &&
      document["extras"].contains("RDTF")) {
    return true;
  }
  for (const Json& node : document["nodes"]) {
    if (!node.contains("extras") || !node["extras"].is_object()) continue;
    for (const auto& [key, value] : node["extras"].items()) {
      if (key.rfind("rdtf_", 0) == 0) return true;
    }
  }
  return false;
}

void check_units_of(const Json& document, const Robot& robot, Diagnostics& diag) {
  if (robot.links.empty()) return;
  Eigen::AlignedBox3d box;
  double largest_part = 0;  // m: edge of a cube of the largest link's volume
  double mass = 0;
  int heaviest = 0;
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    box.extend(link.X_SL.translation());
    if (link.inertial.mass > 0) box.extend(link.X_SL * link.inertial.center_of_mass);
    largest_part = std::max(largest_part, std::cbrt(std::max(0.0, link.inertial.volume)));
    mass += link.inertial.mass;
    if (link.inertial.mass > robot.links[heaviest].inertial.mass) heaviest = static_cast<int>(l);
  }
  const double extent = std::max(box.diagonal().norm(), largest_part);
  if (extent <= kMaxExtent && mass <= kMaxMass) return;
  const Link& link = robot.links[heaviest];
  diag.warning(codes::UNITS_IMPLAUSIBLE, json_pointer("/nodes", link.node),
               "the robot is " + short_number(extent) + " m across and weighs " +
                   short_number(mass) + " kg (" + node_label(document, link.node) + " alone " +
                   short_number(link.inertial.mass) +
                   " kg): implausible in metres. glTF lengths are metres; the model was likely "
                   "drawn in millimetres: scale it by 0.001 (in Blender: select all, scale by "
                   "0.001, Object > Apply > Scale) and export again");
}

}  // namespace

void check_missing_properties(const Json& document, const std::vector<NodeType>& types,
                              Diagnostics& diag) {
  if (!document.contains("nodes") || has_rdtf_keys(document)) return;
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
  bool bones = false;
  for (std::size_t i = 0; i < types.size() && i < document["nodes"].size(); ++i) {
    const Json& node = document["nodes"][i];
    if (types[i] == NodeType::kNone) continue;
    if (node.contains("skin")) bones = true;
    const bool has_children = node.contains("children") && !node["children"].empty();
    if (!node.contains("mesh") && has_children && is_child[i] && !bone[i] &&
        (types[i] == NodeType::kJoint || types[i] == NodeType::kLink)) {
      empties.push_back(i);
    }
  }
  if (empties.empty() && !bones) return;
  std::string names;
  for (std::size_t k = 0; k < empties.size() && k < 4; ++k) {
    names += (k ? ", " : "") + node_label(document, empties[k]);
  }
  if (empties.size() > 4) names += ", ...";
  diag.warning(codes::NO_RDTF_PROPERTIES, "/nodes",
               std::string("no node has an rdtf_* property, so every joint is fixed and the robot is "
                           "one rigid body") +
                   (names.empty() ? std::string() : "; these empties look like joints: " + names) +
                   (bones ? std::string("; the model has an armature") : std::string()) +
                   ". In Blender, tick File > Export > glTF 2.0 > Include > Custom Properties "
                   "(export_extras=True): it is off by default; on an armature set the "
                   "properties on the Bone (Bone tab, edit or object mode), not on the pose bone, "
                   "whose properties are never exported");
}

void check_units(const Json& document, const Robot& robot, Diagnostics& diag) {
  if (document.contains("nodes")) check_units_of(document, robot, diag);
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
