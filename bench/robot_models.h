// Robots for the dynamics benchmarks (issue 4), built as values the way the converter fills them:
// the arm3 fixture converted from tests/data/blender, a serial chain and a branching tree of boxes
// on revolute joints, every root link held by the world.
#pragma once

#include <map>
#include <string>

#include "rdtf/robot.h"

namespace rdtf::bench {

// `links` links in a row: a 0.5 kg box (0.04 x 0.2 x 0.04 m) hanging along -Y from each joint,
// joints about Z and X in turn, 0.2 m apart (tests/dynamics/benchmark_robots.h, shared with the
// gate's tests).
Robot chain_robot(int links);

// `links` links, link i (i >= 1) on a joint below link (i - 1) / 2: a binary tree of the same
// boxes and joints, about seven levels deep for 100 links.
Robot tree_robot(int links);

// The arm3 fixture (tests/data/blender/arm3.gltf) through the converter. Throws on failure.
Robot arm3_robot();

// A start pose off equilibrium, so that the run has motion: `angle` rad on every revolute or
// continuous joint (what the gate does with ValidationOptions::start_offset_angular = angle).
std::map<std::string, double> bent_pose(const Robot& robot, double angle);

}  // namespace rdtf::bench
