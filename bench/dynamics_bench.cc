// Issue 4, dynamics without the daemon: wall time of the validation run that gates every revision
// (physical checks + 3 s of simulated time in ODE), and raw simulation steps per second with each
// of ODE's steppers, for the arm3 fixture, a 30-link chain and a 100-link tree.
#include <benchmark/benchmark.h>

#include <functional>

#include "rdtf/dynamics.h"
#include "robot_models.h"

namespace {

using rdtf::Robot;

constexpr double kStartAngle = 0.3;  // rad on every joint: the runs start off equilibrium.

const Robot& model(int which) {
  static const Robot arm3 = rdtf::bench::arm3_robot();
  static const Robot chain = rdtf::bench::chain_robot(30);
  static const Robot tree = rdtf::bench::tree_robot(100);
  switch (which) {
    case 0: return arm3;
    case 1: return chain;
    default: return tree;
  }
}

const char* model_name(int which) {
  static const char* const kNames[] = {"arm3", "chain30", "tree100"};
  return kNames[which];
}

std::string first_error(const rdtf::ValidationReport& report) {
  for (const auto& d : report.diagnostics.all()) {
    if (d.severity == rdtf::Severity::kError) return " (" + d.code + ")";
  }
  return "";
}

// The gate from a bent start pose. range(1) 0: as rdtfd runs it (default options: 3 s, 1 ms steps,
// dWorldStep below 15 bodies and QuickStep from 15); 1: dWorldStep whatever the size.
void BM_Validate(benchmark::State& state) {
  const Robot& robot = model(static_cast<int>(state.range(0)));
  rdtf::ValidationOptions options;
  if (state.range(1) == 1) options.simulation.stepper = rdtf::Stepper::kWorldStep;
  options.initial_positions = rdtf::bench::bent_pose(robot, kStartAngle);
  rdtf::ValidationReport report;
  for (auto _ : state) {
    report = rdtf::validate_dynamics(robot, options);
    benchmark::DoNotOptimize(report);
  }
  state.counters["links"] = static_cast<double>(robot.links.size());
  state.counters["passed"] = report.passed ? 1 : 0;
  state.counters["steps"] = static_cast<double>(report.steps);
  state.counters["energy_drift"] = report.energy_drift;
  state.counters["worst_misalignment_rad"] = report.worst_joint_misalignment;
  state.counters["worst_separation_m"] = report.worst_joint_error;
  state.SetLabel(std::string(model_name(static_cast<int>(state.range(0)))) + " " + report.stepper +
                 (report.passed ? " passed" : " FAILED" + first_error(report)));
}
BENCHMARK(BM_Validate)->Args({0, 0})->Args({1, 0})->Args({2, 0})->Args({1, 1})->Unit(benchmark::kMillisecond);
// dWorldStep on 100 bodies: about 5 ms of CPU per step, 15 s per run: one run.
BENCHMARK(BM_Validate)->Args({2, 1})->Iterations(1)->Unit(benchmark::kMillisecond);

// One 1 ms step of the whole model; the simulation is rebuilt (untimed) every 3000 steps so that
// every sample covers the same kind of motion as the validation run.
void BM_Step(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  const Robot& robot = model(which);
  rdtf::SimulationOptions options;
  options.stepper = state.range(1) == 0 ? rdtf::Stepper::kWorldStep : rdtf::Stepper::kQuickStep;
  const auto pose = rdtf::bench::bent_pose(robot, kStartAngle);
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

}  // namespace

BENCHMARK_MAIN();
