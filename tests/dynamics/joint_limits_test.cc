// Hinge limits of any range are enforced (docs/dynamics.md, "Joints"): inside (-pi, pi), within
// 1e-5 rad of +-pi, narrower than pi with a stop near it, exactly +-pi, beyond pi on one side (Franka's joint 6), wider than 2 pi (UR's +-2 pi). A bar driven by a
// constant torque against each stop stays within the documented bound of it and comes to rest on
// it; a joint swinging freely inside a wide range is not judged as violating it.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "dynamics/dynamics_models.h"

namespace rdtf {
namespace {

using dynamics_test::all_text;
using dynamics_test::box_inertial;
using dynamics_test::RobotBuilder;
using dynamics_test::with_code;

constexpr double kPi = std::numbers::pi;

// A 1 kg bar, 0.5 m long, hanging from a hinge about Z on a massless frame the world holds; with
// `turned`, the frame (and so the bar and its hinge) is turned in the scene, so that no body axis
// is a world axis (ODE's own hinge offset got such a body wrong).
Robot bar(double lower, double upper, bool turned = false) {
  RobotBuilder b;
  const Eigen::Isometry3d X_SF(Eigen::AngleAxisd(turned ? 0.9 : 0.0, Eigen::Vector3d(1, 2, 3).normalized()));
  const int root = b.root("frame", MassProperties{}, X_SF);
  b.child(root, "pivot", JointKind::kRevolute, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitZ(), "bar",
          box_inertial(1.0, {0.05, 0.5, 0.05}, {0, -0.25, 0}));
  b.joint(0).limits = JointLimits{lower, upper, 0, 0};
  return b.robot();
}

struct Range {
  const char* what;
  double lower, upper;
};

const Range kRanges[] = {
    {"inside (-pi, pi)", -1.0, 1.2},
    {"exactly +-pi", -kPi, kPi},
    {"beyond pi on one side", -0.0175, 3.7525},
    {"wider than 2 pi", -2 * kPi, 2 * kPi},
    {"wider than 2 pi, off centre", -1.0, 7.5},
    // Within a step's travel of pi, as published URDFs write it (SO-100's wrist): the wrapped angle
    // stepped over ODE's own stops (helper sweep s70rob D1).
    {"just inside +-pi", -3.14159, 3.14159},
    {"just inside pi on one side", -0.5, 3.1415},
    // Narrower than pi, a stop 1.6 mrad inside +-pi (pi written 3.14): overrun into the wrap, the
    // hinge's own stop read the angle beyond the other stop and drove the joint on (s101gate D2).
    {"narrower than pi, -3.14", -3.14, 0.0},
    {"narrower than pi, 3.14", 0.0, 3.14},
};

// 20 N m (eight times the bar's largest gravity torque, 2.45 N m) from rest towards one stop,
// for 2 s: the bar turns up to 2 pi and more before it hits the stop at tens of rad/s.
TEST(JointLimits, DrivenAgainstEachStopTheJointStaysWithinTheBound) {
  for (const bool turned : {false, true}) {
  for (const Range& range : kRanges) {
    for (const double sign : {-1.0, 1.0}) {
      SCOPED_TRACE(std::string(range.what) + (sign > 0 ? ", upper stop" : ", lower stop") + (turned ? ", turned" : ""));
      Diagnostics diag;
      auto sim = Simulation::create(bar(range.lower, range.upper, turned), {}, {}, diag);
      ASSERT_TRUE(sim) << all_text(diag);
      EXPECT_FALSE(diag.contains("ODE_LIMIT_NOT_ENFORCED")) << all_text(diag);
      JointCommand command;
      command.joint = "pivot";
      command.effort = 20 * sign;
      ASSERT_TRUE(sim->set_command(command));
      const double stop = sign > 0 ? range.upper : range.lower;
      double worst = 0, largest_speed = 0;
      for (int step = 0; step < 2000; ++step) {
        sim->step();
        const SimulationHealth health = sim->health();
        ASSERT_TRUE(health.finite);
        // The bound: 0.01 rad + the travel past the stop (ERP-decayed) + its load over its stiffness.
        ASSERT_LE(health.worst_limit_ratio, 1.0)
            << "step " << step << ": " << health.worst_limit_violation << " rad past, bound " << health.limit_bound;
        worst = std::max(worst, health.worst_limit_violation);
        largest_speed = std::max(largest_speed, std::abs(sim->joint_state("pivot")->velocity));
      }
      const JointState end = *sim->joint_state("pivot");
      // It came to rest on the stop it was driven against (within a few microradians: the stop's
      // load over its stiffness is 20 / 2e12 rad, the rest is the ERP's decay of the last bounce).
      EXPECT_NEAR(end.position, stop, 1e-4) << "worst " << worst << " rad, speed up to " << largest_speed;
      EXPECT_NEAR(end.velocity, 0.0, 1e-2);
      std::printf("%-28s %s stop %+.4f%s: rests at %+.6f, worst %.4g rad past, up to %.3g rad/s\n", range.what,
                  sign > 0 ? "upper" : "lower", stop, turned ? " (turned)" : "", end.position, worst, largest_speed);
    }
  }
  }
}

// Let go inside a wide range, the bar swings freely through the bottom and back for 3 s without
// reaching a stop: the gate passes it and sees no limit violated. From 2.5 rad it swings to about
// -2.5 rad; from 5.2 rad (-1.08 rad past the bottom at 2 pi) to about 7.36 rad.
TEST(JointLimits, FreeSwingInsideAWideRangeIsNotAViolation) {
  const std::pair<Range, double> cases[] = {{kRanges[1], 2.5}, {kRanges[3], 2.5}, {kRanges[4], 5.2}};
  for (const auto& [range, start] : cases) {
    SCOPED_TRACE(range.what);
    ValidationOptions options;
    options.initial_positions = {{"pivot", start}};
    const ValidationReport report = validate_dynamics(bar(range.lower, range.upper), options);
    EXPECT_TRUE(report.passed) << all_text(report.diagnostics);
    for (const Diagnostic& d : report.diagnostics.all()) {
      EXPECT_EQ(d.severity, Severity::kInfo) << format(d);  // the massless frame the world holds
    }
    EXPECT_EQ(report.worst_limit_violation, 0.0);
  }
}

// Franka's joint 6 under gravity from near its upper end: it swings down through 0 onto its lower
// stop at -0.0175 rad, at about 9 rad/s, and the gate passes it (ODE used to leave this range
// unenforced and the gate then failed the robot).
TEST(JointLimits, FrankaJointSixRangeHoldsAtItsLowerStop) {
  ValidationOptions options;
  options.initial_positions = {{"pivot", 3.0}};
  const ValidationReport report = validate_dynamics(bar(-0.0175, 3.7525), options);
  EXPECT_TRUE(report.passed) << all_text(report.diagnostics);
  EXPECT_GT(report.worst_limit_violation, 0.0);  // it did hit the stop
  std::printf("franka joint 6: %s (worst %g rad past)\n", validation_summary_line(report).c_str(),
              report.worst_limit_violation);
}

// A prismatic slide resting on its lower stop under gravity: its load is its weight, and it rests
// its weight over the stop's stiffness (ERP / (h CFM) = 2e12 N/m) past it, within the bound.
TEST(JointLimits, SlideRestingOnItsStopUnderGravity) {
  RobotBuilder b;
  const int root = b.root("column", MassProperties{});
  b.child(root, "lift", JointKind::kPrismatic, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitY(), "carriage",
          box_inertial(50.0, {0.2, 0.2, 0.2}));
  b.joint(0).limits = JointLimits{0.0, 0.5, 0, 0};
  Diagnostics diag;
  auto sim = Simulation::create(b.robot(), {}, {}, diag);
  ASSERT_TRUE(sim);
  for (int step = 0; step < 1000; ++step) sim->step();
  const SimulationHealth health = sim->health();
  const double k = 0.2 / (1e-3 * 1e-10);
  EXPECT_NEAR(health.worst_limit_violation, 50 * kStandardGravity / k, 1e-6 * 50 * kStandardGravity / k);
  EXPECT_LE(health.worst_limit_ratio, 1.0);
  EXPECT_NEAR(health.limit_bound, 1e-3 + 50 * kStandardGravity / k, 1e-15);
}

// The report names the joint furthest past its limit relative to its bound, as SIM_LIMIT_VIOLATED
// does, not the largest number: a hinge's violation in rad and a slide's in m do not compare. The
// bar of Franka's joint 6 swings onto its stop (mrad past it) beside a slide that rests its weight
// on its stop (a fraction of a nanometre past it) under a linear tolerance of 0.1 nm: the slide is
// the further past relative to its bound. The two hang from a frame the world holds, so each is
// an island of its own and moves as it does alone.
TEST(JointLimits, TheReportNamesTheJointFurthestPastRelativeToItsBound) {
  auto add_bar = [](RobotBuilder& b, int root) {
    b.child(root, "pivot", JointKind::kRevolute, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitZ(), "bar",
            box_inertial(1.0, {0.05, 0.5, 0.05}, {0, -0.25, 0}));
    b.joint(b.robot().joints.size() - 1).limits = JointLimits{-0.0175, 3.7525, 0, 0};
  };
  auto add_slide = [](RobotBuilder& b, int root) {
    b.child(root, "lift", JointKind::kPrismatic, Eigen::Isometry3d(Eigen::Translation3d(2, 0, 0)),
            Eigen::Vector3d::UnitY(), "carriage", box_inertial(50.0, {0.2, 0.2, 0.2}));
    b.joint(b.robot().joints.size() - 1).limits = JointLimits{0.0, 0.5, 0, 0};
  };
  ValidationOptions options;
  options.initial_positions = {{"pivot", 3.0}};
  options.limit_tolerance_linear = 1e-10;
  auto validate = [&](bool bar, bool slide) {
    RobotBuilder b;
    const int root = b.root("frame", MassProperties{});
    if (bar) add_bar(b, root);
    if (slide) add_slide(b, root);
    return validate_dynamics(b.robot(), options);
  };
  const ValidationReport bar_alone = validate(true, false);
  const ValidationReport slide_alone = validate(false, true);
  const ValidationReport both = validate(true, true);
  std::printf("bar: %.6g rad past (ratio %.4g); slide: %.6g m past (ratio %.4g); both: %s %.6g (ratio %.4g)\n",
              bar_alone.worst_limit_violation, bar_alone.worst_limit_ratio, slide_alone.worst_limit_violation,
              slide_alone.worst_limit_ratio, both.worst_limit_joint.c_str(), both.worst_limit_violation,
              both.worst_limit_ratio);
  // What makes the case: the bar's number is the larger, the slide's ratio is.
  ASSERT_EQ(bar_alone.worst_limit_joint, "pivot");
  ASSERT_EQ(slide_alone.worst_limit_joint, "lift");
  ASSERT_GT(bar_alone.worst_limit_violation, 1e6 * slide_alone.worst_limit_violation);
  ASSERT_GT(slide_alone.worst_limit_ratio, bar_alone.worst_limit_ratio);
  EXPECT_EQ(both.worst_limit_joint, "lift");
  EXPECT_EQ(both.worst_limit_violation, slide_alone.worst_limit_violation);
  EXPECT_EQ(both.worst_limit_ratio, slide_alone.worst_limit_ratio);
  EXPECT_EQ(both.passed, slide_alone.passed && bar_alone.passed) << all_text(both.diagnostics);
}

// Effort and speed limits without lower and upper (a wheel's URDF <limit effort velocity/>, an
// rdtf_effort hint alone) bound no motion: the joint turns freely, on a revolute joint as on a
// continuous one. (They were read as the range [0, 0], which locked the joint.) A 1 kg bar 0.5 m
// long turning about the vertical through one end, where gravity has no torque, under 1 N m for
// 1 s: it moves exactly as the same joint with no limits at all does, bit for bit, and about as
// far as tau t^2 / (2 I) says (ODE's first-order step overshoots by (n + 1) / n, 0.1 % in 1000
// steps, less what its hinge's projection takes off); the same joint with the range [0, 0] given stays put.
JointState spin_after_one_second(JointKind kind, const std::optional<JointLimits>& limits) {
  RobotBuilder b;
  const int root = b.root("frame", MassProperties{});
  b.child(root, "spin", kind, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitY(), "bar",
          box_inertial(1.0, {0.5, 0.05, 0.05}, {0.25, 0, 0}));
  b.joint(0).limits = limits;
  Diagnostics diag;
  auto sim = Simulation::create(b.robot(), {}, {}, diag);
  if (!sim) throw std::runtime_error(all_text(diag));
  JointCommand command;
  command.joint = "spin";
  command.effort = 1.0;
  if (!sim->set_command(command)) throw std::runtime_error("command refused");
  for (int step = 0; step < 1000; ++step) sim->step();
  return *sim->joint_state("spin");
}

TEST(JointLimits, EffortAndSpeedLimitsAloneLeaveTheJointFree) {
  JointLimits effort_only;
  effort_only.effort = 20;
  effort_only.velocity = 100;
  effort_only.position = false;
  const JointState free = spin_after_one_second(JointKind::kRevolute, std::nullopt);
  const double I = (0.5 * 0.5 + 0.05 * 0.05) / 12 + 0.25 * 0.25;  // About the hinge, kg m^2.
  const double angle = 1.0 * 1.0 / (2 * I);                          // tau t^2 / (2 I), rad
  EXPECT_NEAR(free.position, angle, 2e-3 * angle);
  for (const JointKind kind : {JointKind::kRevolute, JointKind::kContinuous}) {
    SCOPED_TRACE(to_string(kind));
    const JointState state = spin_after_one_second(kind, effort_only);
    EXPECT_EQ(state.position, free.position);
    EXPECT_EQ(state.velocity, free.velocity);
  }
  const JointState locked = spin_after_one_second(JointKind::kRevolute, JointLimits{0, 0, 20, 100});
  EXPECT_LT(std::abs(locked.position), 0.01);
  std::printf("turned %.6f rad free and with effort limits alone (tau t^2 / 2I: %.6f), %.3g rad with [0, 0]\n",
              free.position, angle, locked.position);
}

}  // namespace
}  // namespace rdtf
