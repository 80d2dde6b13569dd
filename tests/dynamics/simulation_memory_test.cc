// What one live simulation holds on the heap once it has stepped: rdtfd keeps one per live model
// (10,000 models, docs/benchmarks.md), so a few KiB more per world is tens of MiB. ODE reserves
// 64 KiB for each of a world's two step arenas by default (dWORLDSTEP_RESERVESIZE_DEFAULT), which
// alone is 128 KiB a world; rdtfd's worlds reserve what they need.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "dynamics/dynamics_models.h"
#include "support/heap_in_use.h"

namespace rdtf {
namespace {

using dynamics_test::box_inertial;
using dynamics_test::RobotBuilder;

using testing::heap_in_use;

// Heap per simulation of `robot`, each created and stepped once (ODE sizes its step arenas at
// the first step), over `count` of them alive at once.
double heap_per_simulation(const Robot& robot, int count) {
  std::vector<std::unique_ptr<Simulation>> simulations;
  simulations.reserve(static_cast<std::size_t>(count));
  const std::size_t before = heap_in_use();
  for (int i = 0; i < count; ++i) {
    Diagnostics diag;
    simulations.push_back(Simulation::create(robot, SimulationOptions{}, {}, diag));
    EXPECT_TRUE(simulations.back() != nullptr) << dynamics_test::all_text(diag);
    if (!simulations.back()) return 0;
    simulations.back()->step();
  }
  const std::size_t after = heap_in_use();
  return (static_cast<double>(after) - static_cast<double>(before)) / count;
}

Robot one_box() {
  RobotBuilder b;
  b.root("box", box_inertial(1.0, {0.1, 0.1, 0.1}, {0, 0, 0}));
  return b.robot();
}

Robot pendulum() {
  RobotBuilder b;
  const int root = b.root("frame", MassProperties{});
  b.child(root, "pivot", JointKind::kRevolute, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitZ(), "bar",
          box_inertial(2.0, {0.05, 0.5, 0.05}, {0, -0.25, 0}));
  return b.robot();
}

// 32 KiB: a quarter of what ODE's default reservation alone takes, and several times what a
// world of one body holds (printed below).
constexpr double kBoundBytes = 32 * 1024;

TEST(DaemonLiveSimulationMemory, AWorldHoldsWhatItNeedsNotODEsDefaultReservation) {
  for (const auto& [name, robot] : {std::pair{"one fixed box", one_box()}, std::pair{"pendulum", pendulum()}}) {
    const double bytes = heap_per_simulation(robot, 200);
    std::cout << name << ": " << bytes << " bytes of heap per stepped simulation\n";
    EXPECT_GT(bytes, 0) << name;
    EXPECT_LT(bytes, kBoundBytes) << name;
  }
}

}  // namespace
}  // namespace rdtf
