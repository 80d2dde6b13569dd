// The robot as a reader wants it: a JSON summary (inspect --json, the daemon's tables) and a
// plain-text table for people.
#pragma once

#include <string>

#include "rdtf/diagnostics.h"
#include "rdtf/diagnostics_json.h"  // diagnostics_json, which robot_summary uses
#include "rdtf/gltf.h"
#include "rdtf/robot.h"

namespace rdtf {

struct RobotTotals {
  double mass = 0;
  double volume = 0;
  Eigen::Vector3d center_of_mass_scene = Eigen::Vector3d::Zero();  // p_SoScm_S
};

RobotTotals robot_totals(const Robot& robot);

// Links, joints (with their pose in the parent link frame), totals and diagnostics.
Json robot_summary(const Robot& robot, const Json& document, const Diagnostics& diag);

std::string robot_table(const Robot& robot, const Diagnostics& diag);

}  // namespace rdtf
