// The example controller's loop, without LCM: one joint state in, one joint command out.
//
//   state (revision r, hash h, q, qdot) --> targets q* for every joint --> command stamped (r, h)
//
// Targets: the joints given on the command line get their value; every other joint holds the
// position it had in the first state of its revision that this controller saw ("hold the first
// state"). A hot reload (a new revision) keeps the targets of joints that still exist, drops
// those that vanished and holds new joints where they are. Each command answers the state it was
// computed from, so it carries that state's revision and content hash: the daemon rejects a
// command for any other revision, so a controller can never drive a model it has not seen.
//
// Two modes (docs/controller.md explains the choice):
//   kPosition (default): the command sends q* with the gains; rdtfd applies
//     tau = kp (q* - q) - kd qdot at every 1 ms physics step, from the current state.
//   kTorque: this controller computes tau = kp (q* - q) - kd qdot from the state it received and
//     rdtfd holds that torque until the next command: a loop closed over LCM at the state rate,
//     delayed by a state period or more, so only soft gains are stable.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include <rdtf/joint_command_t.hpp>
#include <rdtf/joint_state_t.hpp>

namespace rdtf::controller {

enum class Mode { kPosition, kTorque };

struct PdGains {
  double kp = 200;  // N m/rad (N/m)
  double kd = 10;   // N m s/rad (N s/m)
};

struct PdOptions {
  std::string model_id;
  std::map<std::string, double> targets;  // rad or m, by joint name; others hold their first state
  PdGains gains;
  Mode mode = Mode::kPosition;
};

class PdController {
 public:
  explicit PdController(PdOptions options) : options_(std::move(options)) {}

  // A complete revision from the client library (its newest described): states of any other
  // revision are in flight and are no longer answered.
  void on_description(std::int64_t revision);

  // The command that answers `state`, or nothing (another model, or an outdated revision).
  std::optional<rdtf::joint_command_t> on_state(const rdtf::joint_state_t& state);

  std::int64_t revision() const { return revision_; }
  // The targets of the revision followed (after its first state).
  const std::map<std::string, double>& targets() const { return active_targets_; }
  // Names given with --target that the followed revision does not have.
  const std::map<std::string, double>& unknown_targets() const { return unknown_targets_; }

 private:
  void follow(const rdtf::joint_state_t& state);

  PdOptions options_;
  std::int64_t described_ = 0;
  std::int64_t revision_ = 0;
  std::string content_hash_;
  std::map<std::string, double> active_targets_;
  std::map<std::string, double> unknown_targets_;
};

}  // namespace rdtf::controller
