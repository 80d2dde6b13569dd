// Live simulation of every live model on one thread of its own: steps each model's ODE world in
// real time, publishes joint states and link poses (and answers nothing else), and applies controllers'
// commands. The event loop hands it models and commands through a mutex-guarded inbox, so the
// loop never waits for physics and physics never waits for files.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include <rdtf/joint_command_t.hpp>

#include "live_names.h"
#include "rdtf/dynamics.h"
#include "rdtf/robot.h"

namespace rdtf::daemon {

using Clock = std::chrono::steady_clock;

// How long a joint's command holds after the last command naming it was applied, when the
// setting joint_command_timeout_s does not say (docs/controller.md, "Command lifetime").
inline constexpr Clock::duration kDefaultJointCommandLifetime = std::chrono::milliseconds(500);

struct SimulationHostOptions {
  std::string lcm_url;
  std::string channel_prefix = "RDTF";
  SimulationOptions simulation;
  // JOINT_STATE + LINK_STATE pairs per wall-clock second and model (while the simulation keeps
  // real time), at most one per step: 1 / time_step x real_time_factor.
  double state_rate_hz = 100;
  double real_time_factor = 1.0;   // Simulated seconds per wall-clock second.
  // A joint whose commands stop arriving for this long (the daemon's steady clock) is released.
  Clock::duration joint_command_lifetime = kDefaultJointCommandLifetime;
};



// The live simulation's timing, apart from threads, LCM and the clock so that a test can drive it
// with times of its own (tests/dynamics/live_schedule_test.cc).
//
// Steps keep real time: step k is due at start + k x time_step / real_time_factor. A wake-up takes
// every step due, at most kMaxCatchUp at once; after a longer stall the schedule restarts from
// the wake-up (the simulation falls behind instead of spiralling).
class StepClock {
 public:
  static constexpr int kMaxCatchUp = 50;
  StepClock(double time_step, double real_time_factor, Clock::time_point start);
  int take_due(Clock::time_point now);  // The steps to take now.
  Clock::time_point next_due() const { return next_; }
  void restart(Clock::time_point now) { next_ = now; }

 private:
  Clock::duration tick_;
  Clock::time_point next_;
};

// Joint states follow simulated time, not the wall clock: state n (1, 2, ...) of a model is due at
// simulated time n x period (period = real_time_factor / state_rate_hz) and goes out right after the step
// nearest to it, so no state is skipped however late the thread wakes (steps taken to catch up
// each send theirs), and consecutive states are a period of simulated time apart. Counted in the
// host's steps, so that a simulation ODE stopped (its time frozen) still reports its state.
class StateSchedule {
 public:
  StateSchedule(double period, double time_step) : period_(period), time_step_(time_step) {}
  bool after_step();  // Call after each step; true when a state is due now.

 private:
  double period_;     // s of simulated time
  double time_step_;  // s
  std::uint64_t steps_ = 0;
  std::uint64_t next_ = 1;  // Index of the next state due.
};

struct LiveModel {
  std::int64_t revision = 0;
  std::string content_hash;
  std::unique_ptr<Simulation> simulation;
  std::optional<StateSchedule> states;
  std::shared_ptr<const Robot> robot;  // To start again from rest after a failure.
  SimulationOptions options;           // The host's, with the verdict's stepper.
  bool after_quickstep_failed = false;  // The verdict's stepper is dWorldStep because QuickStep failed.
  double time_offset = 0;              // s: simulated time of the runs before a restart.
  bool failed = false;                 // Its state became non-finite or blew up (not stepped).
  int failure_streak = 0;              // Failures in a row (runs shorter than kFailureStreakReset).
  Clock::time_point restart_at{};      // When failed: when it starts again (back-off).
  Clock::time_point running_since{};   // Wall time of its last (re)start.
  // The CPU budget: the fraction of the host's steps this model takes (budget_step_rates), the
  // credit towards its next step, and the measured wall time of one of its steps.
  double rate = 1;
  double credit = 0;
  double step_seconds = 0;  // moving average
  double window_start_time = 0;  // simulated time (with time_offset) at the window's start
  bool behind = false;
  bool measured = false;  // Has had a whole window.
  double sim_time() const { return time_offset + (simulation ? simulation->time() : 0.0); }
  LiveNames names;
  // Commands' lifetime: each commanded joint (by URDF name) holds its command until its expiry
  // on the host's clock, renewed by every command naming it (docs/controller.md).
  Clock::duration command_lifetime = kDefaultJointCommandLifetime;
  std::map<std::string, Clock::time_point, std::less<>> command_expiry;
};
using LiveModels = std::map<std::string, std::unique_ptr<LiveModel>>;

// One pass of the simulation thread at wall time `now`: joints whose commands ran out released
// (release_expired_commands), then every step due on `clock`, every model in lockstep (a model whose `rate` is below 1 takes that fraction of the steps), and `publish` for
// each state due after each step. A model whose simulation stops advancing (ODE failed on a
// non-finite or blown-up state) is marked `failed` and left alone.
void advance_live_models(StepClock& clock, LiveModels& models, Clock::time_point now, double time_step,
                         const std::function<void(const std::string&, LiveModel&)>& publish);


// A controller's command applied to `model` at `now` (the host thread's clock), all or nothing:
// its revision and content hash must be the model's, and every joint known. Each joint it names
// holds its command until now + model.command_lifetime. "" when applied, else why not.
std::string command_live_model(LiveModel& model, const rdtf::joint_command_t& command, Clock::time_point now);

// Releases every joint of `model` whose command expired by `now`: the joint is passive again (no
// actuator effort; its authored damping, friction, spring and limits, and gravity, act on it).
void release_expired_commands(LiveModel& model, Clock::time_point now);

// The CPU budget of the live simulations: the fraction of the host's steps each model may take
// when one step of every model costs `step_seconds` and `budget_seconds` is available per step.
// Max-min fair (water-filling): models cheaper than an equal share run at full rate and leave the
// rest to the others; a model costlier than its share takes only its share, so one huge model
// falls behind real time alone instead of slowing every simulation.
std::vector<double> budget_step_rates(const std::vector<double>& step_seconds, double budget_seconds);

// A model whose keeping time changed (fell behind, or kept time again) in one window.
struct TimingChange {
  std::string id;
  double factor;     // simulated s per wall s in the window
  std::string line;  // its own log line
};
// The log lines for the changes of one window (`what`: "are behind", "keep time again"): each
// model's own when at most three changed; else one naming the first three, the count and the
// range of factors (a starved thread made every model fall behind at once: 38 lines every few
// seconds on a loaded machine, which said nothing one line does not).
std::vector<std::string> timing_change_lines(const std::vector<TimingChange>& changes, const char* what,
                                             double wanted);

// At most `per_second` reports in any one-second window: a flood of bad commands or failures is
// not answered by a flood of ERRORs. The next report admitted says how many were left out.
class ReportLimiter {
 public:
  ReportLimiter(int per_second, std::string what) : per_second_(per_second), what_(std::move(what)) {}
  // `text` to send at `now` (with the count left out before it), or nothing: left out, counted.
  std::optional<std::string> admit(const std::string& text, Clock::time_point now);

 private:
  int per_second_;
  std::string what_;  // "rejections", "failures"
  Clock::time_point window_{};
  int in_window_ = 0;
  std::uint64_t unreported_ = 0;
};

// The wait before restarting a live simulation that failed for the `n`th time in a row (n >= 1):
// kFirstRestartDelay doubled with each failure, at most kMaxRestartDelay. A run that lasted
// kFailureStreakReset of wall time ends the streak.
inline constexpr auto kFirstRestartDelay = std::chrono::milliseconds(100);
inline constexpr auto kMaxRestartDelay = std::chrono::seconds(30);
inline constexpr auto kFailureStreakReset = std::chrono::seconds(10);
Clock::duration restart_delay(int n);

// How the live simulations keep real time, for STATUS.
struct LiveTiming {
  double real_time_factor = 0;  // the slowest model's simulated s per wall s over the last window
  int behind = 0;               // models below 90% of the configured real-time factor
  std::uint64_t failed = 0;     // simulations that failed and were restarted from rest, since start
};

class SimulationHost {
 public:
  explicit SimulationHost(SimulationHostOptions options);
  ~SimulationHost();
  SimulationHost(const SimulationHost&) = delete;
  SimulationHost& operator=(const SimulationHost&) = delete;

  // Whether its LCM opened (publishing needs a socket and a pipe: a process out of descriptors has
  // none); if not, open_error() says why and nothing is simulated.
  bool ok() const { return lcm_.good(); }
  const std::string& open_error() const { return open_error_; }

  // A new live revision. A model already simulated keeps its joint positions by name where the
  // joint still exists (hot reload).
  // `stepper`: the verdict's (ValidationSummary::live_stepper), which replaces the options' own
  // unless it is kAuto (not simulated when checked, or not checked).
  void load(const std::string& model_id, std::int64_t revision, const std::string& content_hash,
            const Robot& robot, Stepper stepper = Stepper::kAuto, bool after_quickstep_failed = false);
  void remove(const std::string& model_id);
  // A controller's command; rejected (reported on <prefix>/<model>/ERROR) when its revision or
  // content hash is not the live one or it names unknown joints. One with more joints than the
  // model loaded last (a joint a reload removed, a name repeated) is rejected as well, but not
  // queued: only its reason is, so a queued command costs at most that model's joints. Dropped
  // (the reason is returned, for the caller to count) when the queue is full or the model is not
  // simulated.
  std::string command(const rdtf::joint_command_t& command);

  std::size_t model_count() const;
  LiveTiming timing() const;

  // Commands waiting for the host thread beyond this are dropped (a flood of them).
  static constexpr std::size_t kMaxPendingCommands = 4096;
  // Entries a command may have beyond twice its model's joints and still be read entry by entry.
  static constexpr std::size_t kSpareCommandEntries = 16;
  // COMMAND_REJECTED reports a second, at most.
  static constexpr int kRejectionsPerSecond = 20;
  // SIMULATION_FAILED reports a second (all models), at most.
  static constexpr int kFailureReportsPerSecond = 5;

 private:
  struct Inbox {
    std::vector<std::pair<std::string, std::unique_ptr<LiveModel>>> loads;
    std::vector<std::string> removals;
    std::vector<rdtf::joint_command_t> commands;
    std::vector<std::pair<std::string, std::string>> rejections;  // (model id, why)
  };

  void run();
  void apply_inbox();
  // Restarts failed simulations from rest, with a report; measures how each model keeps time and
  // sets its step rate from the budget, once per window.
  void supervise(Clock::time_point now);
  // A failed simulation: counted, logged and reported (both rate-limited), its restart scheduled
  // after the back-off; then started again from rest.
  void report_failure(const std::string& model_id, LiveModel& model, Clock::time_point now);
  void restart(const std::string& model_id, LiveModel& model, Clock::time_point now);
  void publish_problem(const std::string& model_id, const LiveModel& model, const char* code, std::int8_t severity,
                       const std::string& text);
  void apply_command(const rdtf::joint_command_t& command, Clock::time_point now);
  void reject(const rdtf::joint_command_t& command, const std::string& why);
  // JOINT_STATE, then LINK_STATE with the same utime and sim_time.
  void publish_state(const std::string& model_id, LiveModel& model);
  void publish_links(const std::string& model_id, const LiveModel& model, const std::vector<LinkPose>& poses,
                     std::int64_t utime, double sim_time);

  SimulationHostOptions options_;
  lcm::LCM lcm_;
  std::string open_error_;
  mutable std::mutex mutex_;
  Inbox inbox_;
  std::map<std::string, Robot> pending_robots_;  // Under mutex_: robots of inbox_.loads.
  std::map<std::string, std::size_t> joint_counts_;  // Under mutex_: joints of each model loaded last.
  LiveModels models_;                                         // Owned by the host thread.
  std::size_t model_count_ = 0;                               // Under mutex_.
  LiveTiming timing_;                                         // Under mutex_.
  std::uint64_t dropped_commands_ = 0;                        // Under mutex_.
  std::uint64_t failures_ = 0;                                // Host thread.
  Clock::time_point window_start_{};                          // Host thread.
  Clock::time_point next_failure_log_{};                      // Host thread.
  ReportLimiter rejections_{kRejectionsPerSecond, "rejections"};     // Host thread.
  ReportLimiter failure_reports_{kFailureReportsPerSecond, "failures"};  // Host thread.
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace rdtf::daemon
