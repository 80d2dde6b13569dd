// The length fields of rdtf's LCM messages (num_* and a chunk's size) set from the arrays they
// count, in this one place: a message is filled by its vectors and its counts follow. LCM encodes
// `num_x` elements of each array of that length, so a count that disagrees with a vector reads
// past its end or sends a message no receiver decodes.
//
// The daemon's Publisher sets them on every message it sends; code that publishes on an lcm::LCM
// directly goes through publish() below; code that measures a message (getEncodedSize) before it
// is sent calls set_counts first. Semantic counts (description_t::num_links, status_t::num_models,
// manifest_t::total_files ...) are values, not lengths, and are the caller's.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

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

namespace rdtf {

template <typename T>
std::int32_t count_of(const std::vector<T>& values) {
  return static_cast<std::int32_t>(values.size());
}

inline void set_counts(blob_chunk_t& m) { m.size = count_of(m.data); }
inline void set_counts(blob_request_t& m) { m.num_ranges = count_of(m.sha256); }
inline void set_counts(blob_unavailable_t& m) { m.num_blobs = count_of(m.sha256); }
inline void set_counts(delta_t& m) {
  for (delta_change_t& change : m.changes) change.num_aspects = count_of(change.aspects);
  m.num_changes = count_of(m.changes);
}
inline void set_counts(description_chunk_t& m) { m.size = count_of(m.data); }
inline void set_counts(description_t&) {}  // No arrays.
inline void set_counts(inertia_table_t& m) { m.num_links = count_of(m.links); }
inline void set_counts(joint_command_t& m) { m.num_joints = count_of(m.name); }
inline void set_counts(joint_state_t& m) { m.num_joints = count_of(m.name); }
inline void set_counts(link_state_t& m) { m.num_links = count_of(m.name); }
inline void set_counts(manifest_t& m) { m.num_files = count_of(m.files); }
inline void set_counts(model_error_t& m) { m.num_diagnostics = count_of(m.diagnostics); }
inline void set_counts(model_removed_t&) {}  // No arrays.
inline void set_counts(model_saving_t&) {}   // No arrays.
inline void set_counts(request_t&) {}        // No arrays.
inline void set_counts(status_t& m) { m.num_model_ids = count_of(m.model_ids); }
inline void set_counts(validation_report_t& m) { m.num_diagnostics = count_of(m.diagnostics); }

// lcm::LCM::publish with the counts set.
template <typename Message>
int publish(lcm::LCM& lcm, const std::string& channel, Message& message) {
  set_counts(message);
  return lcm.publish(channel, &message);
}

}  // namespace rdtf
