// Live simulation of every live model on one thread of its own: steps each model's ODE world in
// real time, publishes joint states (and answers nothing else), and applies controllers'
// commands. The event loop hands it models and commands through a mutex-guarded inbox, so the
// loop never waits for physics and physics never waits for files.
#pragma once

#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include <rdtf/joint_command_t.hpp>

#include "rdtf/dynamics.h"

namespace rdtf::daemon {

struct SimulationHostOptions {
  std::string lcm_url;
  std::string channel_prefix = "RDTF";
  SimulationOptions simulation;
  double state_rate_hz = 100;      // Joint-state messages per second and model.
  double real_time_factor = 1.0;   // Simulated seconds per wall-clock second.
};

class SimulationHost {
 public:
  explicit SimulationHost(SimulationHostOptions options);
  ~SimulationHost();
  SimulationHost(const SimulationHost&) = delete;
  SimulationHost& operator=(const SimulationHost&) = delete;

  bool ok() const { return lcm_.good(); }

  // A new live revision. A model already simulated keeps its joint positions by name where the
  // joint still exists (hot reload).
  void load(const std::string& model_id, std::int64_t revision, const std::string& content_hash,
            const Robot& robot);
  void remove(const std::string& model_id);
  // A controller's command; rejected (reported on <prefix>/<model>/ERROR) when its revision or
  // content hash is not the live one or it names unknown joints.
  void command(const rdtf::joint_command_t& command);

  std::size_t model_count() const;

 private:
  struct LiveModel {
    std::int64_t revision = 0;
    std::string content_hash;
    std::unique_ptr<Simulation> simulation;
    std::chrono::steady_clock::time_point next_state{};
  };
  struct Inbox {
    std::vector<std::pair<std::string, std::unique_ptr<LiveModel>>> loads;
    std::vector<std::string> removals;
    std::vector<rdtf::joint_command_t> commands;
  };

  void run();
  void apply_inbox();
  void apply_command(const rdtf::joint_command_t& command);
  void reject(const rdtf::joint_command_t& command, const std::string& why);
  void publish_state(const std::string& model_id, LiveModel& model);

  SimulationHostOptions options_;
  lcm::LCM lcm_;
  mutable std::mutex mutex_;
  Inbox inbox_;
  std::map<std::string, Robot> pending_robots_;  // Under mutex_: robots of inbox_.loads.
  std::map<std::string, std::unique_ptr<LiveModel>> models_;  // Owned by the host thread.
  std::size_t model_count_ = 0;                               // Under mutex_.
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace rdtf::daemon
