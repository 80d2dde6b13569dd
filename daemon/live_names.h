// The names of a live model's links and joints, both ways (URDF and glTF), and how a
// controller's command finds its joints by them. docs/controller.md, "The rules rdtfd applies".
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <rdtf/joint_command_t.hpp>

#include "rdtf/dynamics.h"
#include "rdtf/robot.h"

namespace rdtf::daemon {

// A live model's names. Its simulation runs on the robot with every link and joint renamed to
// its URDF name (rdtf/urdf_names.h: unique, and the names the URDF of the same revision has), so
// JOINT_STATE and LINK_STATE carry those and commands find joints by them; the glTF names ride
// along for the states' gltf_name.
struct LiveNames {
  std::vector<std::string> link_gltf;                          // glTF name of Robot::links[i]
  std::map<std::string, std::string, std::less<>> joint_gltf;  // URDF name -> glTF name
  // glTF name -> the URDF names of the joints that have it (several when it is not unique).
  std::map<std::string, std::vector<std::string>, std::less<>> joints_by_gltf;

  // The URDF name of the joint a command names: a joint's URDF name means that joint; any other
  // name may be a glTF name, which must be exactly one joint's. Nothing, and `why`, otherwise.
  std::optional<std::string> joint(std::string_view name, std::string& why) const;
};

// `robot` with its links and joints under their URDF names (what a live simulation runs), and
// both names of each in `names`.
Robot with_urdf_names(const Robot& robot, LiveNames& names);

// The joint commands a controller's message asks of `simulation` (which runs on the URDF names
// of `names`), all or nothing: empty with the reason when a joint is unknown or ambiguous
// (LiveNames::joint), a mode unknown or the arrays disagree with num_joints. Each command names
// its joint by URDF name. (Revision and content hash are checked by command_live_model.)
std::string joint_commands_of(const rdtf::joint_command_t& command, const LiveNames& names,
                              const Simulation& simulation, std::vector<JointCommand>& commands);

}  // namespace rdtf::daemon
