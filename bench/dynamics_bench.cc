// Issue 4, dynamics without the daemon: wall time of the validation run that gates every revision
// (physical checks + 3 s of simulated time in ODE) for the arm3 fixture, chains of 20, 30 and 40
// links and a 100-link tree, healthy and with one link's inertia scaled by 1e-6; raw simulation
// steps per second with each of ODE's steppers, and where QuickStep becomes the cheaper one.
#include <benchmark/benchmark.h>

#include <functional>
#include <string>

#include <Eigen/Geometry>

#include "rdtf/dynamics.h"
#include "robot_models.h"

namespace {

using rdtf::Robot;

constexpr double kStartAngle = 0.3;  // rad on every joint: the runs start off equilibrium.

// 100 links as real descriptions have them: a 25-link tree of moving boxes, each with three
// links on fixed joints (a 10 g IMU box, a camera frame of 1e-5 kg, a massless optical frame). Kept as separate ODE bodies they are 100 bodies (QuickStep); merged, 24 moving
// ones (dWorldStep) and the root's group, which the world holds.
Robot sensor_tree() {
  Robot robot = rdtf::bench::tree_robot(25);
  robot.name = "sensor_tree100";
  const int moving = static_cast<int>(robot.links.size());
  const auto add = [&robot](int parent, const std::string& name, const Eigen::Vector3d& offset,
                            const rdtf::MassProperties& inertial) {
    rdtf::Joint joint;
    joint.name = name + "_joint";
    joint.kind = rdtf::JointKind::kFixed;
    joint.parent_link = parent;
    joint.child_link = static_cast<int>(robot.links.size());
    joint.X_PJ = Eigen::Isometry3d(Eigen::Translation3d(offset));
    rdtf::Link link;
    link.name = name;
    link.parent_joint = static_cast<int>(robot.joints.size());
    link.X_SL = robot.links[parent].X_SL * joint.X_PJ;
    link.inertial = inertial;
    link.inertial_source = rdtf::InertialSource::kAuthored;
    robot.links[parent].child_joints.push_back(link.parent_joint);
    robot.joints.push_back(joint);
    robot.links.push_back(link);
  };
  for (int l = 0; l < moving; ++l) {
    const std::string base = robot.links[l].name;
    rdtf::MassProperties imu;
    imu.mass = 0.01;
    imu.inertia = (0.01 * 0.02 * 0.02 / 6) * Eigen::Matrix3d::Identity();  // a 2 cm cube
    add(l, base + "_imu", {0.01, -0.05, 0}, imu);
    rdtf::MassProperties camera;  // a 1e-5 kg speck of about 1 mm
    camera.mass = 1e-5;
    camera.inertia = 1e-11 * Eigen::Matrix3d::Identity();
    add(l, base + "_camera", {0, -0.1, 0.01}, camera);
    add(static_cast<int>(robot.links.size()) - 1, base + "_camera_optical", {0, 0, 0.005}, rdtf::MassProperties{});
  }
  return robot;
}

const Robot& model(int which) {
  static const Robot arm3 = rdtf::bench::arm3_robot();
  static const Robot chain = rdtf::bench::chain_robot(30);
  static const Robot tree = rdtf::bench::tree_robot(100);
  static const Robot chain20 = rdtf::bench::chain_robot(20);
  static const Robot chain40 = rdtf::bench::chain_robot(40);
  static const Robot sensors = sensor_tree();
  switch (which) {
    case 0: return arm3;
    case 1: return chain;
    case 2: return tree;
    case 3: return chain20;
    case 4: return chain40;
    default: return sensors;
  }
}

const char* model_name(int which) {
  static const char* const kNames[] = {"arm3", "chain30", "tree100", "chain20", "chain40", "sensor_tree100"};
  return kNames[which];
}

std::string first_error(const rdtf::ValidationReport& report) {
  for (const auto& d : report.diagnostics.all()) {
    if (d.severity == rdtf::Severity::kError) return " (" + d.code + ")";
  }
  return "";
}

// The gate as rdtfd runs it: default options (3 s, 1 ms steps, dWorldStep below 27 bodies and
// QuickStep from 27), except the start: these models hang at an equilibrium, where a passive run
// from rest barely moves, so every revolute joint starts 0.3 rad from rest
// (start_offset_angular, rdtfd's validation_start_offset_rad) and the run does real work. range(1): 0 the defaults,
// 1 dWorldStep whatever the size, 2 QuickStep whatever the size. range(2) 1: the broken variant,
// the middle link's inertia scaled by 1e-6 (facts.md), which must fail.
void BM_Validate(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  Robot robot = model(which);
  if (state.range(2) == 1) robot.links[robot.links.size() / 2].inertial.inertia *= 1e-6;
  rdtf::ValidationOptions options;
  options.start_offset_angular = kStartAngle;
  if (state.range(1) == 1) options.simulation.stepper = rdtf::Stepper::kWorldStep;
  if (state.range(1) == 2) options.simulation.stepper = rdtf::Stepper::kQuickStep;
  rdtf::ValidationReport report;
  for (auto _ : state) {
    report = rdtf::validate_dynamics(robot, options);
    benchmark::DoNotOptimize(report);
  }
  state.counters["links"] = static_cast<double>(robot.links.size());
  state.counters["bodies"] = report.bodies;
  state.counters["passed"] = report.passed ? 1 : 0;
  state.counters["steps"] = static_cast<double>(report.steps);
  state.counters["energy_drift"] = report.energy_drift;
  state.counters["worst_misalignment_rad"] = report.worst_joint_misalignment;
  state.counters["worst_separation_m"] = report.worst_joint_error;
  state.counters["misalignment_warning"] = report.diagnostics.contains("SIM_JOINT_MISALIGNMENT") ? 1 : 0;
  state.SetLabel(std::string(model_name(which)) + (state.range(2) == 1 ? " x1e-6 " : " ") + report.stepper +
                 (report.passed ? " passed" : " FAILED" + first_error(report)));
}
BENCHMARK(BM_Validate)
    ->ArgsProduct({{0, 1, 2, 3, 4, 5}, {0}, {0, 1}})
    ->Args({1, 1, 0})
    ->Args({1, 1, 1})
    ->Args({3, 2, 0})
    ->Args({4, 1, 0})
    ->Unit(benchmark::kMillisecond);
// dWorldStep on 100 bodies: about 4.4 ms of CPU per step, 13 s per run: one run each.
BENCHMARK(BM_Validate)->Args({2, 1, 0})->Args({2, 1, 1})->Iterations(1)->Unit(benchmark::kMillisecond);

// One 1 ms step of the whole model; the simulation is rebuilt (untimed) every 3000 steps so that
// every sample covers the same kind of motion as the validation run.
void BM_Step(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  const Robot& robot = model(which);
  rdtf::SimulationOptions options;
  options.stepper = state.range(1) == 0 ? rdtf::Stepper::kWorldStep : rdtf::Stepper::kQuickStep;
  const auto pose = rdtf::bench::bent_pose(robot, kStartAngle);  // as the gate starts
  auto build = [&] {
    rdtf::Diagnostics diag;
    auto simulation = rdtf::Simulation::create(robot, options, pose, diag);
    if (!simulation) throw std::runtime_error("the ODE model was not built");
    return simulation;
  };
  auto simulation = build();
  for (auto _ : state) {
    simulation->step();
    if (simulation->steps() == 3000) {
      state.PauseTiming();
      simulation = build();
      state.ResumeTiming();
    }
  }
  state.counters["steps_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["bodies"] = simulation->body_count();
  state.SetLabel(std::string(model_name(which)) + " " + std::string(simulation->stepper_name()));
}
BENCHMARK(BM_Step)->ArgsProduct({{0, 1, 2}, {0, 1}})->Unit(benchmark::kMicrosecond);

// Where QuickStep becomes the cheaper stepper (SimulationOptions::quickstep_min_bodies): one 1 ms
// step of a chain of range(0) links with each stepper.
void BM_StepChain(benchmark::State& state) {
  const Robot robot = rdtf::bench::chain_robot(static_cast<int>(state.range(0)));
  rdtf::SimulationOptions options;
  options.stepper = state.range(1) == 0 ? rdtf::Stepper::kWorldStep : rdtf::Stepper::kQuickStep;
  rdtf::Diagnostics diag;
  auto simulation = rdtf::Simulation::create(robot, options, rdtf::bench::bent_pose(robot, kStartAngle), diag);
  for (auto _ : state) {
    simulation->step();
    if (simulation->steps() == 3000) {
      state.PauseTiming();
      simulation = rdtf::Simulation::create(robot, options, rdtf::bench::bent_pose(robot, kStartAngle), diag);
      state.ResumeTiming();
    }
  }
  state.SetLabel(std::string(simulation->stepper_name()));
}
BENCHMARK(BM_StepChain)->ArgsProduct({{10, 15, 20, 25, 27, 30, 35, 40, 50, 60, 80, 100}, {0, 1}})->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
