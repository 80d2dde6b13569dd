// A prismatic joint whose parent turns: its rate, its damping and its commanded effort are those of
// the joint, not of ODE's centres of mass (s90ctrl D1-D3); and a joint's velocity limit bounds the
// speed a command drives it at (D5).
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

// A 1 kg arm hanging along -Y from a hinge about Z at the origin, and at its end (1 m down) a
// 0.5 kg carriage on a rail along the arm's X, across the arm: the carriage's centre (its link
// origin) is 0.5 m from the arm's, across the rail, so the arm's turning moves one relative to the
// other along the rail without the carriage sliding.
RobotBuilder arm_with_rail(double rail_damping) {
  RobotBuilder b;
  const int base = b.root("base", MassProperties{});
  const int arm = b.child(base, "hinge", JointKind::kContinuous, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitZ(),
                          "arm", box_inertial(1.0, {0.05, 1.0, 0.05}, {0, -0.5, 0}));
  b.child(arm, "rail", JointKind::kPrismatic, translation(0, -1, 0), Eigen::Vector3d::UnitX(), "carriage",
          box_inertial(0.5, {0.1, 0.1, 0.1}));
  // No stops: a stop's correction moves energy (ODE's ERP), which the dissipation check would see.
  b.joint(1).limits = JointLimits{0, 0, 0, 0, false};
  b.joint(1).damping = rail_damping;
  return b;
}

// The rail's rate computed from the link states alone: the carriage's origin moving along the rail
// (the carriage's own X) relative to the point of the arm it passes. The carriage's centre is its
// link origin and the rail turns with the carriage, as ODE's slider axis does, so this is the
// rate the simulation must report, to rounding.
double rail_rate_from_links(const Simulation& sim) {
  const LinkPose arm = *sim.link_pose("arm");
  const LinkPose carriage = *sim.link_pose("carriage");
  const Eigen::Vector3d axis_S = carriage.X_SL.linear() * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d lever = carriage.X_SL.translation() - arm.X_SL.translation();
  return axis_S.dot(carriage.v_SLo_S - arm.v_SLo_S - arm.w_SL_S.cross(lever));
}

// Let go from 1 rad: the reported rate is the rate of the rail (it was off by the arm's turn times
// the 0.5 m between the centres, and of the wrong sign at times), and the rail's damping only
// takes energy out (on the wrong rate it pushed the carriage on: it went 31% further than in
// MuJoCo). Energy sampled every 10 ms as in DynamicsClosedForm.DampingDissipates.
TEST(DynamicsSlider, OnATurningArmItsRateIsTheRailsAndItsDampingDissipates) {
  RobotBuilder b = arm_with_rail(0.5);
  auto sim = simulate(b.robot(), {}, {{"hinge", 1.0}});
  const auto energy = [&] {
    const SimulationHealth h = sim->health();
    return h.kinetic_energy + h.potential_energy;
  };
  const double E0 = energy();
  double last = E0, worst_rate_error = 0, fastest_turn = 0;
  for (int sample = 1; sample <= 150; ++sample) {
    for (int i = 0; i < 10; ++i) {
      sim->step();
      const double reported = sim->joint_state("rail")->velocity;
      const double expected = rail_rate_from_links(*sim);
      const double arm_turn = sim->link_pose("arm")->w_SL_S.norm();
      fastest_turn = std::max(fastest_turn, arm_turn);
      // Scale: the speeds the rate is made of (the carriage's, the arm's turn over 1.1 m).
      const double scale = sim->link_pose("carriage")->v_SLo_S.norm() + 1.2 * arm_turn;
      worst_rate_error = std::max(worst_rate_error, std::abs(reported - expected) / scale);
    }
    const double E = energy();
    ASSERT_LE(E, last + 1e-6 * (E0 - E)) << "t = " << sim->time();
    last = E;
  }
  std::printf("arm with rail: worst relative rate error %.3g, fastest turn %.3g rad/s, energy %.6g -> %.6g J\n",
              worst_rate_error, fastest_turn, E0, last);
  EXPECT_GT(fastest_turn, 1.0);  // The arm did swing, so the old error would have been 0.5 m/s or more.
  EXPECT_LT(worst_rate_error, 1e-9);
  EXPECT_NEAR(E0 - last, sim->health().dissipated_energy, 0.01 * (E0 - last));
}

// The arm held at 0.6 rad and the carriage at 0.05 m by stiff, critically damped PD commands: at
// rest the rail's reported effort is the force that holds the carriage up along the rail, m g
// times the rail's slope. It was that force times the cosine of the arm's turn (ODE's motor axis
// read in the carriage's frame).
TEST(DynamicsSlider, TheEffortOfARailOnATurnedArmIsAlongTheRail) {
  RobotBuilder b = arm_with_rail(0.0);
  auto sim = simulate(b.robot(), {});
  const double m = 0.5, kp_rail = 300, kd_rail = 2 * std::sqrt(kp_rail * m);
  const double kp_arm = 1000, kd_arm = 2 * std::sqrt(kp_arm * 0.85);  // About the arm and carriage's 0.83 kg m^2.
  ASSERT_TRUE(sim->set_command({"hinge", CommandMode::kPosition, 0, 0.6, 0, kp_arm, kd_arm}));
  ASSERT_TRUE(sim->set_command({"rail", CommandMode::kPosition, 0, 0.05, 0, kp_rail, kd_rail}));
  // Slowest mode about exp(-24 t): nothing of the start is left after 5 s.
  while (sim->time() < 5.0) sim->step();
  const JointState rail = *sim->joint_state("rail");
  const Eigen::Vector3d axis_S = sim->link_pose("carriage")->X_SL.linear() * Eigen::Vector3d::UnitX();
  const double holding = m * kG * axis_S.y();  // Up the rail, against gravity's share along it.
  std::printf("rail on an arm at %.6f rad: effort %.12f N, m g along the rail %.12f N\n",
              sim->joint_state("hinge")->position, rail.effort, holding);
  EXPECT_GT(std::abs(holding), 1.0);
  EXPECT_NEAR(rail.effort, holding, 1e-9 * std::abs(holding));
  EXPECT_NEAR(rail.effort, kp_rail * (0.05 - rail.position), 1e-9 * std::abs(holding));
  // The arm's holding torque is gravity's moment of arm and carriage about the hinge: the rail's
  // motor, acting between two centres 0.5 m apart across the rail, adds no couple of its own.
  const Eigen::Vector3d arm_center = sim->link_pose("arm")->X_SL * Eigen::Vector3d(0, -0.5, 0);
  const Eigen::Vector3d carriage_center = sim->link_pose("carriage")->X_SL.translation();
  const double moment = 1.0 * kG * arm_center.x() + m * kG * carriage_center.x();
  EXPECT_NEAR(sim->joint_state("hinge")->effort, moment, 1e-9 * std::abs(moment));
}

// The arm spun at 2 rad/s without gravity and the rail commanded to 0.1 m/s: at every step the
// rail's motor force F is its law on the rail's rate, F = kd (0.1 - qdot'). The motor's row holds
// the rate as of the step's start (ODE builds its Jacobian there: rail axis ax and the centres'
// offset d at the start, the velocities u = v_c - v_p and w at the end), and qdot' is the rate at
// the end; over a step h the axis turns by at most h |w| and d moves by h |u|, so the two differ by
// at most h |w| (2 |u| + |w| |d|), about 6e-3 m/s here. Had the row measured the centres'
// relative speed (as ODE's own slider rate does), the law would be off by |ax . (w x d)|, 1 m/s.
TEST(DynamicsSlider, ARailCommandedOnASpinningArmFollowsItsLawOnTheRailsRate) {
  RobotBuilder b = arm_with_rail(0.0);
  SimulationOptions no_gravity;
  no_gravity.gravity = Eigen::Vector3d::Zero();
  auto sim = simulate(b.robot(), no_gravity);
  const double kd = 100, target = 0.1, h = no_gravity.time_step;
  ASSERT_TRUE(sim->set_command({"hinge", CommandMode::kVelocity, 0, 0, 2.0, 0, 1000}));
  ASSERT_TRUE(sim->set_command({"rail", CommandMode::kVelocity, 0, 0, target, 0, kd}));
  double worst = 0, worst_bound = 0, largest_lever_term = 0;
  while (sim->time() < 0.5) {
    sim->step();
    const JointState rail = *sim->joint_state("rail");
    const LinkPose arm = *sim->link_pose("arm");
    const LinkPose carriage = *sim->link_pose("carriage");
    const Eigen::Vector3d arm_center = arm.X_SL * Eigen::Vector3d(0, -0.5, 0);
    const Eigen::Vector3d v_arm_center = arm.v_SLo_S + arm.w_SL_S.cross(arm_center - arm.X_SL.translation());
    const Eigen::Vector3d d = carriage.X_SL.translation() - arm_center;  // The carriage's centre is its origin.
    const Eigen::Vector3d u = carriage.v_SLo_S - v_arm_center;
    const double w = arm.w_SL_S.norm();
    const Eigen::Vector3d axis_S = carriage.X_SL.linear() * Eigen::Vector3d::UnitX();
    // The reported effort is F along the axis at the end: F cos(h w), within F (h w)^2 / 2.
    const double bound = h * w * (2 * u.norm() + w * d.norm()) + std::abs(rail.effort) / kd * (h * w) * (h * w) + 1e-12;
    const double departure = std::abs(rail.velocity - (target - rail.effort / kd));
    ASSERT_LE(departure, bound) << "t = " << sim->time();
    worst = std::max(worst, departure);
    worst_bound = std::max(worst_bound, bound);
    largest_lever_term = std::max(largest_lever_term, std::abs(axis_S.dot(arm.w_SL_S.cross(d))));
  }
  std::printf("rail on a spinning arm at %.3f rad/s: worst departure from the law %.3g m/s (bound up to %.3g), "
              "the centres' turning term up to %.3g m/s\n",
              sim->joint_state("hinge")->velocity, worst, worst_bound, largest_lever_term);
  EXPECT_GT(sim->joint_state("hinge")->velocity, 1.9);
  EXPECT_GT(largest_lever_term, 10 * worst_bound);  // The bound tells the two measures apart.
}

// A velocity command beyond the joint's velocity limit drives it at the limit: a hinge about the
// vertical (gravity has no moment about it) commanded to 10 rad/s with a limit of 3 rad/s turns at
// 3 rad/s, the motor's target, once the motor has brought it there.
TEST(DynamicsSlider, AVelocityCommandIsBoundByTheJointsVelocityLimit) {
  RobotBuilder b;
  const int base = b.root("base", MassProperties{});
  b.child(base, "spin", JointKind::kContinuous, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitY(), "wheel",
          box_inertial(1.0, {0.2, 0.05, 0.2}));
  b.joint(0).limits = JointLimits{0, 0, 50, 3.0, false};
  auto sim = simulate(b.robot(), {});
  ASSERT_TRUE(sim->set_command({"spin", CommandMode::kVelocity, 0, 0, 10.0, 0, 5.0}));
  while (sim->time() < 1.0) sim->step();
  EXPECT_NEAR(sim->joint_state("spin")->velocity, 3.0, 1e-9 * 3.0);
  // Backwards too, and the bound is the limit, not the command's gain.
  ASSERT_TRUE(sim->set_command({"spin", CommandMode::kVelocity, 0, 0, -1e6, 0, 5.0}));
  while (sim->time() < 2.0) sim->step();
  EXPECT_NEAR(sim->joint_state("spin")->velocity, -3.0, 1e-9 * 3.0);
}

}  // namespace
}  // namespace rdtf
