// The ODE model against closed forms: a compound pendulum's period, a free fall, a prismatic spring
// under gravity, damping that only dissipates, and a Z-up model that moves as the Y-up one.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "dynamics/dynamics_models.h"

namespace rdtf {
namespace {

using dynamics_test::box_inertial;
using dynamics_test::RobotBuilder;
using dynamics_test::simulate;
using dynamics_test::translation;

constexpr double kG = kStandardGravity;

// A bar (edges w, L, w; mass m) hanging along -Y from a hinge about Z at the origin of its link
// frame; the root is massless, so the hinge holds it to the world.
struct CompoundPendulum {
  double m = 2.0, L = 0.5, w = 0.05;
  double d() const { return L / 2; }
  double I_pivot() const { return m * (L * L + w * w) / 12 + m * d() * d(); }
  Robot robot(const Eigen::Isometry3d& X_SR = Eigen::Isometry3d::Identity()) const {
    RobotBuilder b;
    const int root = b.root("frame", MassProperties{}, X_SR);
    b.child(root, "pivot", JointKind::kRevolute, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitZ(), "bar",
            box_inertial(m, {w, L, w}, {0, -d(), 0}));
    return b.robot();
  }
};

// Upward zero crossings of q(t), linearly interpolated between steps.
std::vector<double> upward_crossings(Simulation& sim, double duration) {
  std::vector<double> crossings;
  double t0 = sim.time();
  double q0 = sim.joint_state("pivot")->position;
  while (sim.time() < duration) {
    sim.step();
    const double t1 = sim.time();
    const double q1 = sim.joint_state("pivot")->position;
    if (q0 < 0 && q1 >= 0) crossings.push_back(t0 + (t1 - t0) * (-q0) / (q1 - q0));
    t0 = t1;
    q0 = q1;
  }
  return crossings;
}

// T = 2 pi sqrt(I_pivot / (m g d)) (1 + theta0^2/16 + 11 theta0^4/3072 + ...). With theta0 = 0.01
// the amplitude terms are 6.25e-6 and 3.6e-11 (the next one, O(theta0^6), is below 1e-12).
// Error budget of the measurement (period about 1.16 s, omega = 5.4 rad/s, h = 1 ms):
// - ODE's semi-implicit Euler shortens a harmonic oscillator's period by (omega h)^2 / 24 =
//   1.2e-6 (relative), the only error of order h^2;
// - linear interpolation at a zero crossing, where q'' = 0, errs by O(h^3): below 1e-9 s;
// - the hinge's constraint error (ERP 0.2, CFM 1e-10) acts at the pivot, which the bar turns about.
// So 1e-5 bounds the relative error with margin, and 6 periods average the crossings.
TEST(Pendulum, CompoundPendulumPeriodMatchesClosedForm) {
  const CompoundPendulum p;
  const double theta0 = 0.01;
  const double T0 = 2 * std::numbers::pi * std::sqrt(p.I_pivot() / (p.m * kG * p.d()));
  const double T = T0 * (1 + theta0 * theta0 / 16 + 11 * std::pow(theta0, 4) / 3072);
  auto sim = simulate(p.robot(), {}, {{"pivot", theta0}});
  ASSERT_EQ(sim->stepper_name(), "dWorldStep");
  const std::vector<double> crossings = upward_crossings(*sim, 6.5 * T);
  ASSERT_GE(crossings.size(), 6u);
  const double measured = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  const double relative_error = std::abs(measured - T) / T;
  RecordProperty("period_relative_error", std::to_string(relative_error));
  std::printf("compound pendulum: T = %.9f s, ODE %.9f s, relative error %.3g\n", T, measured, relative_error);
  EXPECT_LT(relative_error, 1e-5);
  // The amplitude stays (no hidden damping): within 0.1% after 6 periods.
  EXPECT_NEAR(sim->health().kinetic_energy + sim->health().potential_energy,
              -p.m * kG * p.d() * std::cos(theta0), 1e-3 * p.m * kG * p.d() * (1 - std::cos(theta0)));
}

// The same bar on a ball joint, its rest pose tilted by theta0 about Z (a ball joint has no position
// to set): it swings in the XY plane with the hinge's period (same error budget as above).
TEST(Pendulum, BallJointSwingsWithTheSamePeriod) {
  const CompoundPendulum p;
  const double theta0 = 0.01;
  const double T = 2 * std::numbers::pi * std::sqrt(p.I_pivot() / (p.m * kG * p.d())) *
                   (1 + theta0 * theta0 / 16 + 11 * std::pow(theta0, 4) / 3072);
  RobotBuilder b;
  const int root = b.root("frame", MassProperties{});
  const Eigen::Isometry3d tilted(Eigen::AngleAxisd(theta0, Eigen::Vector3d::UnitZ()));
  b.child(root, "socket", JointKind::kBall, tilted, Eigen::Vector3d::UnitX(), "bar",
          box_inertial(p.m, {p.w, p.L, p.w}, {0, -p.d(), 0}));
  auto sim = simulate(b.robot(), {});
  // The bar's angle from the downward vertical, from its -Y axis in the scene.
  const auto angle = [&] {
    const Eigen::Vector3d down = sim->link_pose("bar")->X_SL.linear() * -Eigen::Vector3d::UnitY();
    return std::atan2(down.x(), -down.y());
  };
  EXPECT_NEAR(angle(), theta0, 1e-15);
  std::vector<double> crossings;
  double t0 = 0, a0 = angle();
  while (sim->time() < 6.5 * T) {
    sim->step();
    const double a1 = angle();
    if (a0 < 0 && a1 >= 0) crossings.push_back(t0 + (sim->time() - t0) * (-a0) / (a1 - a0));
    t0 = sim->time();
    a0 = a1;
    ASSERT_NEAR(sim->link_pose("bar")->X_SL.translation().z(), 0.0, 1e-12);  // stays in its plane
  }
  ASSERT_GE(crossings.size(), 6u);
  const double measured = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  std::printf("ball joint pendulum: relative period error %.3g\n", std::abs(measured - T) / T);
  EXPECT_LT(std::abs(measured - T) / T, 1e-5);
}

// A box on a floating joint below a base held by the world falls freely (exactly as ODE's
// semi-implicit Euler gives it, see below); the base does not move.
TEST(DynamicsClosedForm, FloatingJointChildFallsFreely) {
  RobotBuilder b;
  const int base = b.root("base", box_inertial(5.0, {0.2, 0.2, 0.2}));
  b.child(base, "free", JointKind::kFloating, translation(0, -0.5, 0), Eigen::Vector3d::UnitX(), "payload",
          box_inertial(1.0, {0.1, 0.1, 0.1}));
  auto sim = simulate(b.robot(), {});
  const double h = 1e-3;
  for (int n = 1; n <= 500; ++n) sim->step(h);
  EXPECT_NEAR(sim->link_pose("payload")->X_SL.translation().y(), -0.5 - kG * h * h * 500 * 501 / 2, 1e-12);
  EXPECT_LT(sim->link_pose("base")->X_SL.translation().norm(), 1e-9);  // held by the world
  EXPECT_TRUE(sim->joint_states().empty());  // no one-degree-of-freedom joint
}

// A floating box (centre of mass 0.1 m off its link origin) falls from rest. ODE's semi-implicit
// Euler gives exactly y_n = y0 - g h^2 n (n + 1) / 2 = y0 - g t^2 / 2 - g h t / 2 and a total energy
// that falls by m g^2 h t / 2: both checked to rounding, and against the continuous y0 - g t^2 / 2.
TEST(DynamicsClosedForm, FreeFallFollowsGravityAndKeepsEnergy) {
  RobotBuilder b;
  const double m = 3.0, y0 = 2.0, h = 1e-3;
  b.root("box", box_inertial(m, {0.2, 0.3, 0.4}, {0.1, 0, 0}), translation(0, y0, 0));
  SimulationOptions options;
  options.floating_root = true;
  auto sim = simulate(b.robot(), options);
  const double E0 = sim->health().kinetic_energy + sim->health().potential_energy;
  double worst_energy_error = 0;
  for (int n = 1; n <= 1000; ++n) {
    sim->step(h);
    const double t = n * h;
    const LinkPose pose = *sim->link_pose("box");
    const double y_discrete = y0 - kG * h * h * n * (n + 1) / 2;
    ASSERT_NEAR(pose.X_SL.translation().y(), y_discrete, 1e-12) << n;
    ASSERT_NEAR(pose.X_SL.translation().x(), 0.0, 1e-15);
    ASSERT_NEAR(pose.v_SLo_S.y(), -kG * t, 1e-12);
    EXPECT_LE(std::abs(pose.X_SL.translation().y() - (y0 - kG * t * t / 2)), kG * h * t / 2 + 1e-12);
    const SimulationHealth health = sim->health();
    const double E = health.kinetic_energy + health.potential_energy;
    worst_energy_error = std::max(worst_energy_error, std::abs(E - (E0 - m * kG * kG * h * t / 2)));
  }
  EXPECT_LT(worst_energy_error, 1e-9 * m * kG * y0);
  const SimulationHealth end = sim->health();
  const double drift = (end.kinetic_energy + end.potential_energy - E0) / end.kinetic_energy;
  std::printf("free fall: after 1 s the total energy changed by %.6g of the kinetic energy\n", drift);
  EXPECT_NEAR(drift, -h / 1.0, 1e-9);  // m g^2 h t / 2 over m g^2 t^2 / 2
  EXPECT_TRUE(sim->link_pose("box")->X_SL.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-15));

  // The gate on the same model: it passes with its energy drift within the tolerance.
  ValidationOptions validation;
  validation.simulation.floating_root = true;
  const ValidationReport report = validate_dynamics(b.robot(), validation);
  EXPECT_TRUE(report.passed) << dynamics_test::all_text(report.diagnostics);
  EXPECT_LE(report.energy_drift, validation.energy_tolerance);
  EXPECT_LT(report.final_energy_drift, 0);
}

// A carriage of mass m on a prismatic joint with a spring k, damped critically (c = 2 sqrt(k m)),
// under gravity along the joint: it settles at q = -m g / k. The joint frame is turned 90 degrees
// about Z, so its axis +X is the parent's +Y: the axis must be taken in the joint frame.
TEST(DynamicsClosedForm, PrismaticSpringSettlesAtItsEquilibrium) {
  const double m = 1.0, k = 100.0;
  RobotBuilder b;
  const int root = b.root("rail", MassProperties{});
  Eigen::Isometry3d X_PJ(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()));
  X_PJ.translation() = Eigen::Vector3d(0, 1, 0);
  b.child(root, "slide", JointKind::kPrismatic, X_PJ, Eigen::Vector3d::UnitX(), "carriage",
          box_inertial(m, {0.1, 0.1, 0.1}));
  b.joint(0).spring_stiffness = k;
  b.joint(0).damping = 2 * std::sqrt(k * m);
  auto sim = simulate(b.robot(), {});
  // Slowest mode: (1 + omega t) exp(-omega t), omega = 10 rad/s: below 1e-15 after 4 s.
  while (sim->time() < 4.0) sim->step();
  const double expected = -m * kG / k;
  const JointState state = *sim->joint_state("slide");
  std::printf("prismatic spring: q = %.12f m, closed form %.12f m\n", state.position, expected);
  EXPECT_NEAR(state.position, expected, 1e-9 * std::abs(expected));
  EXPECT_NEAR(state.velocity, 0.0, 1e-9);
  const Eigen::Vector3d p = sim->link_pose("carriage")->X_SL.translation();
  EXPECT_NEAR(p.y(), 1 + expected, 1e-9);
  EXPECT_NEAR(p.x(), 0.0, 1e-9);
  EXPECT_NEAR(p.z(), 0.0, 1e-9);
}

// The arm with damped joints, let go from a bent pose: its mechanical energy only goes down (sampled
// every 10 ms, each sample at most 1e-6 of the drop so far above the last: ODE's constraint
// correction moves energy by far less than the damping takes), and the energy balance closes.
TEST(DynamicsClosedForm, DampingDissipates) {
  RobotBuilder b = dynamics_test::arm_builder();
  b.joint(0).damping = 0.5;
  b.joint(1).damping = 0.2;
  auto sim = simulate(b.robot(), {}, {{"shoulder", 1.2}, {"elbow", -0.8}});
  const auto energy = [&] {
    const SimulationHealth h = sim->health();
    return h.kinetic_energy + h.potential_energy;
  };
  const double E0 = energy();
  double last = E0;
  double last_dissipated = 0;
  for (int sample = 1; sample <= 300; ++sample) {
    for (int i = 0; i < 10; ++i) sim->step();
    const double E = energy();
    const double dissipated = sim->health().dissipated_energy;
    ASSERT_LE(E, last + 1e-6 * (E0 - E)) << "t = " << sim->time();
    ASSERT_GE(dissipated, last_dissipated);
    last = E;
    last_dissipated = dissipated;
  }
  // It lost most of what it can lose: the energy of the arm hanging at rest is the least.
  const double E_rest = simulate(b.robot(), {})->health().potential_energy;
  std::printf("damped arm: E0 - E_rest = %.6g J, left after 3 s: %.6g J\n", E0 - E_rest, last - E_rest);
  EXPECT_LT(last - E_rest, 0.5 * (E0 - E_rest));
  // Work of the damping accounts for the loss within 1% of it.
  EXPECT_NEAR(E0 - last, last_dissipated, 0.01 * (E0 - last));
}

// The same arm built Z up (every frame turned +90 degrees about X, which takes +Y to +Z) with gravity
// {0, 0, -g}: the same joint trajectory, and link poses that are the Y-up ones turned.
TEST(DynamicsClosedForm, ZUpModelWithZGravityMovesAsTheYUpOne) {
  const Eigen::Isometry3d R(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  RobotBuilder y_up = dynamics_test::arm_builder();
  RobotBuilder z_up;
  {
    const Robot& r = y_up.robot();
    const int base = z_up.root("base", r.links[0].inertial, R * r.links[0].X_SL);
    const int upper = z_up.child(base, "shoulder", JointKind::kRevolute, r.joints[0].X_PJ, r.joints[0].axis,
                                 "upper_arm", r.links[1].inertial);
    z_up.joint(0).limits = r.joints[0].limits;
    z_up.child(upper, "elbow", JointKind::kContinuous, r.joints[1].X_PJ, r.joints[1].axis, "forearm",
               r.links[2].inertial);
  }
  SimulationOptions z_gravity;
  z_gravity.gravity = {0, 0, -kG};
  const std::map<std::string, double> start{{"shoulder", 0.9}, {"elbow", 0.4}};
  auto a = simulate(y_up.robot(), {}, start);
  auto b = simulate(z_up.robot(), z_gravity, start);
  double worst_q = 0, worst_p = 0;
  for (int n = 0; n < 2000; ++n) {
    a->step();
    b->step();
    for (const char* joint : {"shoulder", "elbow"}) {
      worst_q = std::max(worst_q, std::abs(a->joint_state(joint)->position - b->joint_state(joint)->position));
    }
    const auto pa = a->link_poses(), pb = b->link_poses();
    for (std::size_t l = 0; l < pa.size(); ++l) {
      worst_p = std::max(worst_p, ((R * pa[l].X_SL).translation() - pb[l].X_SL.translation()).norm());
    }
  }
  std::printf("Z up vs Y up over 2 s: joint positions within %.3g rad, link origins within %.3g m\n", worst_q, worst_p);
  EXPECT_LT(worst_q, 1e-9);
  EXPECT_LT(worst_p, 1e-9);
  EXPECT_GT(std::abs(a->joint_state("shoulder")->position - 0.9), 0.1);  // it did swing
  // With Y-up gravity the Z-up model's hinges (their axes now along -Y) feel no torque: it stays.
  auto wrong = simulate(z_up.robot(), {}, start);
  for (int n = 0; n < 500; ++n) wrong->step();
  EXPECT_NEAR(wrong->joint_state("shoulder")->position, 0.9, 1e-9);
}

}  // namespace
}  // namespace rdtf
