// Joint damping against the recurrences of its two integrators (docs/dynamics.md, "Joint forces").
// A joint whose damping c acts on a small inertia I (c h / I > 2 at the step h) blew up when the
// damping was a torque from the state before the step (forward Euler); such a joint is damped
// implicitly now, and a heavy one keeps the torque. Each test drives one degree of freedom whose
// motion is exactly one of the two recurrences (a cube turning about its centre, or sliding), so
// the simulation must reproduce it to rounding.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <Eigen/LU>

#include "dynamics/dynamics_models.h"

namespace rdtf {
namespace {

using dynamics_test::box_inertial;
using dynamics_test::RobotBuilder;
using dynamics_test::simulate;

constexpr double kStep = 1e-3;  // the default time step

// A cube of `mass` kg and edge `edge` m on a joint to the world through its centre (gravity acts
// through the joint: only the command moves it). Its inertia is m a^2 / 6 about every axis.
struct Cube {
  double mass, edge;
  double inertia() const { return mass * edge * edge / 6; }
};

void add_cube(RobotBuilder& b, const std::string& name, const Cube& cube, JointKind kind, double damping) {
  const int root = b.root(name + "_base", MassProperties{});
  b.child(root, name, kind, Eigen::Isometry3d::Identity(), Eigen::Vector3d::UnitZ(), name + "_cube",
          box_inertial(cube.mass, Eigen::Vector3d::Constant(cube.edge)));
  b.joint(static_cast<int>(b.robot().joints.size()) - 1).damping = damping;
}

JointCommand torque(const std::string& joint, double effort) {
  JointCommand command;
  command.joint = joint;
  command.mode = CommandMode::kTorque;
  command.effort = effort;
  return command;
}

// The speeds of the two recurrences for a constant effort tau from rest, inertia (or mass) I:
// implicit v' = (v + h tau / I) / (1 + c h / I); explicit v' = v + h (tau - c v) / I.
double implicit_speed(double v, double tau, double c, double I) { return (v + kStep * tau / I) / (1 + c * kStep / I); }
double explicit_speed(double v, double tau, double c, double I) { return v + kStep * (tau - c * v) / I; }

// A 6 cm, 0.2 kg cube damped by 0.4 N m s: c h / I = 3.33 (the forearm of the report). Implicit
// Euler to rounding over 200 steps, and the energy balance closes on the damper's work to rounding:
// the work of a step is its force times h (v before + v after) / 2, which is what the kinetic energy
// gains, 1/2 I (v'^2 - v^2) = 1/2 I (v' - v) (v' + v) with I (v' - v) = h (tau - c v'). (Counting
// it as the force times the travel, h v', left the balance short by the implicit step's own loss,
// sum 1/2 I dv^2: 5.9e-7 J of 1.2e-3 J of work here.)
TEST(JointDamping, ALightLinkIsDampedImplicitly) {
  const Cube cube{0.2, 0.06};
  const double c = 0.4, tau = 0.05;
  ASSERT_GT(c * kStep / cube.inertia(), 2);  // where a torque from the last state blows up
  RobotBuilder b;
  add_cube(b, "spin", cube, JointKind::kContinuous, c);
  auto sim = simulate(b.robot(), {});
  ASSERT_TRUE(sim->set_command(torque("spin", tau)));
  double v = 0, dissipated = 0, work = 0;
  for (int n = 1; n <= 200; ++n) {
    sim->step();
    const double next = implicit_speed(v, tau, c, cube.inertia());
    dissipated += c * next * kStep * (v + next) / 2;
    work += tau * kStep * (v + next) / 2;
    v = next;
    ASSERT_NEAR(sim->joint_state("spin")->velocity, v, 1e-12 * std::abs(v)) << "step " << n;
  }
  EXPECT_NEAR(v, tau / c, 1e-9 * tau / c);  // at its terminal speed
  const SimulationHealth h = sim->health();
  const double balance = h.kinetic_energy + h.dissipated_energy - h.actuator_work;
  std::printf("light cube: v = %.15g rad/s, balance %.6g J of %.6g J of work\n", v, balance, h.actuator_work);
  EXPECT_NEAR(h.dissipated_energy, dissipated, 1e-9 * dissipated);
  EXPECT_NEAR(h.actuator_work, work, 1e-9 * work);
  EXPECT_NEAR(balance, 0.0, 1e-9 * h.actuator_work);
}

// A 0.3 m, 0.667 kg cube (I = 1e-2 kg m^2) damped by 0.4: c h / I = 0.04, and the damper stays a
// torque from the last state, forward Euler to rounding. Its dissipation counts c v h (v + v') / 2,
// v the speed before the step (the force's) and v' after it, and the balance closes to rounding.
TEST(JointDamping, AHeavyLinkKeepsTheExplicitDamper) {
  const Cube cube{2.0 / 3.0, 0.3};
  const double c = 0.4, tau = 0.05;
  RobotBuilder b;
  add_cube(b, "spin", cube, JointKind::kRevolute, c);
  auto sim = simulate(b.robot(), {});
  ASSERT_TRUE(sim->set_command(torque("spin", tau)));
  double v = 0, dissipated = 0;
  for (int n = 1; n <= 200; ++n) {
    sim->step();
    const double next = explicit_speed(v, tau, c, cube.inertia());
    dissipated += c * v * kStep * (v + next) / 2;
    v = next;
    ASSERT_NEAR(sim->joint_state("spin")->velocity, v, 1e-12 * std::abs(v)) << "step " << n;
  }
  const SimulationHealth h = sim->health();
  EXPECT_NEAR(h.dissipated_energy, dissipated, 1e-9 * dissipated);
  EXPECT_NEAR(h.kinetic_energy + h.dissipated_energy - h.actuator_work, 0.0, 1e-9 * h.actuator_work);
}

// The rule for several dampers: in each island, the explicit ones' rates, summed, times h, at most 1
// (every mode then decays without reversing). One island: cube A on a joint to the world, cube B on
// a joint to A about the same axis through both centres (the joint space inertia M = [[I_A + I_B,
// I_B], [I_B, I_B]] in (qdot_a, qdot_b), no gyroscopic or gravity torque). Their rates, c_a / I_A and
// c_b (1 / I_B + 1 / I_A), times h are 0.6 and 0.7: A stays explicit, B, which would take the sum
// to 1.3, is implicit, and the speeds follow (M + h C_implicit) x' = M x + h (tau - C_explicit x) to
// rounding; with h halved both fit and both are explicit.
TEST(JointDamping, TheLeastRatesOfAnIslandStayExplicitWhileTheirSumIsOne) {
  const Cube cube_a{0.2, 0.06}, cube_b{0.1, 0.05};
  const double I_A = cube_a.inertia(), I_B = cube_b.inertia(), tau_a = 0.05, tau_b = -0.02;
  const double c_a = 0.6 / (kStep / I_A), c_b = 0.7 / (kStep * (1 / I_B + 1 / I_A));
  RobotBuilder b;
  add_cube(b, "a", cube_a, JointKind::kContinuous, c_a);
  b.child(b.robot().joints[0].child_link, "b", JointKind::kContinuous, Eigen::Isometry3d::Identity(),
          Eigen::Vector3d::UnitZ(), "b_cube", box_inertial(cube_b.mass, Eigen::Vector3d::Constant(cube_b.edge)));
  b.joint(1).damping = c_b;
  Eigen::Matrix2d M;
  M << I_A + I_B, I_B, I_B, I_B;
  const Eigen::Vector2d tau(tau_a, tau_b);
  for (const double h : {kStep, kStep / 2}) {
    SCOPED_TRACE("h " + std::to_string(h));
    auto sim = simulate(b.robot(), {});
    ASSERT_TRUE(sim->set_command(torque("a", tau_a)));
    ASSERT_TRUE(sim->set_command(torque("b", tau_b)));
    const Eigen::Matrix2d C_explicit = Eigen::Vector2d(c_a, h == kStep ? 0 : c_b).asDiagonal();
    const Eigen::Matrix2d C_implicit = Eigen::Vector2d(0, h == kStep ? c_b : 0).asDiagonal();
    Eigen::Vector2d x = Eigen::Vector2d::Zero();
    for (int n = 1; n <= 50; ++n) {
      sim->step(h);
      x = (M + h * C_implicit).lu().solve(M * x + h * (tau - C_explicit * x));
      const double scale = x.cwiseAbs().maxCoeff();
      ASSERT_NEAR(sim->joint_state("a")->velocity, x(0), 1e-12 * scale) << "step " << n;
      ASSERT_NEAR(sim->joint_state("b")->velocity, x(1), 1e-12 * scale) << "step " << n;
    }
  }
}

// Separate islands are bounded each on its own: two cubes of c h / I = 0.6 and 0.7, each on a joint
// to the world, both stay explicit (their sum, 1.3, is no bound on either: M is block diagonal).
TEST(JointDamping, DampersOfSeparateIslandsAreBoundedEachOnItsOwn) {
  const Cube cube{0.2, 0.06};
  const double I = cube.inertia(), tau = 0.05;
  const double c_a = 0.6 * I / kStep, c_b = 0.7 * I / kStep;
  RobotBuilder b;
  add_cube(b, "a", cube, JointKind::kContinuous, c_a);
  add_cube(b, "b", cube, JointKind::kContinuous, c_b);
  auto sim = simulate(b.robot(), {});
  ASSERT_TRUE(sim->set_command(torque("a", tau)));
  ASSERT_TRUE(sim->set_command(torque("b", tau)));
  double v_a = 0, v_b = 0;
  for (int n = 1; n <= 50; ++n) {
    sim->step();
    v_a = v_a + kStep * (tau - c_a * v_a) / I;
    v_b = v_b + kStep * (tau - c_b * v_b) / I;
    ASSERT_NEAR(sim->joint_state("a")->velocity, v_a, 1e-12 * std::abs(v_a)) << "step " << n;
    ASSERT_NEAR(sim->joint_state("b")->velocity, v_b, 1e-12 * std::abs(v_b)) << "step " << n;
  }
}

// A slider is always damped implicitly: what it moves along its axis depends on where it is once
// its parent turns, so no bound taken at the start holds. A 50 g carriage, c = 2 N s/m (c h / m =
// 0.04), pushed by 0.1 N along the rail.
TEST(JointDamping, ASliderIsDampedImplicitly) {
  const Cube carriage{0.05, 0.02};
  const double c = 2.0, force = 0.1;
  RobotBuilder b;
  add_cube(b, "rail", carriage, JointKind::kPrismatic, c);
  b.joint(0).axis = Eigen::Vector3d::UnitX();  // across gravity (-Y): only the push moves it
  auto sim = simulate(b.robot(), {});
  ASSERT_TRUE(sim->set_command(torque("rail", force)));
  double v = 0;
  for (int n = 1; n <= 200; ++n) {
    sim->step();
    v = implicit_speed(v, force, c, carriage.mass);
    ASSERT_NEAR(sim->joint_state("rail")->velocity, v, 1e-12 * std::abs(v)) << "step " << n;
  }
}

// A thin 20 g rod swinging on a damped ball joint: about its own length its inertia is 1.6e-9 kg m^2,
// so a damper of 0.05 N m s as a torque multiplies any twist by 1 - c h / I = -3e4 each step (it
// blew up); implicit, the swing only loses energy and the damper's work accounts for the loss.
TEST(JointDamping, ALightBallJointOnlyDissipates) {
  RobotBuilder b;
  const int root = b.root("frame", MassProperties{});
  // Tilted about an axis between its principal ones, so the swing couples into a twist.
  const Eigen::Isometry3d tilted(Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 0, 1).normalized()));
  b.child(root, "socket", JointKind::kBall, tilted, Eigen::Vector3d::UnitX(), "rod",
          box_inertial(0.02, {5.5e-4, 0.3, 8e-4}, {0, -0.15, 0}));
  b.joint(0).damping = 0.05;
  auto sim = simulate(b.robot(), {});
  const auto energy = [&] {
    const SimulationHealth h = sim->health();
    return h.kinetic_energy + h.potential_energy;
  };
  const double E0 = energy();
  double last = E0;
  for (int sample = 1; sample <= 100; ++sample) {
    for (int i = 0; i < 10; ++i) sim->step();
    const double E = energy();
    ASSERT_TRUE(std::isfinite(E)) << "t = " << sim->time();
    ASSERT_LE(E, last + 1e-6 * (E0 - E)) << "t = " << sim->time();
    last = E;
  }
  const SimulationHealth h = sim->health();
  std::printf("damped rod on a ball: lost %.6g J, damper's work %.6g J\n", E0 - last, h.dissipated_energy);
  EXPECT_GT(E0 - last, 0);
  EXPECT_NEAR(E0 - last, h.dissipated_energy, 0.01 * (E0 - last));
}

}  // namespace
}  // namespace rdtf
