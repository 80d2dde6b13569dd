// The live simulation's commands (docs/dynamics.md, "The live simulation"): torque, position and
// velocity modes against closed forms on a bar turning about a hinge without gravity, clamping to
// the effort limit, and the commands that are rejected.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "dynamics/dynamics_models.h"

namespace rdtf {
namespace {

using dynamics_test::box_inertial;
using dynamics_test::RobotBuilder;

// A 2 kg bar (0.05 x 0.5 x 0.05 m) turning about a hinge along Z through its centre (a propeller:
// the hinge then carries no load, so ODE's constraint handling adds no error to the closed forms),
// and a massless tool frame fixed at its end.
constexpr double kMass = 2.0, kLength = 0.5, kWidth = 0.05;
const double kInertiaAboutPivot = kMass * (kLength * kLength + kWidth * kWidth) / 12;

RobotBuilder bar_builder() {
  RobotBuilder b;
  const int root = b.root("frame", MassProperties{});
  const int bar = b.child(root, "pivot", JointKind::kRevolute, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitZ(),
                          "bar", box_inertial(kMass, {kWidth, kLength, kWidth}));
  b.child(bar, "mount", JointKind::kFixed, dynamics_test::translation(0, -kLength / 2, 0), Eigen::Vector3d::UnitX(),
          "tool", MassProperties{});
  return b;
}

std::unique_ptr<Simulation> weightless(const Robot& robot) {
  SimulationOptions options;
  options.gravity = Eigen::Vector3d::Zero();
  Diagnostics diag;
  auto sim = Simulation::create(robot, options, {}, diag);
  EXPECT_FALSE(diag.has_errors()) << dynamics_test::all_text(diag);
  if (!sim) throw std::runtime_error("not built");
  return sim;
}

// Constant torque tau: ODE's semi-implicit Euler gives w_n = tau h n / I exactly, and its finite
// rotation mode turns the bar by w_n h a step (ODE's default turns it by 2 atan(w_n h / 2), short by
// (w_n h)^3 / 12 a step), so q_N = tau h^2 N (N + 1) / 2I: checked to rounding.
TEST(DynamicsCommands, TorqueAcceleratesAsTauOverI) {
  auto sim = weightless(bar_builder().robot());
  const double tau = 0.3, h = 1e-3;
  const int N = 500;
  ASSERT_TRUE(sim->set_command({"pivot", CommandMode::kTorque, tau}));
  for (int n = 1; n <= N; ++n) sim->step(h);
  const JointState state = *sim->joint_state("pivot");
  const double expected_qdot = tau * h * N / kInertiaAboutPivot;
  const double expected_q = tau * h * h * N * (N + 1) / (2 * kInertiaAboutPivot);
  std::printf("torque: q %.12g (%.12g), qdot %.12g (%.12g)\n", state.position, expected_q, state.velocity,
              expected_qdot);
  EXPECT_NEAR(state.position, expected_q, 1e-9 * expected_q);
  EXPECT_NEAR(state.velocity, expected_qdot, 1e-9 * expected_qdot);
  EXPECT_EQ(state.effort, tau);
}

// A wheel spun up to 1000 rad/s (a continuous joint, torque tau for N steps, no damping): its
// position advances by exactly w h a step, as its velocity says. With ODE's default rotation update
// it advanced by 2 atan(w h / 2) / h = 927 rad/s at 1000 rad/s, a lag that grows without bound and
// that nothing reported (helper sweep s70sim D1).
TEST(DynamicsCommands, AFastWheelTurnsAsFastAsItsVelocitySays) {
  RobotBuilder b;
  const int root = b.root("frame", MassProperties{});
  b.child(root, "wheel", JointKind::kContinuous, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitY(), "disc",
          box_inertial(kMass, {kWidth, kLength, kWidth}));
  auto sim = weightless(b.robot());
  const double inertia = kMass * (kWidth * kWidth + kWidth * kWidth) / 12, h = 1e-3;
  const int N = 1000;
  const double tau = 1000 * inertia / (h * N);  // 1000 rad/s after N steps
  ASSERT_TRUE(sim->set_command({"wheel", CommandMode::kTorque, tau}));
  for (int n = 1; n <= N; ++n) sim->step(h);
  ASSERT_TRUE(sim->set_command({"wheel", CommandMode::kTorque, 0.0}));
  const double q0 = sim->joint_state("wheel")->position;
  EXPECT_NEAR(q0, tau * h * h * N * (N + 1) / (2 * inertia), 1e-9 * q0);
  for (int n = 1; n <= N; ++n) sim->step(h);
  const JointState state = *sim->joint_state("wheel");
  EXPECT_NEAR(state.velocity, 1000, 1e-9 * 1000);
  EXPECT_NEAR(state.position - q0, 1000 * h * N, 1e-9 * 1000 * h * N);
}

TEST(DynamicsCommands, EffortIsClampedToTheLimit) {
  RobotBuilder b = bar_builder();
  b.joint(0).limits = JointLimits{-3.0, 3.0, 0.1, 0};
  auto sim = weightless(b.robot());
  ASSERT_TRUE(sim->set_command({"pivot", CommandMode::kTorque, -5.0}));
  for (int n = 0; n < 100; ++n) sim->step();
  const JointState state = *sim->joint_state("pivot");
  EXPECT_EQ(state.effort, -0.1);
  EXPECT_NEAR(state.velocity, -0.1 * 0.1 / kInertiaAboutPivot, 1e-9 * 0.1 * 0.1 / kInertiaAboutPivot);
}

// Without an authored effort limit, any finite command is clamped to kDefaultEffortLimit, each
// term before the sum: a torque of 1e300, and a position command whose kp (1e308) times its error
// overflows to inf, both give the bound exactly, and the simulation goes on with a finite state.
TEST(DynamicsCommands, HugeFiniteCommandsAreClampedToTheDefaultBound) {
  for (const JointCommand& command : {JointCommand{"pivot", CommandMode::kTorque, 1e300},
                                      JointCommand{"pivot", CommandMode::kTorque, -1e300},
                                      JointCommand{"pivot", CommandMode::kPosition, 1e308, 1e308, 0.0, 1e308, 1e308},
                                      JointCommand{"pivot", CommandMode::kPosition, 0.0, -1e308, 0.0, 1e308, 0.0},
                                      JointCommand{"pivot", CommandMode::kVelocity, 0.0, 0.0, -1e308, 0.0, 1e308}}) {
    auto sim = weightless(bar_builder().robot());
    ASSERT_TRUE(sim->set_command(command));
    sim->step();
    const JointState state = *sim->joint_state("pivot");
    EXPECT_EQ(std::abs(state.effort), kDefaultEffortLimit) << state.effort;
    for (int n = 0; n < 100; ++n) sim->step();
    EXPECT_TRUE(sim->health().finite);
    EXPECT_NEAR(sim->time(), 101 * 1e-3, 1e-12);
    EXPECT_LE(std::abs(sim->joint_state("pivot")->effort), kDefaultEffortLimit);
  }
}

// Position mode on a joint that moves little inertia, with rdtf-pd-controller's default gains
// (kp 200, kd 10): the bar turning about its own length, I = m (w^2 + w^2) / 12 = 8.3e-4 kg m^2,
// so kd h / I = 12. Applied from the state before each step the law is unstable past kd h / I = 2
// (each step's velocity change overshoots its target), and arm3's shoulder, held so, swung by 2 rad
// within 10 ms. The motor row makes it implicit: with no other load ODE's step gives exactly
// w' = (I w + h kp (q* - q)) / (I + h (kp h + kd)), then turns the bar by w' h, and the state
// follows that recurrence to rounding, settling on the target without overshoot.
TEST(DynamicsCommands, PositionModeIsStableOnASmallInertiaWithStiffGains) {
  RobotBuilder b;
  const int root = b.root("frame", MassProperties{});
  b.child(root, "spin", JointKind::kRevolute, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitY(), "bar",
          box_inertial(kMass, {kWidth, kLength, kWidth}));
  auto sim = weightless(b.robot());
  const double inertia = kMass * (kWidth * kWidth + kWidth * kWidth) / 12, kp = 200, kd = 10, h = 1e-3;
  const double target = 0.7;
  ASSERT_TRUE(sim->set_command({"spin", CommandMode::kPosition, 0.0, target, 0.0, kp, kd}));
  double q = 0, w = 0, largest = 0;
  for (int n = 1; n <= 1000; ++n) {
    sim->step();
    w = (inertia * w + h * kp * (target - q)) / (inertia + h * (kp * h + kd));
    q += w * h;
    const JointState state = *sim->joint_state("spin");
    ASSERT_NEAR(state.position, q, 1e-9 * target) << "step " << n;
    ASSERT_NEAR(state.velocity, w, 1e-9 * target / h) << "step " << n;
    // The effort the motor applied is the law at the step's end: kp (q* - q) - (kp h + kd) w'.
    ASSERT_NEAR(state.effort, kp * (target - (q - w * h)) - (kp * h + kd) * w,
                1e-9 * kp * target) << "step " << n;
    largest = std::max(largest, state.position);
  }
  EXPECT_NEAR(q, target, 1e-6 * target);
  EXPECT_LE(largest, target);  // overdamped: never past the target
}

// Gains so soft that kp h + kd is below 1e-12 are applied as a torque from the state before the
// step (a motor of CFM 1 / (kp h + kd) would not be a number the solver can use): the first step's
// effort is kp (q* - q) exactly, and the state stays finite.
TEST(DynamicsCommands, TinyGainsAreAppliedAsATorque) {
  auto sim = weightless(bar_builder().robot());
  ASSERT_TRUE(sim->set_command({"pivot", CommandMode::kPosition, 0.0, 1e300, 0.0, 1e-320, 0.0}));
  sim->step();
  EXPECT_EQ(sim->joint_state("pivot")->effort, 1e-320 * 1e300);
  for (int n = 0; n < 100; ++n) sim->step();
  EXPECT_TRUE(sim->health().finite);
}

// Critically damped (kd = 2 sqrt(kp I)): the error decays as (1 + w t) exp(-w t), w = sqrt(kp / I)
// = 7.7 rad/s, below 1e-12 of the step after 5 s.
TEST(DynamicsCommands, PositionModeReachesTheTarget) {
  auto sim = weightless(bar_builder().robot());
  const double kp = 10.0, kd = 2 * std::sqrt(kp * kInertiaAboutPivot);
  ASSERT_TRUE(sim->set_command({"pivot", CommandMode::kPosition, 0.0, 0.7, 0.0, kp, kd}));
  while (sim->time() < 5.0) sim->step();
  const JointState state = *sim->joint_state("pivot");
  EXPECT_NEAR(state.position, 0.7, 1e-9);
  EXPECT_NEAR(state.velocity, 0.0, 1e-9);
  // The tool rides on the bar: L/2 from the pivot along the bar's -Y turned by 0.7 rad.
  const Eigen::Vector3d tool = sim->link_pose("tool")->X_SL.translation();
  EXPECT_NEAR(tool.x(), kLength / 2 * std::sin(0.7), 1e-9);
  EXPECT_NEAR(tool.y(), -kLength / 2 * std::cos(0.7), 1e-9);
}

TEST(DynamicsCommands, VelocityModeReachesTheSpeed) {
  auto sim = weightless(bar_builder().robot());
  ASSERT_TRUE(sim->set_command({"pivot", CommandMode::kVelocity, 0.0, 0.0, 1.5, 0.0, 2.0}));
  while (sim->time() < 3.0) sim->step();  // time constant I / kd = 0.021 s
  EXPECT_NEAR(sim->joint_state("pivot")->velocity, 1.5, 1e-9);
  sim->clear_command("pivot");
  sim->step();
  EXPECT_EQ(sim->joint_state("pivot")->effort, 0.0);
  EXPECT_NEAR(sim->joint_state("pivot")->velocity, 1.5, 1e-9);  // no torque, no gravity: it coasts
}

TEST(DynamicsCommands, BadCommandsAreRejectedAndChangeNothing) {
  auto sim = weightless(bar_builder().robot());
  ASSERT_TRUE(sim->set_command({"pivot", CommandMode::kTorque, 0.2}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const struct {
    JointCommand command;
    const char* reason;
  } rejected[] = {
      {{"wrist", CommandMode::kTorque, 1.0}, "command for 'wrist' rejected: no such joint"},
      {{"mount", CommandMode::kTorque, 1.0}, "command for 'mount' rejected: a fixed joint takes no command"},
      {{"pivot", CommandMode::kPosition, 0.0, nan, 0.0, 1.0, 0.0}, "command for 'pivot' rejected: values must be finite"},
      {{"pivot", CommandMode::kPosition, 0.0, 1.0, 0.0, -1.0, 0.0},
       "command for 'pivot' rejected: gains must not be negative"},
      {{"pivot", CommandMode::kVelocity, 0.0, 0.0, 1.0, 0.0, -2.0},
       "command for 'pivot' rejected: gains must not be negative"},
  };
  for (const auto& [command, reason] : rejected) {
    std::string error;
    EXPECT_FALSE(sim->set_command(command, &error));
    EXPECT_EQ(error, reason);
  }
  sim->step();
  EXPECT_EQ(sim->joint_state("pivot")->effort, 0.2);  // the last accepted command still acts
  EXPECT_FALSE(sim->joint_state("mount").has_value());
}

// A state that blew up stops the simulation instead of letting ODE abort the process on it.
TEST(DynamicsCommands, ABlownUpSimulationStops) {
  // An authored effort limit of 1e120 (no stops: the limits are wider than a turn) lets the
  // command through unclamped: 1e120 N m, after one step the bar turns at 6e117 rad/s, beyond
  // what may be stepped (1e100).
  RobotBuilder b = bar_builder();
  b.joint(0).limits = JointLimits{-1e9, 1e9, 1e120, 0};
  auto sim = weightless(b.robot());
  ASSERT_TRUE(sim->set_command({"pivot", CommandMode::kTorque, 1e120}));
  EXPECT_TRUE(sim->steppable());
  // After one step the state is finite but beyond the bound: not steppable, so never published.
  sim->step();
  EXPECT_FALSE(sim->steppable());
  const auto exploded = sim->joint_state("pivot");
  ASSERT_TRUE(exploded.has_value());
  EXPECT_GT(std::abs(exploded->velocity), 1e100);
  for (int n = 0; n < 19; ++n) sim->step();
  EXPECT_FALSE(sim->steppable());
  EXPECT_FALSE(sim->health().finite);
  ASSERT_FALSE(sim->ode_messages().empty());
  EXPECT_NE(sim->ode_messages().back().find("the simulation stopped"), std::string::npos) << sim->ode_messages().back();
  const std::uint64_t steps = sim->steps();
  sim->step();
  EXPECT_EQ(sim->steps(), steps);
}

}  // namespace
}  // namespace rdtf
