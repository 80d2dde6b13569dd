#include "messages.h"

#include <algorithm>
#include <chrono>
#include <cstdint>

#include "counts.h"
#include "diagnostic_message.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/urdf_names.h"

namespace rdtf::daemon {

std::int64_t now_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::vector<rdtf::diagnostic_t> to_messages(const Diagnostics& diagnostics) {
  std::vector<rdtf::diagnostic_t> out;
  for (const Diagnostic& d : diagnostics.all()) out.push_back(to_message(d));
  return out;
}

namespace {

// Pieces of `text` of at most `piece_bytes`, as chunks of the record's live revision.
std::vector<rdtf::description_chunk_t> chunks_of(const ModelRecord& record, const std::string& text,
                                                 std::int64_t utime, std::size_t max_message_bytes) {
  rdtf::description_chunk_t empty;
  empty.utime = utime;
  empty.model_id = record.id;
  empty.revision = record.revisions;
  empty.content_hash = record.live->content_hash;
  set_counts(empty);
  const std::size_t overhead = static_cast<std::size_t>(empty.getEncodedSize());
  // The piece is what the limit leaves beside the chunk's own fields. A floor of 1024 sent chunks
  // of up to 1,150 bytes at the documented minimum limit, 1024 (s80client D4); the floor now only
  // keeps a model id of nearly the limit's length making progress.
  constexpr std::size_t kSmallestPiece = 64;
  const std::size_t piece = max_message_bytes > overhead + kSmallestPiece ? max_message_bytes - overhead : kSmallestPiece;
  const std::size_t count = (text.size() + piece - 1) / piece;
  std::vector<rdtf::description_chunk_t> chunks;
  for (std::size_t i = 0; i < count; ++i) {
    rdtf::description_chunk_t chunk = empty;
    chunk.index = static_cast<std::int32_t>(i);
    chunk.count = static_cast<std::int32_t>(count);
    const std::size_t begin = i * piece;
    const std::size_t end = std::min(text.size(), begin + piece);
    chunk.data.assign(text.begin() + static_cast<std::ptrdiff_t>(begin), text.begin() + static_cast<std::ptrdiff_t>(end));
    set_counts(chunk);
    chunks.push_back(std::move(chunk));
  }
  return chunks;
}

}  // namespace

DescriptionMessages make_description(const ModelRecord& record, const LiveTexts& texts, std::size_t max_message_bytes) {
  const ConvertedModel& model = *record.live;
  DescriptionMessages out;
  rdtf::description_t& message = out.description;
  message.utime = now_utime();
  message.model_id = record.id;
  message.source_path = record.source.string();
  message.revision = record.revisions;
  message.content_hash = model.content_hash;
  message.output_path = model.output_path;
  message.urdf_path = model.urdf_path;
  message.num_links = static_cast<std::int32_t>(model.robot.links.size());
  message.num_joints = static_cast<std::int32_t>(model.robot.joints.size());
  message.validated = model.validation.has_value();
  message.validation_passed = model.validation && model.validation->passed;
  message.rdtf_json_size = static_cast<std::int64_t>(texts.rdtf_json.size());
  message.rdtf_json_sha256 = sha256_hex(texts.rdtf_json);
  message.num_chunks = 0;
  message.num_urdf_chunks = 0;
  message.urdf_size = static_cast<std::int64_t>(texts.urdf.size());
  message.urdf_sha256 = texts.urdf.empty() ? "" : sha256_hex(texts.urdf);
  const std::size_t fields = static_cast<std::size_t>(message.getEncodedSize());
  const std::size_t room = max_message_bytes > fields ? max_message_bytes - fields : 0;
  const std::size_t json = texts.rdtf_json.size();
  const std::size_t urdf = texts.urdf.size();
  // Both inline when they fit together; else the one that fits alone stays inline (the smaller
  // first) and the other goes in chunks; else both go in chunks.
  bool json_inline = json + urdf <= room;
  bool urdf_inline = json_inline;
  if (!json_inline) {
    if (urdf <= json && urdf <= room) {
      urdf_inline = true;
    } else if (json < urdf && json <= room) {
      json_inline = true;
    }
  }
  if (json_inline) {
    message.rdtf_json = texts.rdtf_json;
  } else {
    out.json_chunks = chunks_of(record, texts.rdtf_json, message.utime, max_message_bytes);
    message.num_chunks = static_cast<std::int32_t>(out.json_chunks.size());
  }
  if (urdf_inline) {
    message.urdf = texts.urdf;
  } else {
    out.urdf_chunks = chunks_of(record, texts.urdf, message.utime, max_message_bytes);
    message.num_urdf_chunks = static_cast<std::int32_t>(out.urdf_chunks.size());
  }
  return out;
}

std::vector<rdtf::inertia_table_t> make_inertia_tables(const ModelRecord& record, std::size_t max_message_bytes) {
  const ConvertedModel& model = *record.live;
  rdtf::inertia_table_t table;
  table.utime = now_utime();
  table.model_id = record.id;
  table.revision = record.revisions;
  table.content_hash = model.content_hash;
  table.total_mass = model.totals.mass;
  for (int i = 0; i < 3; ++i) table.center_of_mass_scene[i] = model.totals.center_of_mass_scene[i];
  set_counts(table);
  const std::size_t fields = static_cast<std::size_t>(table.getEncodedSize());
  std::vector<rdtf::inertia_table_t> tables;
  std::size_t size = fields;
  // The URDF's link names, as in LINK_STATE (urdf_names.h), with the glTF ones beside them.
  const UrdfNames names = urdf_names(model.robot);
  for (std::size_t l = 0; l < model.robot.links.size(); ++l) {
    const Link& link = model.robot.links[l];
    rdtf::link_inertia_t row;
    row.name = names.links[l];
    row.gltf_name = lcm_text(link.name);
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
    const std::size_t row_size = static_cast<std::size_t>(row._getEncodedSizeNoHash());
    if (!table.links.empty() && size + row_size > max_message_bytes) {
      set_counts(table);
      tables.push_back(table);
      table.links.clear();
      size = fields;
    }
    table.links.push_back(std::move(row));
    size += row_size;
  }
  set_counts(table);
  tables.push_back(std::move(table));
  return tables;
}

namespace {

// Keeps the message within max_bytes: diagnostics are dropped from the end (errors come first,
// conversion warnings last) and one INFO says how many went, all of which are in the log.
template <typename Message>
void fit_diagnostics(Message& message, std::size_t max_bytes) {
  if (static_cast<std::size_t>(message.getEncodedSize()) <= max_bytes) return;
  const auto note_text = [](std::size_t left_out) {
    return std::to_string(left_out) +
           " more diagnostics not sent: they did not fit in one datagram, which keeps the most severe (rdtf "
           "inspect or rdtf validate of the model lists every one)";
  };
  // Sized with the longest count it can hold; the real count is put in below.
  rdtf::diagnostic_t note = to_message(Severity::kInfo, codes::DIAGNOSTICS_TRUNCATED, note_text(999999));
  std::vector<rdtf::diagnostic_t> all = std::move(message.diagnostics);
  message.diagnostics.clear();
  set_counts(message);
  std::size_t size = static_cast<std::size_t>(message.getEncodedSize()) + static_cast<std::size_t>(note._getEncodedSizeNoHash());
  // The most severe first, each that fits, then sent in their own order: a report cut to size
  // kept the infos that came first and dropped the warnings after them (s100java D2).
  std::vector<std::size_t> by_severity(all.size());
  for (std::size_t k = 0; k < all.size(); ++k) by_severity[k] = k;
  std::stable_sort(by_severity.begin(), by_severity.end(),
                   [&](std::size_t a, std::size_t b) { return all[a].severity > all[b].severity; });
  std::vector<bool> keep(all.size(), false);
  std::size_t kept = 0;
  for (const std::size_t k : by_severity) {
    const std::size_t row = static_cast<std::size_t>(all[k]._getEncodedSizeNoHash());
    if (size + row > max_bytes) break;
    size += row;
    keep[k] = true;
    ++kept;
  }
  for (std::size_t k = 0; k < all.size(); ++k) {
    if (keep[k]) message.diagnostics.push_back(std::move(all[k]));
  }
  note.message = note_text(all.size() - kept);
  message.diagnostics.push_back(std::move(note));
  set_counts(message);
}

}  // namespace

rdtf::model_error_t make_model_error(const ModelRecord& record, const std::string& content_hash,
                                     const Diagnostics& diagnostics, std::size_t max_message_bytes) {
  rdtf::model_error_t message;
  message.utime = now_utime();
  message.model_id = record.id;
  message.source_path = record.source.string();
  message.live_revision = record.live ? record.revisions : 0;
  message.content_hash = content_hash;
  message.diagnostics = to_messages(diagnostics);
  // Errors first: what refused the save is what a viewer shows first, and what a message cut to
  // size keeps (fit_diagnostics keeps the first).
  std::stable_sort(message.diagnostics.begin(), message.diagnostics.end(),
                   [](const rdtf::diagnostic_t& a, const rdtf::diagnostic_t& b) { return a.severity > b.severity; });
  set_counts(message);
  fit_diagnostics(message, max_message_bytes);
  return message;
}

rdtf::model_saving_t make_model_saving(const ModelRecord& record, std::chrono::milliseconds settle) {
  rdtf::model_saving_t message;
  message.utime = now_utime();
  message.model_id = record.id;
  message.live_revision = record.revisions;
  message.settle_ms = static_cast<std::int32_t>(std::min<std::int64_t>(settle.count(), INT32_MAX));
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
                                                 const ValidationSummary& summary, std::size_t max_message_bytes) {
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
  set_counts(message);
  fit_diagnostics(message, max_message_bytes);
  return message;
}

}  // namespace rdtf::daemon
