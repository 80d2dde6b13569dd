#include "live_names.h"

#include <cmath>

#include "diagnostic_message.h"
#include "rdtf/diagnostics.h"
#include "rdtf/urdf_names.h"
#include "safe_decode.h"

namespace rdtf::daemon {

Robot with_urdf_names(const Robot& robot, LiveNames& names) {
  const UrdfNames urdf = urdf_names(robot);
  Robot renamed = robot;
  names = LiveNames{};
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    // As the states carry them: a NUL (a name written \u0000 in the glTF) as \x00 (lcm_text).
    names.link_gltf.push_back(lcm_text(robot.links[l].name));
    renamed.links[l].name = urdf.links[l];
  }
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    names.joint_gltf[urdf.joints[j]] = lcm_text(robot.joints[j].name);
    names.joints_by_gltf[lcm_text(robot.joints[j].name)].push_back(urdf.joints[j]);
    renamed.joints[j].name = urdf.joints[j];
  }
  return renamed;
}

std::optional<std::string> LiveNames::joint(std::string_view name, std::string& why) const {
  if (const auto urdf = joint_gltf.find(name); urdf != joint_gltf.end()) return urdf->first;
  const auto gltf = joints_by_gltf.find(name);
  // Names from the bus go into ERROR messages and logs escaped.
  const std::string shown = lcm_safe::printable(name, 80);
  if (gltf == joints_by_gltf.end()) {
    why = "unknown joint '" + shown + "' (neither a joint's URDF name nor its glTF name)";
    return std::nullopt;
  }
  if (gltf->second.size() > 1) {
    why = "joint name '" + shown + "' is the glTF name of " + std::to_string(gltf->second.size()) +
          " joints (URDF names";
    for (std::size_t k = 0; k < gltf->second.size(); ++k) why += (k ? ", '" : " '") + gltf->second[k] + "'";
    why += "): name the joint by its URDF name";
    return std::nullopt;
  }
  return gltf->second.front();
}

std::string joint_commands_of(const rdtf::joint_command_t& command, const LiveNames& names,
                              const Simulation& simulation, std::vector<JointCommand>& commands) {
  commands.clear();
  if (command.num_joints < 0) return "num_joints is negative";
  const auto n = static_cast<std::size_t>(command.num_joints);
  if (command.name.size() != n || command.mode.size() != n || command.value.size() != n ||
      command.kp.size() != n || command.kd.size() != n) {
    return "array lengths do not match num_joints";
  }
  // All or nothing: check every joint before applying any.
  for (std::size_t i = 0; i < n; ++i) {
    // Names from the bus go into ERROR messages and logs escaped.
    const std::string name = lcm_safe::printable(command.name[i], 80);
    std::string why;
    const auto joint = names.joint(command.name[i], why);
    if (!joint) {
      commands.clear();
      return why;
    }
    if (!simulation.joint_state(*joint)) {
      commands.clear();
      return "joint '" + name + "' takes no command (not a one-degree-of-freedom joint)";
    }
    // One command per joint: a joint named twice (perhaps once by its URDF name and once by its
    // glTF name) says two things, and which one holds would be the order of the array.
    for (std::size_t k = 0; k < commands.size(); ++k) {
      if (commands[k].joint != *joint) continue;
      const std::string first = lcm_safe::printable(command.name[k], 80);
      commands.clear();
      return "joint '" + name + "' is named twice in one command (entries " + std::to_string(k) + " '" + first +
             "' and " + std::to_string(i) + "): send one entry per joint";
    }
    JointCommand c;
    c.joint = *joint;
    switch (command.mode[i]) {
      case rdtf::joint_command_t::TORQUE:
        c.mode = CommandMode::kTorque;
        c.effort = command.value[i];
        break;
      case rdtf::joint_command_t::POSITION:
        c.mode = CommandMode::kPosition;
        c.position = command.value[i];
        c.kp = command.kp[i];
        c.kd = command.kd[i];
        break;
      case rdtf::joint_command_t::VELOCITY:
        c.mode = CommandMode::kVelocity;
        c.velocity = command.value[i];
        c.kd = command.kd[i];
        break;
      default:
        commands.clear();
        return "unknown mode " + std::to_string(command.mode[i]) + " for joint '" + name + "'";
    }
    // Checked here too (set_command checks them again) so that a bad value for the last joint
    // leaves the others' commands unapplied. The reason names the field and its value as sent.
    const std::pair<const char*, double> sent[] = {{"value", command.value[i]}, {"kp", command.kp[i]}, {"kd", command.kd[i]}};
    for (const auto& [field, v] : sent) {
      // A torque command reads no gains, a velocity command no kp.
      const std::string_view f = field;
      const bool read = f == "value" || c.mode == CommandMode::kPosition || (f == "kd" && c.mode == CommandMode::kVelocity);
      if (!read) continue;
      if (!std::isfinite(v) || (std::string_view(field) != "value" && v < 0)) {
        commands.clear();
        return "command for '" + name + "' rejected: " + field + " " + format_number(v) +
               (std::isfinite(v) ? " is negative (gains must not be)" : " is not finite");
      }
    }
    commands.push_back(c);
  }
  return "";
}

}  // namespace rdtf::daemon
