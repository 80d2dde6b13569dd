// Joint springs and the energy the stepper keeps (docs/dynamics.md, "Energy balance"): a spring's
// torque is taken from the position before the step and the position moves with the speed after
// it (symplectic Euler), which conserves 1/2 m qdot^2 + 1/2 k q^2 - 1/2 h k q qdot exactly; the
// physical energy ripples about it by h omega / 2 of itself, which the gate read as energy made.
#include <gtest/gtest.h>

#include <cmath>

#include "dynamics/dynamics_models.h"

namespace rdtf {
namespace {

using dynamics_test::all_text;
using dynamics_test::box_inertial;
using dynamics_test::RobotBuilder;
using dynamics_test::simulate;
using dynamics_test::with_code;

// A 50 g carriage on an undamped spring of 600 N/m (omega = 110 rad/s, h omega = 0.11), let go
// 5 cm from rest with no gravity: it moves exactly as symplectic Euler, so the energy health()
// reports is constant to rounding at every step, while 1/2 m v^2 + 1/2 k q^2 swings by 5.5%.
TEST(JointSpring, TheEnergyTheStepperKeepsIsConstant) {
  const double m = 0.05, k = 600;
  RobotBuilder b;
  const int root = b.root("rail", MassProperties{});
  b.child(root, "slide", JointKind::kPrismatic, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitX(), "carriage",
          box_inertial(m, {0.02, 0.02, 0.02}));
  b.joint(0).spring_stiffness = k;
  SimulationOptions weightless;
  weightless.gravity = Eigen::Vector3d::Zero();
  auto sim = simulate(b.robot(), weightless, {{"slide", 0.05}});
  const auto energy = [&] {
    const SimulationHealth h = sim->health();
    return h.kinetic_energy + h.potential_energy;
  };
  const double E0 = energy();
  ASSERT_NEAR(E0, 0.5 * k * 0.05 * 0.05, 1e-15);
  double physical_low = E0, physical_high = E0;
  for (int n = 1; n <= 1000; ++n) {
    sim->step();
    ASSERT_NEAR(energy(), E0, 1e-12 * E0) << "step " << n;
    const JointState s = *sim->joint_state("slide");
    const double physical = 0.5 * m * s.velocity * s.velocity + 0.5 * k * s.position * s.position;
    physical_low = std::min(physical_low, physical);
    physical_high = std::max(physical_high, physical);
  }
  std::printf("spring: stepper's energy constant; physical energy within [%.4f, %.4f] of it\n", physical_low / E0,
              physical_high / E0);
  EXPECT_GT(physical_high - physical_low, 0.05 * E0);  // what the gate used to read as energy made
}

// A 20 g, 4 cm finger on a 0.2 N m/rad spring (omega = 136 rad/s at its pivot), under gravity, from
// 0.3 rad: a sound model the gate refused (SIM_ENERGY_RISE, 6.7% of its scale; s101gate D8).
TEST(JointSpring, AStiffSpringOnALightFingerPasses) {
  RobotBuilder b;
  const int root = b.root("palm", MassProperties{});
  b.child(root, "knuckle", JointKind::kRevolute, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitZ(), "finger",
          box_inertial(0.02, {0.01, 0.04, 0.01}, {0, -0.02, 0}));
  b.joint(0).limits = JointLimits{-1.5, 1.5, 0, 0};
  b.joint(0).spring_stiffness = 0.2;
  ValidationOptions options;
  options.start_offset_angular = 0.3;
  const ValidationReport report = validate_dynamics(b.robot(), options);
  std::printf("spring finger: %s\n", validation_summary_line(report).c_str());
  EXPECT_TRUE(report.passed) << all_text(report.diagnostics);
  EXPECT_TRUE(with_code(report.diagnostics, "SIM_ENERGY_RISE").empty());
  EXPECT_LT(report.energy_drift, 1e-3);
}

}  // namespace
}  // namespace rdtf
