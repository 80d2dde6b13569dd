#include "rdtf/summary.h"

#include <cstdio>
#include <sstream>
#include <string_view>

#include "rdtf/rdtf_extras.h"
#include "rdtf/diagnostics_json.h"
#include "rdtf/utf8.h"

namespace rdtf {
namespace {

std::string fixed(double value) { return format_number(value); }

std::string vector_text(const Eigen::Vector3d& v) {
  return "(" + fixed(v.x()) + ", " + fixed(v.y()) + ", " + fixed(v.z()) + ")";
}

Json pose_json(const Eigen::Isometry3d& X) {
  const Eigen::Quaterniond q(X.linear());
  return {{"translation", vector_to_json(X.translation())},
          {"rotation", Json::array({q.x(), q.y(), q.z(), q.w()})}};
}

}  // namespace

RobotTotals robot_totals(const Robot& robot) {
  RobotTotals totals;
  Eigen::Vector3d weighted = Eigen::Vector3d::Zero();
  for (const Link& link : robot.links) {
    totals.mass += link.inertial.mass;
    totals.volume += link.inertial.volume;
    weighted += link.inertial.mass * (link.X_SL * link.inertial.center_of_mass);
  }
  if (totals.mass > 0) totals.center_of_mass_scene = weighted / totals.mass;
  return totals;
}

Json robot_summary(const Robot& robot, const Json& document, const Diagnostics& diag) {
  (void)document;
  Json links = Json::array();
  for (const Link& link : robot.links) {
    Json meshes = Json::array();
    for (const LinkMesh& mesh : link.meshes) {
      meshes.push_back({{"node", mesh.node}, {"volume", mesh.volume}, {"density", mesh.density}});
    }
    links.push_back({{"name", json_safe(link.name)},
                     {"node", link.node},
                     {"parentJoint", link.parent_joint},
                     {"pose", pose_json(link.X_SL)},
                     {"mass", link.inertial.mass},
                     {"volume", link.inertial.volume},
                     {"centerOfMass", vector_to_json(link.inertial.center_of_mass)},
                     {"inertia", inertia_to_json(link.inertial.inertia)},
                     {"inertialSource", link.inertial_source == InertialSource::kAuthored ? "authored" : "computed"},
                     {"meshes", meshes}});
  }
  Json joints = Json::array();
  for (const Joint& joint : robot.joints) {
    Json item = {{"name", json_safe(joint.name)},
                 {"node", joint.node},
                 {"type", to_string(joint.kind)},
                 {"parent", json_safe(robot.links[joint.parent_link].name)},
                 {"child", json_safe(robot.links[joint.child_link].name)},
                 {"origin", pose_json(joint.X_PJ)},
                 {"axis", vector_to_json(joint.axis)},
                 {"damping", joint.damping},
                 {"friction", joint.friction},
                 {"springStiffness", joint.spring_stiffness}};
    // Each limit only when given, as in extras.RDTF: a reader cannot tell a 0 written for "none"
    // from a limit of 0 (lower and upper: an effort limit alone bounds no motion).
    if (joint.limits) {
      Json limits = Json::object();
      if (joint.limits->effort != 0) limits["effort"] = joint.limits->effort;
      if (joint.limits->velocity != 0) limits["velocity"] = joint.limits->velocity;
      if (joint.limits->position) {
        limits["lower"] = joint.limits->lower;
        limits["upper"] = joint.limits->upper;
      }
      item["limits"] = std::move(limits);
    }
    joints.push_back(std::move(item));
  }
  const RobotTotals totals = robot_totals(robot);
  return {{"robot", json_safe(robot.name)},
          {"frames", "inertial values are in each link's frame; poses in the scene frame (glTF: Y up, metres)"},
          {"links", links},
          {"joints", joints},
          {"totals", {{"mass", totals.mass}, {"volume", totals.volume},
                      {"centerOfMassScene", vector_to_json(totals.center_of_mass_scene)}}},
          {"diagnostics", diagnostics_json(diag)}};
}

std::string robot_table(const Robot& robot, const Diagnostics& diag) {
  std::ostringstream out;
  // Names are the input's to choose: escaped, so that none can forge a line or drive the terminal.
  const auto shown = [](const std::string& name) { return escape_for_terminal(name); };
  out << "robot '" << shown(robot.name) << "': " << robot.links.size() << " links, " << robot.joints.size()
      << " joints\n\nLINKS (inertial in the link frame)\n";
  for (const Link& link : robot.links) {
    const auto& I = link.inertial.inertia;
    out << "  " << shown(link.name) << "  (node " << link.node << ")"
        << (link.parent_joint < 0 ? "  root" : "") << "\n"
        << "    mass " << fixed(link.inertial.mass) << " kg   volume " << fixed(link.inertial.volume)
        << " m^3   " << (link.inertial_source == InertialSource::kAuthored ? "authored" : "computed")
        << "\n    centre of mass " << vector_text(link.inertial.center_of_mass) << " m\n"
        << "    inertia ixx " << fixed(I(0, 0)) << "  ixy " << fixed(I(0, 1)) << "  ixz "
        << fixed(I(0, 2)) << "  iyy " << fixed(I(1, 1)) << "  iyz " << fixed(I(1, 2)) << "  izz "
        << fixed(I(2, 2)) << " kg m^2\n";
  }
  out << "\nJOINTS (origin and axis in the parent link frame / joint frame)\n";
  for (const Joint& joint : robot.joints) {
    out << "  " << shown(joint.name) << "  " << to_string(joint.kind) << "  "
        << shown(robot.links[joint.parent_link].name) << " -> " << shown(robot.links[joint.child_link].name)
        << "\n    origin " << vector_text(joint.X_PJ.translation()) << " m   axis "
        << vector_text(joint.axis);
    if (joint.limits && joint.limits->position) {
      out << "   limits [" << fixed(joint.limits->lower) << ", " << fixed(joint.limits->upper) << "]";
    }
    if (joint.limits && joint.limits->effort != 0) out << "   effort " << fixed(joint.limits->effort);
    if (joint.limits && joint.limits->velocity != 0) out << "   velocity " << fixed(joint.limits->velocity);
    out << "\n    damping " << fixed(joint.damping) << "  friction " << fixed(joint.friction)
        << "  spring " << fixed(joint.spring_stiffness) << "\n";
  }
  const RobotTotals totals = robot_totals(robot);
  out << "\nTOTAL mass " << fixed(totals.mass) << " kg   volume " << fixed(totals.volume)
      << " m^3   centre of mass (scene) " << vector_text(totals.center_of_mass_scene) << " m\n";
  if (!diag.all().empty()) {
    out << "\nDIAGNOSTICS\n";
    for (const Diagnostic& d : diag.all()) out << "  " << shown(format(d)) << "\n";
  }
  return out.str();
}

}  // namespace rdtf
