// rdtf-view's picture of the bus: every model the client library reports, in the JSON the page
// draws from, the files of its recent revisions, and the joint targets pages set.
//
// Fed by rdtf_client's callbacks (on the thread that dispatches LCM; the hub has no thread and is
// not thread-safe). It turns what it hears into page messages (JSON text, docs/view.md "Page
// protocol") handed to `broadcast`, and answers each JOINT_STATE of a model that has targets with
// one JOINT_COMMAND (POSITION mode, each joint's gains: GainRule) stamped with that state's revision and hash,
// as rdtf-pd-controller does: a command lives joint_command_timeout_s in rdtfd, so it is renewed
// with every state while a target is held.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <rdtf/joint_command_t.hpp>
#include <rdtf/joint_state_t.hpp>
#include <rdtf/link_state_t.hpp>

#include "joint_gains.h"
#include "page_protocol.h"
#include "rdtf/client.h"

namespace rdtf::view {

// A joint as the page needs it: from the revision's URDF (names are URDF names).
struct JointInfo {
  std::string name, type, parent, child;
  double axis[3] = {1, 0, 0};
  std::optional<double> lower, upper;
  double moved_inertia = 0;  // kg m^2 (kg for a prismatic joint): joint_gains.h
  Gains gains;               // of the slider's commands (set by the hub's GainRule)
};

// The joints of a URDF text; empty with `error` set when it does not parse.
std::vector<JointInfo> joints_of_urdf(const std::string& urdf, std::string* error);

// How the hub picks each joint's gains: the rule of joint_gains.h at `frequency_hz`, or the same
// kp and/or kd for every joint when given.
struct GainRule {
  double frequency_hz = 4;
  std::optional<double> kp, kd;
  Gains of(const JointInfo& joint) const;
};

class ModelHub {
 public:
  using Broadcast = std::function<void(std::shared_ptr<const std::string> json)>;
  using PublishCommand = std::function<void(const std::string& model_id, rdtf::joint_command_t& command)>;
  // A model's state message (a newer one of the same model may replace it before it is sent).
  using BroadcastState = std::function<void(const std::string& model_id, std::shared_ptr<const std::string> json)>;

  // Without `broadcast_state`, states go through `broadcast`.
  ModelHub(GainRule gains, Broadcast broadcast, PublishCommand publish, BroadcastState broadcast_state = nullptr);

  // rdtf_client's callbacks.
  void on_revision(std::shared_ptr<const rdtf::client::Snapshot> snapshot);
  void on_error(const rdtf::model_error_t& error);
  void on_removed(const rdtf::model_removed_t& removed);
  // SAVING: told to the pages as it is (`saving`) when it names the revision they draw.
  void on_saving(const rdtf::model_saving_t& saving);
  void on_joint_state(const rdtf::client::Snapshot& snapshot, const rdtf::joint_state_t& state);
  void on_link_state(const rdtf::client::Snapshot& snapshot, const rdtf::link_state_t& state);
  // Model ids heard (rdtfd's STATUS) that have no entry yet are listed as pending.
  void on_models_seen(const std::set<std::string>& ids);

  // Everything a page that just connected needs, one message per model.
  std::vector<std::shared_ptr<const std::string>> welcome() const;
  // The state messages of models whose states changed since the last call (at most one per
  // model: the newest), so a page gets at most one per model and flush, however fast rdtfd sends.
  void flush_states();

  // A page's request, already parsed. Returns the refusal reason, or "" when done.
  std::string apply(const SetJoint& request);
  std::string apply(const Release& request);
  // What pages may command now.
  const Catalog& catalog() const { return catalog_; }

  // The bytes of a file of one of a model's recent revisions (the live one and the one before,
  // so a page still loading the previous revision gets it), or nullptr.
  std::shared_ptr<const std::string> file(const std::string& model_id, std::int64_t revision,
                                          const std::string& path) const;

  std::size_t model_count() const { return models_.size(); }

 private:
  struct Model {
    std::string status = "pending";  // pending, live, error, removed
    std::deque<std::shared_ptr<const rdtf::client::Snapshot>> recent;  // newest first, at most 2
    std::int64_t complete_utime = 0;  // when the newest snapshot came whole (its blobs fetched)
    std::vector<JointInfo> joints;
    std::string urdf_error;
    std::optional<rdtf::model_error_t> error;  // the last rejected save since the live revision
    std::map<std::string, double> targets;
    std::optional<rdtf::joint_state_t> joint_state;
    std::optional<rdtf::link_state_t> link_state;
    bool states_changed = false;
  };

  std::shared_ptr<const std::string> model_message(const std::string& id, const Model& model) const;
  std::shared_ptr<const std::string> targets_message(const std::string& id, const Model& model) const;
  void update_catalog(const std::string& id);

  GainRule gains_;
  Broadcast broadcast_;
  BroadcastState broadcast_state_;
  PublishCommand publish_;
  std::map<std::string, Model> models_;
  Catalog catalog_;
};

}  // namespace rdtf::view
