// The names a robot's links and joints have in its URDF (docs/urdf.md, "Names"). URDF export
// (export_urdf) names every link and joint with this function, and rdtfd's JOINT_STATE,
// LINK_STATE and INERTIA carry the same names, so a ROS tool that matches a state against the
// URDF always finds it.
#pragma once

#include <string>
#include <vector>

#include "rdtf/diagnostics.h"
#include "rdtf/robot.h"

namespace rdtf {

// glTF names are free text and need not be unique; URDF names here are unique among the links
// (and among the joints) and use only letters, digits, '_', '-' and '.': any other character
// becomes '_', an empty name becomes "link" or "joint", and a name already taken gets "_2", "_3",
// ... (in Robot::links and Robot::joints order, so the first of two equal names keeps it).
struct UrdfNames {
  std::vector<std::string> links;   // URDF name of Robot::links[i].
  std::vector<std::string> joints;  // URDF name of Robot::joints[j].
};

// The URDF names of `robot`'s links and joints. With `diag`, a URDF_NAME_CHANGED warning (node
// pointer, glTF name and URDF name) for every name that differs from the glTF one.
UrdfNames urdf_names(const Robot& robot, Diagnostics* diag = nullptr);

}  // namespace rdtf
