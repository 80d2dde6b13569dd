#include "pd_controller.h"

#include "counts.h"

namespace rdtf::controller {

void PdController::on_description(std::int64_t revision) { described_ = revision; }

void PdController::follow(const rdtf::joint_state_t& state) {
  // Targets by name: a given target, else the target this joint had in the previous revision
  // (hot reload keeps positions by name), else where the joint is now.
  std::map<std::string, double> targets;
  for (std::size_t i = 0; i < state.name.size(); ++i) {
    const std::string& joint = state.name[i];
    if (const auto given = options_.targets.find(joint); given != options_.targets.end()) {
      targets[joint] = given->second;
    } else if (const auto kept = active_targets_.find(joint); kept != active_targets_.end()) {
      targets[joint] = kept->second;
    } else {
      targets[joint] = state.position[i];
    }
  }
  unknown_targets_.clear();
  for (const auto& [joint, value] : options_.targets) {
    if (!targets.count(joint)) unknown_targets_[joint] = value;
  }
  active_targets_ = std::move(targets);
  revision_ = state.revision;
  content_hash_ = state.content_hash;
}

std::optional<rdtf::joint_command_t> PdController::on_state(const rdtf::joint_state_t& state) {
  if (state.model_id != options_.model_id) return std::nullopt;
  // The revision the bus described last is the model's, lower or not: a restarted rdtfd without
  // its state numbers from 1 again (docs/lcm.md). States of any other are in flight and stale.
  if (described_ != 0 && state.revision != described_) return std::nullopt;
  if (state.revision != revision_ || state.content_hash != content_hash_) follow(state);

  rdtf::joint_command_t command;
  command.utime = 0;  // Stamped when published.
  command.model_id = state.model_id;
  command.revision = state.revision;
  command.content_hash = state.content_hash;
  for (std::size_t i = 0; i < state.name.size(); ++i) {
    const double target = active_targets_.at(state.name[i]);
    command.name.push_back(state.name[i]);
    if (options_.mode == Mode::kPosition) {
      command.mode.push_back(rdtf::joint_command_t::POSITION);
      command.value.push_back(target);
      command.kp.push_back(options_.gains.kp);
      command.kd.push_back(options_.gains.kd);
    } else {
      command.mode.push_back(rdtf::joint_command_t::TORQUE);
      command.value.push_back(options_.gains.kp * (target - state.position[i]) -
                              options_.gains.kd * state.velocity[i]);
      command.kp.push_back(0);
      command.kd.push_back(0);
    }
  }
  set_counts(command);  // lcmtypes/counts.h
  return command;
}

}  // namespace rdtf::controller
