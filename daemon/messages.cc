#include "messages.h"

#include <chrono>

namespace rdtf::daemon {

std::int64_t now_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::vector<rdtf::diagnostic_t> to_messages(const Diagnostics& diagnostics) {
  std::vector<rdtf::diagnostic_t> out;
  for (const Diagnostic& d : diagnostics.all()) {
    rdtf::diagnostic_t m;
    m.severity = d.severity == Severity::kError     ? rdtf::diagnostic_t::ERROR
                 : d.severity == Severity::kWarning ? rdtf::diagnostic_t::WARNING
                                                    : rdtf::diagnostic_t::INFO;
    m.code = d.code;
    m.file = d.file;
    m.pointer = d.pointer;
    m.byte_offset = d.byte_offset ? static_cast<std::int64_t>(*d.byte_offset) : -1;
    m.message = d.message;
    out.push_back(std::move(m));
  }
  return out;
}

rdtf::description_t make_description(const ModelRecord& record, std::size_t max_inline_bytes,
                                     std::vector<rdtf::description_chunk_t>& chunks) {
  const ConvertedModel& model = *record.live;
  rdtf::description_t message;
  message.utime = now_utime();
  message.model_id = record.id;
  message.source_path = record.source.string();
  message.revision = record.revisions;
  message.content_hash = model.content_hash;
  message.output_path = model.output_path.string();
  message.urdf_path = model.urdf_path.string();
  message.num_links = static_cast<std::int32_t>(model.robot.links.size());
  message.num_joints = static_cast<std::int32_t>(model.robot.joints.size());
  message.validated = model.validation.has_value();
  message.validation_passed = model.validation && model.validation->passed;
  message.rdtf_json_size = static_cast<std::int64_t>(model.rdtf_json.size());
  message.rdtf_json_sha256 = sha256_hex(model.rdtf_json);
  message.urdf = model.urdf;
  chunks.clear();
  if (model.rdtf_json.size() <= max_inline_bytes) {
    message.rdtf_json = model.rdtf_json;
    message.num_chunks = 0;
    return message;
  }
  message.rdtf_json = "";
  const std::size_t count = (model.rdtf_json.size() + max_inline_bytes - 1) / max_inline_bytes;
  message.num_chunks = static_cast<std::int32_t>(count);
  for (std::size_t i = 0; i < count; ++i) {
    rdtf::description_chunk_t chunk;
    chunk.utime = message.utime;
    chunk.model_id = record.id;
    chunk.revision = record.revisions;
    chunk.content_hash = model.content_hash;
    chunk.index = static_cast<std::int32_t>(i);
    chunk.count = static_cast<std::int32_t>(count);
    const std::size_t begin = i * max_inline_bytes;
    const std::size_t end = std::min(model.rdtf_json.size(), begin + max_inline_bytes);
    chunk.data.assign(model.rdtf_json.begin() + static_cast<std::ptrdiff_t>(begin),
                      model.rdtf_json.begin() + static_cast<std::ptrdiff_t>(end));
    chunk.size = static_cast<std::int32_t>(chunk.data.size());
    chunks.push_back(std::move(chunk));
  }
  return message;
}

rdtf::inertia_table_t make_inertia_table(const ModelRecord& record) {
  const ConvertedModel& model = *record.live;
  rdtf::inertia_table_t table;
  table.utime = now_utime();
  table.model_id = record.id;
  table.revision = record.revisions;
  table.content_hash = model.content_hash;
  table.total_mass = model.totals.mass;
  for (int i = 0; i < 3; ++i) table.center_of_mass_scene[i] = model.totals.center_of_mass_scene[i];
  for (const Link& link : model.robot.links) {
    rdtf::link_inertia_t row;
    row.name = link.name;
    row.node = link.node;
    row.mass = link.inertial.mass;
    row.volume = link.inertial.volume;
    for (int i = 0; i < 3; ++i) row.center_of_mass[i] = link.inertial.center_of_mass[i];
    const auto& I = link.inertial.inertia;
    row.ixx = I(0, 0);
    row.ixy = I(0, 1);
    row.ixz = I(0, 2);
    row.iyy = I(1, 1);
    row.iyz = I(1, 2);
    row.izz = I(2, 2);
    row.authored = link.inertial_source == InertialSource::kAuthored;
    table.links.push_back(std::move(row));
  }
  table.num_links = static_cast<std::int32_t>(table.links.size());
  return table;
}

rdtf::model_error_t make_model_error(const ModelRecord& record, const std::string& content_hash,
                                     const Diagnostics& diagnostics) {
  rdtf::model_error_t message;
  message.utime = now_utime();
  message.model_id = record.id;
  message.source_path = record.source.string();
  message.live_revision = record.live ? record.revisions : 0;
  message.content_hash = content_hash;
  message.diagnostics = to_messages(diagnostics);
  message.num_diagnostics = static_cast<std::int32_t>(message.diagnostics.size());
  return message;
}

rdtf::model_removed_t make_model_removed(const ModelRecord& record) {
  rdtf::model_removed_t message;
  message.utime = now_utime();
  message.model_id = record.id;
  message.source_path = record.source.string();
  message.last_revision = record.revisions;
  return message;
}

}  // namespace rdtf::daemon

namespace rdtf::daemon {

rdtf::validation_report_t make_validation_report(const std::string& model_id, std::int64_t revision,
                                                 const std::string& content_hash,
                                                 const ValidationSummary& summary) {
  rdtf::validation_report_t message;
  message.utime = now_utime();
  message.model_id = model_id;
  message.revision = revision;
  message.content_hash = content_hash;
  message.passed = summary.passed;
  message.simulated_time = summary.simulated_time;
  message.steps = static_cast<std::int32_t>(summary.steps);
  message.energy_drift = summary.energy_drift;
  message.worst_joint_error = summary.worst_joint_error;
  message.wall_time = summary.wall_time;
  message.diagnostics = to_messages(summary.diagnostics);
  message.num_diagnostics = static_cast<std::int32_t>(message.diagnostics.size());
  return message;
}

}  // namespace rdtf::daemon
