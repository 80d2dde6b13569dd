// The live simulation's timing (daemon/simulation_host.h), driven with a clock of the test's own:
// the simulation thread's pass (advance_live_models) at wake-up times that come late by a varying
// amount, as sleep_until's do, sometimes by several steps, once by a long stall. Every joint state
// the configured rate asks for must go out, a period of simulated time apart. (rdtfd sent about
// every other state at 1 kHz when states were checked against the wake-up time: docs/benchmarks.md.)
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "dynamics/dynamics_models.h"
#include "simulation_host.h"

namespace rdtf::daemon {
namespace {

using namespace std::chrono_literals;

struct Sent {
  std::map<std::string, std::vector<double>> sim_times;  // per model, in order
};

// `count` live arms, their states every `rate_hz` per wall second at `real_time_factor`.
LiveModels live_arms(int count, double rate_hz, double real_time_factor, double time_step) {
  LiveModels models;
  SimulationOptions options;
  options.time_step = time_step;
  for (int i = 0; i < count; ++i) {
    auto model = std::make_unique<LiveModel>();
    Diagnostics diag;
    model->simulation = Simulation::create(dynamics_test::arm_builder().robot(), options, {}, diag);
    if (!model->simulation) throw std::runtime_error("arm not built: " + dynamics_test::all_text(diag));
    model->states.emplace(real_time_factor / rate_hz, time_step);
    models.emplace("arm" + std::to_string(i), std::move(model));
  }
  return models;
}

// A wake-up `late` after it was due. Deterministic: 0 to 0.97 ms late in a scrambled order (a
// sleep_until on a loaded machine), every 53rd wake-up 3.4 ms late (several steps to catch up).
Clock::duration lateness(int wake) {
  if (wake % 53 == 52) return 3400us;
  return std::chrono::microseconds((wake * 389) % 971);
}

// Drives the thread's pass from the clock's start until just before `end` of wall time, so that
// exactly the steps due before `end` are taken; returns the wake-ups.
int drive(StepClock& clock, LiveModels& models, double time_step, Clock::time_point end, Sent& sent) {
  const auto publish = [&](const std::string& id, LiveModel& model) {
    sent.sim_times[id].push_back(model.simulation->time());
  };
  int wake = 0;
  for (Clock::time_point now = clock.next_due(); now < end; now = clock.next_due() + lateness(++wake)) {
    advance_live_models(clock, models, now, time_step, publish);
  }
  advance_live_models(clock, models, end - 1ns, time_step, publish);
  return wake + 1;
}

void expect_every_state(const Sent& sent, int models, std::size_t states, double period) {
  ASSERT_EQ(sent.sim_times.size(), static_cast<std::size_t>(models));
  for (const auto& [id, times] : sent.sim_times) {
    SCOPED_TRACE(id);
    EXPECT_EQ(times.size(), states);
    for (std::size_t i = 1; i < times.size(); ++i) {
      ASSERT_NEAR(times[i] - times[i - 1], period, 1e-9) << "between states " << i - 1 << " and " << i;
    }
  }
}

const Clock::time_point kStart = Clock::time_point{} + 1h;

// 1 kHz with 1 ms steps: a state after every step. In 2 s of wall time from kStart, steps are due
// at kStart + 0, 1, ..., 1999 ms: 2000 steps and as many states per model.
TEST(SimulationSchedule, EveryStateAtOneKilohertzDespiteLateWakeUps) {
  LiveModels models = live_arms(3, 1000, 1.0, 1e-3);
  StepClock clock(1e-3, 1.0, kStart);
  Sent sent;
  const int wakes = drive(clock, models, 1e-3, kStart + 2s, sent);
  EXPECT_LT(wakes, 2000);  // some wake-ups took several steps
  expect_every_state(sent, 3, 2000, 1e-3);
  for (const auto& [id, model] : models) EXPECT_EQ(model->simulation->steps(), 2000u);
}

// Lower rates: a state every `period` of simulated time, after the step nearest to it.
TEST(SimulationSchedule, StatesFollowSimulatedTimeAtLowerRates) {
  {
    LiveModels models = live_arms(1, 100, 1.0, 1e-3);
    StepClock clock(1e-3, 1.0, kStart);
    Sent sent;
    drive(clock, models, 1e-3, kStart + 2s, sent);
    expect_every_state(sent, 1, 200, 10e-3);  // after steps 10, 20, ..., 2000
    EXPECT_NEAR(sent.sim_times["arm0"].front(), 10e-3, 1e-12);
  }
  {
    // 300 Hz with 1 ms steps: 3 or 4 ms apart, 3.33 ms on average, 600 states in 2 s.
    LiveModels models = live_arms(1, 300, 1.0, 1e-3);
    StepClock clock(1e-3, 1.0, kStart);
    Sent sent;
    drive(clock, models, 1e-3, kStart + 2s, sent);
    const std::vector<double>& times = sent.sim_times["arm0"];
    ASSERT_EQ(times.size(), 600u);
    for (std::size_t i = 1; i < times.size(); ++i) {
      const double gap = times[i] - times[i - 1];
      EXPECT_TRUE(std::abs(gap - 3e-3) < 1e-9 || std::abs(gap - 4e-3) < 1e-9) << gap;
    }
    // State n (1, 2, ...) goes out within half a step of n / 300 s.
    for (std::size_t i = 0; i < times.size(); ++i) EXPECT_NEAR(times[i], (i + 1) / 300.0, 0.5e-3 + 1e-9) << i;
  }
}

// Simulated seconds per wall second 2: steps every 0.5 ms of wall time, and 1000 states per wall
// second are one every 2 ms of simulated time.
TEST(SimulationSchedule, RealTimeFactorScalesTheSimulatedPeriod) {
  LiveModels models = live_arms(2, 1000, 2.0, 1e-3);
  StepClock clock(1e-3, 2.0, kStart);
  Sent sent;
  drive(clock, models, 1e-3, kStart + 1s, sent);
  expect_every_state(sent, 2, 1000, 2e-3);
}

// Asked for more states than steps: one per step.
TEST(SimulationSchedule, AtMostOneStatePerStep) {
  LiveModels models = live_arms(1, 5000, 1.0, 1e-3);
  StepClock clock(1e-3, 1.0, kStart);
  Sent sent;
  drive(clock, models, 1e-3, kStart + 500ms, sent);
  expect_every_state(sent, 1, 500, 1e-3);
}

// A stall of 200 ms: the wake-up takes kMaxCatchUp steps (each sends its state), then the schedule
// restarts from that wake-up: the simulation falls 150 ms behind instead of spiralling.
TEST(SimulationSchedule, AfterAStallTheSimulationFallsBehindWithoutSkippingStates) {
  LiveModels models = live_arms(1, 1000, 1.0, 1e-3);
  StepClock clock(1e-3, 1.0, kStart);
  Sent sent;
  const auto publish = [&](const std::string& id, LiveModel& model) {
    sent.sim_times[id].push_back(model.simulation->time());
  };
  advance_live_models(clock, models, kStart, 1e-3, publish);  // step 1
  const Clock::time_point stalled = kStart + 200ms;
  advance_live_models(clock, models, stalled, 1e-3, publish);
  EXPECT_EQ(models["arm0"]->simulation->steps(), 1u + StepClock::kMaxCatchUp);
  EXPECT_EQ(clock.next_due(), stalled);
  advance_live_models(clock, models, stalled, 1e-3, publish);
  EXPECT_EQ(models["arm0"]->simulation->steps(), 2u + StepClock::kMaxCatchUp);
  EXPECT_EQ(clock.next_due(), stalled + 1ms);
  expect_every_state(sent, 1, 2 + StepClock::kMaxCatchUp, 1e-3);
}

}  // namespace
}  // namespace rdtf::daemon
