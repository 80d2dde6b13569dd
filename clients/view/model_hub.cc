#include "model_hub.h"

#include <chrono>
#include <set>

#include <nlohmann/json.hpp>
#include <urdf_parser/urdf_parser.h>

#include "counts.h"
#include "http_paths.h"

namespace rdtf::view {
namespace {

using Json = nlohmann::json;

// Strings from the bus may hold anything: invalid UTF-8 is replaced, never thrown on.
std::shared_ptr<const std::string> to_text(const Json& json) {
  return std::make_shared<const std::string>(json.dump(-1, ' ', false, Json::error_handler_t::replace));
}

std::int64_t now_utime() {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

const char* severity_name(std::int8_t severity) {
  switch (severity) {
    case rdtf::diagnostic_t::ERROR: return "error";
    case rdtf::diagnostic_t::WARNING: return "warning";
    default: return "info";
  }
}

Json diagnostics_json(const std::vector<rdtf::diagnostic_t>& diagnostics) {
  Json out = Json::array();
  for (const auto& d : diagnostics) {
    Json one = {{"severity", severity_name(d.severity)}, {"code", d.code}, {"file", d.file},
                {"pointer", d.pointer}, {"line", d.line}, {"message", d.message}};
    if (d.byte_offset >= 0) one["byte_offset"] = d.byte_offset;  // A GLB's container, where no pointer reaches.
    out.push_back(std::move(one));
  }
  return out;
}

// Errors that are not about a save: the live simulation's (a rejected command, a blow-up).
bool is_simulation_error(const rdtf::model_error_t& error) {
  if (error.diagnostics.empty()) return false;
  for (const auto& d : error.diagnostics) {
    if (d.code != "COMMAND_REJECTED" && d.code != "SIMULATION_FAILED") return false;
  }
  return true;
}

// A revision's glTF (its JSON text) up to this size rides in the model message itself, which
// spares the page a request before it can parse: the page's first step after a save. Larger ones
// are fetched (100 models' welcome stays well under a page's send queue limit either way).
constexpr std::size_t kInlineGltfBytes = 64 * 1024;

// The text when it can go into JSON as it is (UTF-8), else nothing (the page fetches it).
std::optional<std::string> inline_text(const std::shared_ptr<const std::string>& bytes) {
  if (!bytes || bytes->size() > kInlineGltfBytes) return std::nullopt;
  try {
    (void)Json(*bytes).dump();  // throws on invalid UTF-8
  } catch (const Json::exception&) {
    return std::nullopt;
  }
  return *bytes;
}

bool movable(const std::string& type) { return type == "revolute" || type == "continuous" || type == "prismatic"; }

}  // namespace

std::vector<JointInfo> joints_of_urdf(const std::string& urdf, std::string* error) {
  std::vector<JointInfo> out;
  if (urdf.empty()) {
    if (error) *error = "no URDF with this revision";
    return out;
  }
  const auto model = urdf::parseURDF(urdf);
  if (!model) {
    if (error) *error = "the URDF does not parse";
    return out;
  }
  // A urdfdom Link owns its children: freed from the root, a long chain would recurse once per link
  // (core/urdf/urdf_internal.h, FlatRelease). Each link is also held by the model's map.
  for (auto& [name, link] : model->links_) link->child_links.clear();
  for (const auto& [name, joint] : model->joints_) {
    JointInfo j;
    j.name = name;
    switch (joint->type) {
      case urdf::Joint::REVOLUTE: j.type = "revolute"; break;
      case urdf::Joint::CONTINUOUS: j.type = "continuous"; break;
      case urdf::Joint::PRISMATIC: j.type = "prismatic"; break;
      case urdf::Joint::FLOATING: j.type = "floating"; break;
      case urdf::Joint::PLANAR: j.type = "planar"; break;
      case urdf::Joint::FIXED: j.type = "fixed"; break;
      default: j.type = "unknown"; break;
    }
    j.parent = joint->parent_link_name;
    j.child = joint->child_link_name;
    j.axis[0] = joint->axis.x;
    j.axis[1] = joint->axis.y;
    j.axis[2] = joint->axis.z;
    if (joint->limits && (j.type == "revolute" || j.type == "prismatic")) {
      j.lower = joint->limits->lower;
      j.upper = joint->limits->upper;
    }
    j.moved_inertia = moved_inertia(*model, *joint);
    out.push_back(std::move(j));
  }
  return out;
}

Gains GainRule::of(const JointInfo& joint) const {
  Gains g = gains_for(joint.moved_inertia, frequency_hz);
  if (kp) g.kp = *kp;
  if (kd) g.kd = *kd;
  return g;
}

ModelHub::ModelHub(GainRule gains, Broadcast broadcast, PublishCommand publish, BroadcastState broadcast_state)
    : gains_(gains), broadcast_(std::move(broadcast)), broadcast_state_(std::move(broadcast_state)), publish_(std::move(publish)) {}

void ModelHub::on_revision(std::shared_ptr<const rdtf::client::Snapshot> snapshot) {
  const std::string id = snapshot->model_id();
  Model& m = models_[id];
  m.status = "live";
  m.error.reset();
  m.recent.push_front(snapshot);
  m.complete_utime = now_utime();
  while (m.recent.size() > 2) m.recent.pop_back();
  m.urdf_error.clear();
  m.joints = joints_of_urdf(snapshot->description.urdf, &m.urdf_error);
  for (auto& j : m.joints) j.gains = gains_.of(j);
  m.joint_state.reset();
  m.link_state.reset();
  // Targets are kept by name where the joint still moves within its limits (a hot reload keeps
  // positions by name); others are dropped.
  std::map<std::string, double> kept;
  for (const auto& j : m.joints) {
    const auto target = m.targets.find(j.name);
    if (target == m.targets.end() || !movable(j.type)) continue;
    if ((j.lower && target->second < *j.lower) || (j.upper && target->second > *j.upper)) continue;
    kept.insert(*target);
  }
  m.targets = std::move(kept);
  update_catalog(id);
  broadcast_(model_message(id, m));
  broadcast_(targets_message(id, m));
}

void ModelHub::on_error(const rdtf::model_error_t& error) {
  if (is_simulation_error(error)) {
    broadcast_(to_text({{"type", "notice"}, {"id", error.model_id}, {"diagnostics", diagnostics_json(error.diagnostics)}}));
    return;
  }
  Model& m = models_[error.model_id];
  m.status = "error";
  m.error = error;
  broadcast_(model_message(error.model_id, m));
}

void ModelHub::on_removed(const rdtf::model_removed_t& removed) {
  Model& m = models_[removed.model_id];
  m.status = "removed";
  m.recent.clear();
  m.joints.clear();
  m.targets.clear();
  m.error.reset();
  m.joint_state.reset();
  m.link_state.reset();
  update_catalog(removed.model_id);
  broadcast_(model_message(removed.model_id, m));
}

void ModelHub::on_saving(const rdtf::model_saving_t& saving) {
  // Only a save of the revision the pages draw: a page holds that model's motion frames until
  // the next one is drawn. rdtfd's settle_ms is 1 .. 60000 (docs/daemon.md); another value did
  // not come from it, and a page would hold them for as long.
  const auto model = models_.find(saving.model_id);
  if (model == models_.end() || model->second.recent.empty() ||
      model->second.recent.front()->revision() != saving.live_revision || saving.settle_ms < 0 ||
      saving.settle_ms > 60000) {
    return;
  }
  broadcast_(to_text({{"type", "saving"}, {"id", saving.model_id}, {"live_revision", saving.live_revision},
                      {"settle_ms", saving.settle_ms}}));
}

void ModelHub::on_models_seen(const std::set<std::string>& ids) {
  for (const auto& id : ids) {
    if (models_.count(id)) continue;
    broadcast_(model_message(id, models_[id]));
  }
}

void ModelHub::on_joint_state(const rdtf::client::Snapshot& snapshot, const rdtf::joint_state_t& state) {
  Model& m = models_[snapshot.model_id()];
  m.joint_state = state;
  m.states_changed = true;
  auto& entry = catalog_[snapshot.model_id()];
  if (!entry.simulated) {
    entry.simulated = true;
    // Only one-degree-of-freedom joints of the state take commands (its names are URDF names).
    std::map<std::string, MovableJoint> joints;
    for (const auto& name : state.name) {
      if (const auto found = entry.joints.find(name); found != entry.joints.end()) joints.insert(*found);
    }
    entry.joints = std::move(joints);
  }
  if (m.targets.empty()) return;
  rdtf::joint_command_t command;
  command.utime = now_utime();
  command.model_id = state.model_id;
  command.revision = state.revision;
  command.content_hash = state.content_hash;
  for (const auto& j : m.joints) {
    const auto target = m.targets.find(j.name);
    if (target == m.targets.end()) continue;
    command.name.push_back(j.name);
    command.mode.push_back(rdtf::joint_command_t::POSITION);
    command.value.push_back(target->second);
    command.kp.push_back(j.gains.kp);
    command.kd.push_back(j.gains.kd);
  }
  if (command.name.empty()) return;
  rdtf::set_counts(command);
  publish_(state.model_id, command);
}

void ModelHub::on_link_state(const rdtf::client::Snapshot& snapshot, const rdtf::link_state_t& state) {
  Model& m = models_[snapshot.model_id()];
  m.link_state = state;
  m.states_changed = true;
}

void ModelHub::flush_states() {
  for (auto& [id, m] : models_) {
    if (!m.states_changed) continue;
    m.states_changed = false;
    Json message = {{"type", "state"}, {"id", id}};
    if (m.link_state) {
      const auto& s = *m.link_state;
      Json position = Json::array();
      Json orientation = Json::array();
      for (std::size_t i = 0; i < s.name.size(); ++i) {
        position.push_back({s.position[i][0], s.position[i][1], s.position[i][2]});
        orientation.push_back({s.orientation[i][0], s.orientation[i][1], s.orientation[i][2], s.orientation[i][3]});
      }
      message["links"] = {{"revision", s.revision}, {"sim_time", s.sim_time}, {"names", s.name},
                          {"position", position}, {"orientation", orientation}};
    }
    if (m.joint_state) {
      const auto& s = *m.joint_state;
      message["joints"] = {{"revision", s.revision}, {"sim_time", s.sim_time}, {"names", s.name},
                           {"position", s.position}};
    }
    if (broadcast_state_) {
      broadcast_state_(id, to_text(message));
    } else {
      broadcast_(to_text(message));
    }
  }
}

std::string ModelHub::apply(const SetJoint& request) {
  const auto found = models_.find(request.model_id);
  if (found == models_.end() || found->second.status == "removed") return "unknown model";
  found->second.targets[request.joint] = request.value;
  broadcast_(targets_message(request.model_id, found->second));
  return "";
}

std::string ModelHub::apply(const Release& request) {
  const auto found = models_.find(request.model_id);
  if (found == models_.end()) return "unknown model";
  found->second.targets.clear();
  broadcast_(targets_message(request.model_id, found->second));
  return "";
}

std::vector<std::shared_ptr<const std::string>> ModelHub::welcome() const {
  std::vector<std::shared_ptr<const std::string>> out;
  Json ids = Json::array();
  for (const auto& [id, m] : models_) {
    out.push_back(model_message(id, m));
    if (!m.targets.empty()) out.push_back(targets_message(id, m));
    ids.push_back(id);
  }
  // Last, every model it knows: a page that outlived a restart of rdtf-view drops the others.
  out.push_back(to_text({{"type", "known"}, {"ids", std::move(ids)}}));
  return out;
}

std::shared_ptr<const std::string> ModelHub::file(const std::string& model_id, std::int64_t revision,
                                                  const std::string& path) const {
  const auto found = models_.find(model_id);
  if (found == models_.end()) return nullptr;
  for (const auto& snapshot : found->second.recent) {
    if (snapshot->revision() != revision) continue;
    for (const auto& f : snapshot->manifest) {
      if (f.path != path) continue;
      const auto blob = snapshot->blobs.find(f.sha256);
      return blob == snapshot->blobs.end() ? nullptr : blob->second;
    }
  }
  return nullptr;
}

void ModelHub::update_catalog(const std::string& id) {
  const Model& m = models_.at(id);
  if (m.recent.empty()) {
    catalog_.erase(id);
    return;
  }
  CommandableModel entry;
  entry.revision = m.recent.front()->revision();
  for (const auto& j : m.joints) {
    if (movable(j.type)) entry.joints[j.name] = MovableJoint{j.lower, j.upper};
  }
  catalog_[id] = std::move(entry);
}

std::shared_ptr<const std::string> ModelHub::targets_message(const std::string& id, const Model& model) const {
  return to_text({{"type", "targets"}, {"id", id}, {"targets", model.targets}});
}

std::shared_ptr<const std::string> ModelHub::model_message(const std::string& id, const Model& m) const {
  Json message = {{"type", "model"}, {"id", id}, {"status", m.status}};
  if (m.error) {
    message["error"] = {{"live_revision", m.error->live_revision}, {"content_hash", m.error->content_hash},
                        {"diagnostics", diagnostics_json(m.error->diagnostics)}};
  }
  if (m.recent.empty()) return to_text(message);
  const auto& s = *m.recent.front();
  const auto& d = s.description;
  message["revision"] = d.revision;
  message["content_hash"] = d.content_hash;
  message["validated"] = d.validated;
  message["validation_passed"] = d.validation_passed;
  // Where the time from a save to the page went (docs/view.md, "Timing"): rdtfd published the
  // DESCRIPTION, the snapshot came whole here; ms since the Unix epoch, the page's clock too.
  message["timing"] = {{"published_at", static_cast<double>(d.utime) / 1000.0},
                       {"complete_at", static_cast<double>(m.complete_utime) / 1000.0}};
  Json files = Json::array();
  for (const auto& f : s.manifest) {
    Json file = {{"path", f.path}, {"sha256", f.sha256}, {"size", f.size}, {"role", f.role},
                 {"url", model_file_url(id, d.revision, f.path)}};
    if (f.role == "rdtf") {
      const auto blob = s.blobs.find(f.sha256);
      if (auto text = inline_text(blob == s.blobs.end() ? nullptr : blob->second)) file["text"] = std::move(*text);
    }
    files.push_back(std::move(file));
  }
  message["files"] = files;
  for (const auto& f : s.manifest) {
    if (f.role == "rdtf") message["gltf"] = model_file_url(id, d.revision, f.path);
  }
  if (s.validation) {
    message["validation"] = {{"passed", s.validation->passed}, {"diagnostics", diagnostics_json(s.validation->diagnostics)}};
  }
  Json links = Json::array();
  for (const auto& l : s.inertia.links) {
    links.push_back({{"name", l.name}, {"gltf_name", l.gltf_name}, {"node", l.node}, {"mass", l.mass},
                     {"com", {l.center_of_mass[0], l.center_of_mass[1], l.center_of_mass[2]}},
                     {"inertia", {l.ixx, l.ixy, l.ixz, l.iyy, l.iyz, l.izz}}});
  }
  message["links"] = links;
  message["total_mass"] = s.inertia.total_mass;
  message["com_scene"] = {s.inertia.center_of_mass_scene[0], s.inertia.center_of_mass_scene[1],
                          s.inertia.center_of_mass_scene[2]};
  Json joints = Json::array();
  for (const auto& j : m.joints) {
    Json joint = {{"name", j.name}, {"type", j.type}, {"parent", j.parent}, {"child", j.child},
                  {"axis", {j.axis[0], j.axis[1], j.axis[2]}}};
    joint["moved_inertia"] = j.moved_inertia;
    joint["kp"] = j.gains.kp;
    joint["kd"] = j.gains.kd;
    joint["lower"] = j.lower ? Json(*j.lower) : Json(nullptr);
    joint["upper"] = j.upper ? Json(*j.upper) : Json(nullptr);
    joints.push_back(joint);
  }
  message["joints"] = joints;
  if (!m.urdf_error.empty()) message["joints_note"] = m.urdf_error;
  return to_text(message);
}

}  // namespace rdtf::view
