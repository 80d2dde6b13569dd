#include "simulation_host.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <rdtf/joint_state_t.hpp>
#include <rdtf/link_state_t.hpp>
#include <rdtf/model_error_t.hpp>

#include "counts.h"
#include "diagnostic_message.h"
#include "daemon.h"
#include "messages.h"
#include "safe_decode.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::daemon {

StepClock::StepClock(double time_step, double real_time_factor, Clock::time_point start)
    : tick_(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(time_step / real_time_factor))),
      next_(start) {}

int StepClock::take_due(Clock::time_point now) {
  int steps = 0;
  for (; next_ <= now && steps < kMaxCatchUp; ++steps) next_ += tick_;
  if (next_ <= now) next_ = now;
  return steps;
}

bool StateSchedule::after_step() {
  ++steps_;
  // Simulated time as a product, not a running sum, and compared half a step early: the state goes
  // out after the step nearest to its time, whatever the rounding.
  const double t = static_cast<double>(steps_) * time_step_ + 0.5 * time_step_;
  if (t < static_cast<double>(next_) * period_) return false;
  // The next state after this one; when states are due faster than steps, one per step.
  next_ = static_cast<std::uint64_t>(std::floor(t / period_)) + 1;
  return true;
}

void advance_live_models(StepClock& clock, LiveModels& models, Clock::time_point now, double time_step,
                         const std::function<void(const std::string&, LiveModel&)>& publish) {
  for (auto& [id, model] : models) {
    if (!model->failed && model->simulation) release_expired_commands(*model, now);
  }
  // Each model's state is published right after the step it belongs to. Checked once per wake-up
  // against the wall clock instead (as before), a wake-up late by a step or more (common on a
  // loaded machine) sent one state for all the steps it took, and the schedule's restart put the
  // following states behind any wake-up that came earlier in its millisecond: 90 to 99.7% of the
  // states at 1 kHz with 20 models on a machine with load 6 (bench/live_sim_bench.cc).
  for (int due = clock.take_due(now); due > 0; --due) {
    for (auto& [id, model] : models) {
      if (model->failed) continue;
      model->credit += model->rate;
      if (model->credit < 1) continue;
      model->credit -= 1;
      const double before = model->simulation->time();
      const auto start = Clock::now();
      model->simulation->step(time_step);
      const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
      model->step_seconds = model->step_seconds == 0 ? seconds : 0.95 * model->step_seconds + 0.05 * seconds;
      // Simulation::step does nothing once ODE's state is non-finite or beyond its bound.
      if (!(model->simulation->time() > before)) {
        model->failed = true;
        continue;
      }
      if (model->states->after_step()) publish(id, *model);
    }
  }
}

std::vector<std::string> timing_change_lines(const std::vector<TimingChange>& changes, const char* what,
                                             double wanted) {
  constexpr std::size_t kLinesEach = 3;
  std::vector<std::string> lines;
  if (changes.size() <= kLinesEach) {
    for (const TimingChange& change : changes) lines.push_back(change.line);
    return lines;
  }
  double low = changes.front().factor, high = low;
  std::string names;
  for (std::size_t i = 0; i < changes.size(); ++i) {
    low = std::min(low, changes[i].factor);
    high = std::max(high, changes[i].factor);
    if (i < kLinesEach) names += (i ? ", " : "") + changes[i].id;
  }
  char text[256];
  std::snprintf(text, sizeof(text),
                " and %zu more): %.3g to %.3g simulated s per wall s of %.3g wanted (all at once: the machine's "
                "load, not one model's cost)",
                changes.size() - kLinesEach, low, high, wanted);
  lines.push_back("live simulations of " + std::to_string(changes.size()) + " models " + what + " (" + names + text);
  return lines;
}

std::vector<double> budget_step_rates(const std::vector<double>& step_seconds, double budget_seconds) {
  std::vector<double> rates(step_seconds.size(), 1.0);
  std::vector<std::size_t> order(step_seconds.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return step_seconds[a] < step_seconds[b]; });
  double left = std::max(budget_seconds, 0.0);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const double share = left / static_cast<double>(order.size() - k);
    const double cost = step_seconds[order[k]];
    if (cost <= share) {
      left -= cost;
      continue;
    }
    rates[order[k]] = share / cost;
    left -= share;
  }
  return rates;
}

SimulationHost::SimulationHost(SimulationHostOptions options)
    : options_(std::move(options)), lcm_(options_.lcm_url) {
  if (!lcm_.good()) {
    // Not errno: LCM's clean-up has replaced it. LCM printed the failing call and why.
    open_error_ = "cannot open LCM at " +
                  (options_.lcm_url.empty() ? std::string("LCM's default URL") : "'" + options_.lcm_url + "'") +
                  " (LCM's message above says why)";
    return;  // No thread: a host that cannot publish steps nothing.
  }
  thread_ = std::thread([this] { run(); });
}

SimulationHost::~SimulationHost() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void SimulationHost::load(const std::string& model_id, std::int64_t revision,
                          const std::string& content_hash, const Robot& robot, Stepper stepper,
                          bool after_quickstep_failed) {
  // The ODE world is built on the host thread (ODE keeps per-thread data); here only the inputs.
  auto model = std::make_unique<LiveModel>();
  model->revision = revision;
  model->content_hash = content_hash;
  model->command_lifetime = options_.joint_command_lifetime;
  model->options = options_.simulation;
  // Simulated as it was judged: the check saw the model hold under the verdict's stepper, and may
  // not have under the settings' (a reload that forces quick_step keeps a revision judged under
  // dWorldStep live when its new check fails).
  if (stepper != Stepper::kAuto) model->options.stepper = stepper;
  model->after_quickstep_failed = after_quickstep_failed;
  Robot renamed = with_urdf_names(robot, model->names);
  std::lock_guard lock(mutex_);
  joint_counts_[model_id] = robot.joints.size();
  pending_robots_[model_id] = std::move(renamed);
  inbox_.loads.emplace_back(model_id, std::move(model));
}

void SimulationHost::remove(const std::string& model_id) {
  std::lock_guard lock(mutex_);
  joint_counts_.erase(model_id);
  inbox_.removals.push_back(model_id);
}

std::string SimulationHost::command(const rdtf::joint_command_t& command) {
  std::lock_guard lock(mutex_);
  const auto joints = joint_counts_.find(command.model_id);
  if (joints == joint_counts_.end()) {
    ++dropped_commands_;
    return "joint_command_t for model '" + lcm_safe::printable(command.model_id, 80) + "', which is not simulated";
  }
  if (inbox_.commands.size() + inbox_.rejections.size() >= kMaxPendingCommands) {
    ++dropped_commands_;
    return "joint_command_t dropped: " + std::to_string(kMaxPendingCommands) + " commands already wait";
  }
  // The queue's bound by count bounds its bytes only if each command's size is bounded by its
  // model's: beyond twice its joints and a few, a command is not queued, but rejected on ERROR all
  // the same (a controller must hear why its robot went passive). Below that, the simulation
  // thread names what is wrong: the joint named twice, the joint a reload removed (s90ctrl D6:
  // a count above the model's hid both).
  const std::size_t count = joints->second;
  if (command.num_joints < 0 || static_cast<std::size_t>(command.num_joints) > 2 * count + kSpareCommandEntries) {
    inbox_.rejections.emplace_back(
        command.model_id, "command names " + std::to_string(command.num_joints) + " joints, but the model has " +
                              std::to_string(count) + " joint" + (count == 1 ? "" : "s") + ": send one entry per joint");
    return "";
  }
  inbox_.commands.push_back(command);
  return "";
}

LiveTiming SimulationHost::timing() const {
  std::lock_guard lock(mutex_);
  return timing_;
}

std::size_t SimulationHost::model_count() const {
  std::lock_guard lock(mutex_);
  return model_count_;
}

void SimulationHost::apply_inbox() {
  Inbox inbox;
  std::map<std::string, Robot> robots;
  {
    std::lock_guard lock(mutex_);
    std::swap(inbox, inbox_);
    robots.swap(pending_robots_);
  }
  for (const std::string& id : inbox.removals) models_.erase(id);
  // Only the newest load of a model counts; its robot is the one in `robots`.
  std::map<std::string, std::unique_ptr<LiveModel>> loads;
  for (auto& [id, model] : inbox.loads) loads[id] = std::move(model);
  for (auto& [id, model] : loads) {
    const auto robot = robots.find(id);
    if (robot == robots.end()) continue;
    // Hot reload: keep every joint position whose joint still exists.
    std::map<std::string, double> positions;
    if (const auto old = models_.find(id); old != models_.end() && old->second->simulation) {
      for (const JointState& state : old->second->simulation->joint_states()) {
        positions[state.name] = state.position;
      }
    }
    Diagnostics diag;
    model->simulation = Simulation::create(robot->second, model->options, positions, diag);
    model->states.emplace(options_.real_time_factor / options_.state_rate_hz, options_.simulation.time_step);
    if (!model->simulation) {
      log_line("simulation of " + id + " revision " + std::to_string(model->revision) +
               " not started: " + (diag.all().empty() ? std::string("unknown reason") : format(diag.all().front())));
      models_.erase(id);
      continue;
    }
    if (model->after_quickstep_failed) {
      log_line("simulation of " + id + " revision " + std::to_string(model->revision) + " steps with " +
               std::string(model->simulation->stepper_name()) +
               ", the stepper its dynamics check passed it with (SIM_QUICKSTEP_FAILED)");
    }
    model->robot = std::make_shared<const Robot>(robot->second);
    models_[id] = std::move(model);
  }
  const auto now = Clock::now();
  for (const auto& command : inbox.commands) apply_command(command, now);
  for (const auto& [model_id, why] : inbox.rejections) {
    rdtf::joint_command_t stub;
    stub.model_id = model_id;
    reject(stub, why);
  }
  std::lock_guard lock(mutex_);
  model_count_ = models_.size();
  if (models_.empty()) timing_ = LiveTiming{0, 0, failures_};
}

void SimulationHost::reject(const rdtf::joint_command_t& command, const std::string& why) {
  const auto admitted = rejections_.admit(why, Clock::now());
  if (!admitted) return;
  const std::string& text = *admitted;
  rdtf::model_error_t message;
  message.utime = now_utime();
  message.model_id = command.model_id;
  const auto live = models_.find(command.model_id);
  message.live_revision = live == models_.end() ? 0 : live->second->revision;
  // The live model's hash, never the bus's (which may be megabytes of anything).
  message.content_hash = live == models_.end() ? std::string() : live->second->content_hash;
  const rdtf::diagnostic_t d = to_message(Severity::kError, codes::COMMAND_REJECTED, text);
  message.diagnostics.push_back(d);
  rdtf::publish(lcm_, options_.channel_prefix + "/" + command.model_id + "/ERROR", message);
}

void SimulationHost::apply_command(const rdtf::joint_command_t& command, Clock::time_point now) {
  const auto found = models_.find(command.model_id);
  if (found == models_.end()) {
    return reject(command, "no live simulation of model '" + lcm_safe::printable(command.model_id, 80) + "'");
  }
  if (const std::string why = command_live_model(*found->second, command, now); !why.empty()) reject(command, why);
}

std::string command_live_model(LiveModel& model, const rdtf::joint_command_t& command, Clock::time_point now) {
  if (command.revision != model.revision) {
    return "command for revision " + std::to_string(command.revision) + " but revision " +
           std::to_string(model.revision) + " is live";
  }
  if (command.content_hash != model.content_hash) {
    return "command for content hash '" + lcm_safe::printable(command.content_hash, 80) + "' but revision " +
           std::to_string(model.revision) + " has content hash '" + model.content_hash + "'";
  }
  std::vector<JointCommand> commands;
  if (std::string why = joint_commands_of(command, model.names, *model.simulation, commands); !why.empty()) {
    return why;
  }
  for (const JointCommand& c : commands) {
    std::string error;
    if (!model.simulation->set_command(c, &error)) return error;
    model.command_expiry[c.joint] = now + model.command_lifetime;
  }
  return "";
}

void release_expired_commands(LiveModel& model, Clock::time_point now) {
  for (auto it = model.command_expiry.begin(); it != model.command_expiry.end();) {
    if (now < it->second) {
      ++it;
      continue;
    }
    model.simulation->clear_command(it->first);
    it = model.command_expiry.erase(it);
  }
}

std::optional<std::string> ReportLimiter::admit(const std::string& text, Clock::time_point now) {
  if (now - window_ >= std::chrono::seconds(1)) {
    window_ = now;
    in_window_ = 0;
  }
  if (++in_window_ > per_second_) {
    ++unreported_;
    return std::nullopt;
  }
  if (unreported_ == 0) return text;
  std::string out = text + " (and " + std::to_string(unreported_) + " earlier " + what_ +
                    " not reported: over " + std::to_string(per_second_) + " a second)";
  unreported_ = 0;
  return out;
}

Clock::duration restart_delay(int n) {
  Clock::duration delay = kFirstRestartDelay;
  for (int k = 1; k < n && delay < kMaxRestartDelay; ++k) delay *= 2;
  return std::min<Clock::duration>(delay, kMaxRestartDelay);
}

void SimulationHost::publish_state(const std::string& model_id, LiveModel& model) {
  // Both messages of the pair are checked before either goes out: a state that is non-finite,
  // or finite but beyond what ODE may step (an explosion, e.g. 1e117 rad/s), is published in
  // neither; the simulation has failed and is restarted.
  const auto joints = model.simulation->joint_states();
  const auto poses = model.simulation->link_poses();
  bool finite = model.simulation->steppable();
  for (const JointState& state : joints) {
    finite = finite && std::isfinite(state.position) && std::isfinite(state.velocity) && std::isfinite(state.effort);
  }
  for (const LinkPose& pose : poses) {
    finite = finite && pose.X_SL.matrix().allFinite() && pose.v_SLo_S.allFinite() && pose.w_SL_S.allFinite();
  }
  if (!finite) {
    model.failed = true;
    return;
  }
  rdtf::joint_state_t message;
  message.utime = now_utime();
  message.model_id = model_id;
  message.revision = model.revision;
  message.content_hash = model.content_hash;
  message.sim_time = model.sim_time();
  for (const JointState& state : joints) {
    message.name.push_back(state.name);
    const auto gltf = model.names.joint_gltf.find(state.name);
    message.gltf_name.push_back(gltf == model.names.joint_gltf.end() ? state.name : gltf->second);
    message.position.push_back(state.position);
    message.velocity.push_back(state.velocity);
    message.effort.push_back(state.effort);
  }
  rdtf::publish(lcm_, options_.channel_prefix + "/" + model_id + "/JOINT_STATE", message);
  publish_links(model_id, model, poses, message.utime, message.sim_time);
}

void SimulationHost::publish_links(const std::string& model_id, const LiveModel& model,
                                   const std::vector<LinkPose>& poses, std::int64_t utime, double sim_time) {
  rdtf::link_state_t message;
  // The joint state's stamp and simulated time, so that a subscriber pairs the two exactly.
  message.utime = utime;
  message.model_id = model_id;
  message.revision = model.revision;
  message.content_hash = model.content_hash;
  message.sim_time = sim_time;
  for (std::size_t l = 0; l < poses.size(); ++l) {
    const LinkPose& pose = poses[l];
    message.name.push_back(pose.name);
    message.gltf_name.push_back(l < model.names.link_gltf.size() ? model.names.link_gltf[l] : pose.name);
    const Eigen::Vector3d p = pose.X_SL.translation();
    // The rotation comes out of ODE's bodies as a matrix; renormalised so that subscribers get a
    // unit quaternion whatever the rounding of the conversion.
    const Eigen::Quaterniond q = Eigen::Quaterniond(pose.X_SL.linear()).normalized();
    message.position.push_back({p.x(), p.y(), p.z()});
    message.orientation.push_back({q.w(), q.x(), q.y(), q.z()});
    message.linear_velocity.push_back({pose.v_SLo_S.x(), pose.v_SLo_S.y(), pose.v_SLo_S.z()});
    message.angular_velocity.push_back({pose.w_SL_S.x(), pose.w_SL_S.y(), pose.w_SL_S.z()});
  }
  rdtf::publish(lcm_, options_.channel_prefix + "/" + model_id + "/LINK_STATE", message);
}

void SimulationHost::publish_problem(const std::string& model_id, const LiveModel& model, const char* code,
                                     std::int8_t severity, const std::string& text) {
  rdtf::model_error_t message;
  message.utime = now_utime();
  message.model_id = model_id;
  message.live_revision = model.revision;
  message.content_hash = model.content_hash;
  rdtf::diagnostic_t d = to_message(Severity::kError, code, text);
  d.severity = severity;
  message.diagnostics.push_back(d);
  rdtf::publish(lcm_, options_.channel_prefix + "/" + model_id + "/ERROR", message);
}

void SimulationHost::report_failure(const std::string& model_id, LiveModel& model, Clock::time_point now) {
  ++failures_;
  // Back-off: a sender that makes it fail again and again gets ever fewer restarts, and so ever
  // fewer reports, instead of one per restart at the step rate.
  model.failure_streak = now - model.running_since >= kFailureStreakReset ? 1 : model.failure_streak + 1;
  const auto delay = restart_delay(model.failure_streak);
  model.restart_at = now + delay;
  std::string why = "its state became non-finite or blew up";
  if (!model.simulation->ode_messages().empty()) why += " (" + model.simulation->ode_messages().back() + ")";
  const std::string text =
      "live simulation of " + model_id + " revision " + std::to_string(model.revision) + " failed at t = " +
      std::to_string(model.sim_time()) + " s: " + why + "; restarts from the rest pose in " +
      std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(delay).count()) + " ms (failure " +
      std::to_string(model.failure_streak) + " in a row), commands cleared";
  // One log line a second, not one per failure.
  if (now >= next_failure_log_) {
    next_failure_log_ = now + std::chrono::seconds(1);
    log_line(text + " (" + std::to_string(failures_) + " failures since start)");
  }
  if (const auto admitted = failure_reports_.admit(text, now)) {
    publish_problem(model_id, model, codes::SIMULATION_FAILED, rdtf::diagnostic_t::ERROR, *admitted);
  }
}

void SimulationHost::restart(const std::string& model_id, LiveModel& model, Clock::time_point now) {
  Diagnostics diag;
  // Simulated time goes on from where it was, so that subscribers see it keep advancing.
  const double offset = model.sim_time();
  auto fresh = Simulation::create(*model.robot, model.options, {}, diag);
  if (!fresh) {
    log_line("simulation of " + model_id + " could not be started again: " +
             (diag.all().empty() ? std::string("unknown reason") : format(diag.all().front())));
    model.simulation.reset();
    return;
  }
  model.simulation = std::move(fresh);
  model.command_expiry.clear();  // The fresh simulation holds no command.
  model.time_offset = offset;
  model.failed = false;
  model.restart_at = {};
  model.running_since = now;
}

void SimulationHost::supervise(Clock::time_point now) {
  for (auto it = models_.begin(); it != models_.end();) {
    LiveModel& model = *it->second;
    if (model.failed && model.restart_at == Clock::time_point{}) report_failure(it->first, model, now);
    if (model.failed && now >= model.restart_at) restart(it->first, model, now);
    if (!it->second->simulation) {
      it = models_.erase(it);
    } else {
      ++it;
    }
  }
  // Once per window: how each model kept time, and its step rate for the next window.
  constexpr auto kWindow = std::chrono::milliseconds(500);
  if (window_start_ == Clock::time_point{}) window_start_ = now;
  const double wall = std::chrono::duration<double>(now - window_start_).count();
  if (now - window_start_ < kWindow) return;
  window_start_ = now;
  const double tick = options_.simulation.time_step / options_.real_time_factor;
  std::vector<double> costs;
  LiveTiming timing;
  timing.failed = failures_;
  bool first = true;
  std::vector<TimingChange> went_behind, caught_up;
  for (auto& [id, model] : models_) {
    costs.push_back(model->step_seconds);
    if (model->failed) {  // Waiting for its restart: not behind, measured again after it.
      model->measured = false;
      continue;
    }
    if (!model->measured) {  // Loaded during this window: measured from the next one on.
      model->measured = true;
      model->window_start_time = model->sim_time();
      continue;
    }
    const double simulated = model->sim_time() - model->window_start_time;
    model->window_start_time = model->sim_time();
    const double factor = simulated / wall;
    timing.real_time_factor = first ? factor : std::min(timing.real_time_factor, factor);
    first = false;
    const bool behind = factor < 0.9 * options_.real_time_factor;
    if (behind) ++timing.behind;
    if (behind != model->behind) {
      model->behind = behind;
      char text[256];
      std::snprintf(text, sizeof(text),
                    behind ? "live simulation of %s is behind: %.3g simulated s per wall s of %.3g wanted "
                             "(one step %.3g ms; its share of the CPU budget %.0f%% of the steps)"
                           : "live simulation of %s keeps time again: %.3g simulated s per wall s of %.3g wanted "
                             "(one step %.3g ms; %.0f%% of the steps)",
                    id.c_str(), factor, options_.real_time_factor, model->step_seconds * 1e3, model->rate * 100);
      (behind ? went_behind : caught_up).push_back({id, factor, text});
    }
  }
  for (const std::string& line : timing_change_lines(went_behind, "are behind", options_.real_time_factor)) log_line(line);
  for (const std::string& line : timing_change_lines(caught_up, "keep time again", options_.real_time_factor)) {
    log_line(line);
  }
  // 80% of the thread's time for stepping; the rest publishes and sleeps.
  const auto rates = budget_step_rates(costs, 0.8 * tick);
  std::size_t k = 0;
  for (auto& [id, model] : models_) model->rate = rates[k++];
  std::lock_guard lock(mutex_);
  timing_ = timing;
}

void SimulationHost::run() {
  init_ode();
  const double dt = options_.simulation.time_step;
  StepClock clock(dt, options_.real_time_factor, Clock::now());
  const auto publish = [this](const std::string& id, LiveModel& model) { publish_state(id, model); };
  while (!stop_) {
    apply_inbox();
    const auto now = Clock::now();
    if (models_.empty()) {
      clock.restart(now + std::chrono::milliseconds(20));
      std::this_thread::sleep_until(clock.next_due());
      continue;
    }
    advance_live_models(clock, models_, now, dt, publish);
    supervise(Clock::now());
    std::this_thread::sleep_until(clock.next_due());
  }
}

}  // namespace rdtf::daemon
