#include "message_json.h"

#include <functional>
#include <map>

#include <rdtf/blob_chunk_t.hpp>
#include <rdtf/blob_request_t.hpp>
#include <rdtf/blob_unavailable_t.hpp>
#include <rdtf/delta_t.hpp>
#include <rdtf/description_chunk_t.hpp>
#include <rdtf/description_t.hpp>
#include <rdtf/inertia_table_t.hpp>
#include <rdtf/joint_command_t.hpp>
#include <rdtf/joint_state_t.hpp>
#include <rdtf/link_state_t.hpp>
#include <rdtf/manifest_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/model_removed_t.hpp>
#include <rdtf/model_saving_t.hpp>
#include <rdtf/request_t.hpp>
#include <rdtf/status_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "diagnostic_message.h"
#include "rdtf/diagnostics_json.h"
#include "safe_decode.h"

namespace rdtf::clients {
namespace {

using Json = nlohmann::ordered_json;

// The core library's JSON of a diagnostic, the same as `rdtf inspect --json` prints.
Json to_json(const rdtf::diagnostic_t& m) { return rdtf::diagnostic_json(rdtf::from_message(m)); }

Json header(const char* type, std::int64_t utime, const std::string& model_id) {
  return {{"type", type}, {"utime", utime}, {"model_id", model_id}};
}

Json to_json(const rdtf::description_t& m) {
  Json j = header("rdtf.description_t", m.utime, m.model_id);
  j.update({{"source_path", m.source_path}, {"revision", m.revision},
            {"content_hash", m.content_hash}, {"output_path", m.output_path},
            {"urdf_path", m.urdf_path}, {"num_links", m.num_links}, {"num_joints", m.num_joints},
            {"validated", m.validated}, {"validation_passed", m.validation_passed},
            {"num_chunks", m.num_chunks}, {"rdtf_json_size", m.rdtf_json_size},
            {"rdtf_json_sha256", m.rdtf_json_sha256}, {"rdtf_json", m.rdtf_json},
            {"urdf", m.urdf}, {"num_urdf_chunks", m.num_urdf_chunks}, {"urdf_size", m.urdf_size},
            {"urdf_sha256", m.urdf_sha256}});
  return j;
}

Json to_json(const rdtf::description_chunk_t& m) {
  Json j = header("rdtf.description_chunk_t", m.utime, m.model_id);
  j.update({{"revision", m.revision}, {"content_hash", m.content_hash}, {"index", m.index},
            {"count", m.count}, {"size", m.size},
            {"data", std::string(m.data.begin(), m.data.end())}});
  return j;
}

Json to_json(const rdtf::manifest_t& m) {
  Json files = Json::array();
  for (const auto& f : m.files) {
    files.push_back({{"path", f.path}, {"sha256", f.sha256}, {"size", f.size}, {"role", f.role}});
  }
  Json j = header("rdtf.manifest_t", m.utime, m.model_id);
  j.update({{"revision", m.revision}, {"content_hash", m.content_hash}, {"part", m.part},
            {"num_parts", m.num_parts}, {"total_files", m.total_files}, {"files", files}});
  return j;
}

Json to_json(const rdtf::blob_request_t& m) {
  Json ranges = Json::array();
  for (std::size_t i = 0; i < m.sha256.size(); ++i) {
    ranges.push_back({{"sha256", m.sha256[i]}, {"first_chunk", m.first_chunk[i]},
                      {"num_chunks", m.num_chunks[i]}});
  }
  return {{"type", "rdtf.blob_request_t"}, {"utime", m.utime}, {"requester", m.requester},
          {"ranges", ranges}};
}

// The bytes are left out: a blob is binary (a buffer, a mesh) and rdtf-echo prints lines of JSON.
Json to_json(const rdtf::blob_chunk_t& m) {
  return {{"type", "rdtf.blob_chunk_t"}, {"utime", m.utime}, {"sha256", m.sha256},
          {"blob_size", m.blob_size}, {"chunk_size", m.chunk_size}, {"index", m.index},
          {"count", m.count}, {"size", m.size}};
}

Json to_json(const rdtf::blob_unavailable_t& m) {
  Json blobs = Json::array();
  for (std::size_t i = 0; i < m.sha256.size(); ++i) {
    blobs.push_back({{"sha256", m.sha256[i]}, {"reason", m.reason[i]}});
  }
  return {{"type", "rdtf.blob_unavailable_t"}, {"utime", m.utime}, {"requester", m.requester},
          {"blobs", blobs}};
}

Json to_json(const rdtf::inertia_table_t& m) {
  Json links = Json::array();
  for (const auto& l : m.links) {
    links.push_back({{"name", l.name}, {"gltf_name", l.gltf_name}, {"node", l.node}, {"mass", l.mass}, {"volume", l.volume},
                     {"center_of_mass", {l.center_of_mass[0], l.center_of_mass[1], l.center_of_mass[2]}},
                     {"ixx", l.ixx}, {"ixy", l.ixy}, {"ixz", l.ixz}, {"iyy", l.iyy},
                     {"iyz", l.iyz}, {"izz", l.izz}, {"authored", l.authored}});
  }
  Json j = header("rdtf.inertia_table_t", m.utime, m.model_id);
  j.update({{"revision", m.revision}, {"content_hash", m.content_hash},
            {"total_mass", m.total_mass},
            {"center_of_mass_scene", {m.center_of_mass_scene[0], m.center_of_mass_scene[1], m.center_of_mass_scene[2]}},
            {"links", links}});
  return j;
}

Json to_json(const rdtf::delta_t& m) {
  Json changes = Json::array();
  for (const auto& c : m.changes) {
    changes.push_back({{"element", c.element}, {"change", c.change}, {"name", c.name},
                       {"urdf_name", c.urdf_name}, {"aspects", c.aspects}});
  }
  Json j = header("rdtf.delta_t", m.utime, m.model_id);
  j.update({{"previous_revision", m.previous_revision}, {"previous_content_hash", m.previous_content_hash},
            {"revision", m.revision}, {"content_hash", m.content_hash}, {"part", m.part},
            {"num_parts", m.num_parts}, {"total_changes", m.total_changes}, {"changes", changes}});
  return j;
}

Json to_json(const rdtf::model_error_t& m) {
  Json diagnostics = Json::array();
  for (const auto& d : m.diagnostics) diagnostics.push_back(to_json(d));
  Json j = header("rdtf.model_error_t", m.utime, m.model_id);
  j.update({{"source_path", m.source_path}, {"live_revision", m.live_revision},
            {"content_hash", m.content_hash}, {"diagnostics", diagnostics}});
  return j;
}

Json to_json(const rdtf::model_removed_t& m) {
  Json j = header("rdtf.model_removed_t", m.utime, m.model_id);
  j.update({{"source_path", m.source_path}, {"last_revision", m.last_revision}});
  return j;
}

Json to_json(const rdtf::model_saving_t& m) {
  Json j = header("rdtf.model_saving_t", m.utime, m.model_id);
  j.update({{"live_revision", m.live_revision}, {"settle_ms", m.settle_ms}});
  return j;
}

Json to_json(const rdtf::request_t& m) {
  Json j = header("rdtf.request_t", m.utime, m.model_id);
  j["requester"] = m.requester;
  return j;
}

Json to_json(const rdtf::status_t& m) {
  return {{"type", "rdtf.status_t"}, {"utime", m.utime}, {"version", m.version},
          {"pid", m.pid}, {"uptime", m.uptime}, {"num_models", m.num_models},
          {"num_watched_dirs", m.num_watched_dirs}, {"conversions", m.conversions},
          {"rejections", m.rejections}, {"skipped_unchanged", m.skipped_unchanged},
          {"rescans", m.rescans}, {"pending", m.pending}, {"dropped_messages", m.dropped_messages},
          {"coalesced_requests", m.coalesced_requests}, {"send_queue_bytes", m.send_queue_bytes},
          {"send_dropped", m.send_dropped}, {"live_real_time_factor", m.live_real_time_factor},
          {"simulations_behind", m.simulations_behind}, {"simulations_failed", m.simulations_failed},
          {"blob_requests", m.blob_requests}, {"blob_chunks_sent", m.blob_chunks_sent},
          {"blob_bytes_sent", m.blob_bytes_sent}, {"blob_unavailable", m.blob_unavailable},
          {"blob_requests_dropped", m.blob_requests_dropped}, {"model_ids", m.model_ids}};
}

Json to_json(const rdtf::joint_state_t& m) {
  Json j = header("rdtf.joint_state_t", m.utime, m.model_id);
  j.update({{"revision", m.revision}, {"content_hash", m.content_hash}, {"sim_time", m.sim_time},
            {"name", m.name}, {"gltf_name", m.gltf_name}, {"position", m.position}, {"velocity", m.velocity},
            {"effort", m.effort}});
  return j;
}

Json to_json(const rdtf::link_state_t& m) {
  Json j = header("rdtf.link_state_t", m.utime, m.model_id);
  j.update({{"revision", m.revision}, {"content_hash", m.content_hash}, {"sim_time", m.sim_time},
            {"name", m.name}, {"gltf_name", m.gltf_name}, {"position", m.position}, {"orientation", m.orientation},
            {"linear_velocity", m.linear_velocity}, {"angular_velocity", m.angular_velocity}});
  return j;
}

Json to_json(const rdtf::joint_command_t& m) {
  std::vector<int> modes(m.mode.begin(), m.mode.end());
  Json j = header("rdtf.joint_command_t", m.utime, m.model_id);
  j.update({{"revision", m.revision}, {"content_hash", m.content_hash}, {"name", m.name},
            {"mode", modes}, {"value", m.value}, {"kp", m.kp}, {"kd", m.kd}});
  return j;
}

Json to_json(const rdtf::validation_report_t& m) {
  Json diagnostics = Json::array();
  for (const auto& d : m.diagnostics) diagnostics.push_back(to_json(d));
  Json j = header("rdtf.validation_report_t", m.utime, m.model_id);
  j.update({{"revision", m.revision}, {"content_hash", m.content_hash}, {"passed", m.passed},
            {"simulated_time", m.simulated_time}, {"steps", m.steps},
            {"energy_drift", m.energy_drift}, {"worst_joint_error", m.worst_joint_error},
            {"wall_time", m.wall_time}, {"diagnostics", diagnostics}});
  return j;
}

using Decoder = std::function<std::optional<Json>(const void*, std::uint32_t)>;

template <typename Message>
std::pair<std::int64_t, Decoder> decoder() {
  return {Message::getHash(), [](const void* data, std::uint32_t size) -> std::optional<Json> {
            // Schema check first: lcm-gen's decoder alone throws or allocates gigabytes on a
            // crafted length (lcmtypes/safe_decode.h).
            std::string why;
            auto message = lcm_safe::decode<Message>(data, size, why);
            if (!message) return std::nullopt;
            return to_json(*message);
          }};
}

}  // namespace

std::optional<nlohmann::ordered_json> message_to_json(const void* data, std::uint32_t size) {
  static const std::map<std::int64_t, Decoder> decoders = {
      decoder<rdtf::description_t>(),    decoder<rdtf::description_chunk_t>(),
      decoder<rdtf::inertia_table_t>(),  decoder<rdtf::model_error_t>(),
      decoder<rdtf::model_removed_t>(),  decoder<rdtf::request_t>(),
      decoder<rdtf::status_t>(),         decoder<rdtf::joint_state_t>(),
      decoder<rdtf::link_state_t>(),
      decoder<rdtf::joint_command_t>(),  decoder<rdtf::validation_report_t>(),
      decoder<rdtf::manifest_t>(),       decoder<rdtf::blob_request_t>(),
      decoder<rdtf::blob_chunk_t>(),     decoder<rdtf::blob_unavailable_t>(),
      decoder<rdtf::delta_t>(),          decoder<rdtf::model_saving_t>()};
  if (size < 8) return std::nullopt;
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  std::uint64_t hash = 0;
  for (int i = 0; i < 8; ++i) hash = hash << 8 | bytes[i];  // LCM writes it big-endian.
  const auto found = decoders.find(static_cast<std::int64_t>(hash));
  if (found == decoders.end()) return std::nullopt;
  return found->second(data, size);
}

}  // namespace rdtf::clients
