#include "robot_models.h"

#include <stdexcept>

#include "../tests/dynamics/benchmark_robots.h"
#include "rdtf/convert.h"

namespace rdtf::bench {

// The chain and the tree are the gate tests' too (tests/dynamics/validation_gate_test.cc): one
// definition, so that the benchmark measures the models the tests pass.
Robot chain_robot(int links) { return benchmark_robots::chain_robot(links); }
Robot tree_robot(int links) { return benchmark_robots::tree_robot(links); }

Robot arm3_robot() {
  const std::filesystem::path path = std::filesystem::path(RDTF_BENCH_DATA_DIR) / "blender" / "arm3.gltf";
  Diagnostics diag;
  auto conversion = convert_file(path, ConvertOptions{}, diag);
  if (!conversion) throw std::runtime_error("cannot convert " + path.string());
  return std::move(conversion->robot);
}

std::map<std::string, double> bent_pose(const Robot& robot, double angle) {
  std::map<std::string, double> pose;
  for (const Joint& joint : robot.joints) {
    if (joint.kind == JointKind::kRevolute || joint.kind == JointKind::kContinuous) pose[joint.name] = angle;
  }
  return pose;
}

}  // namespace rdtf::bench
