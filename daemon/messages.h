// From the daemon's values to rdtf LCM messages (lcmtypes/), with every count field set from
// its vector in one place.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <rdtf/description_chunk_t.hpp>
#include <rdtf/description_t.hpp>
#include <rdtf/inertia_table_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/model_removed_t.hpp>
#include <rdtf/model_saving_t.hpp>
#include <rdtf/status_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "registry.h"

namespace rdtf::daemon {

std::int64_t now_utime();

// The description of a record's live revision as messages that each encode to at most
// max_message_bytes (one UDP datagram): documents that do not fit inline go into chunks
// (docs/lcm.md, "Large descriptions"), sent before the description in this order.
struct DescriptionMessages {
  std::vector<rdtf::description_chunk_t> json_chunks;  // <prefix>/<model_id>/DESCRIPTION_CHUNK
  std::vector<rdtf::description_chunk_t> urdf_chunks;  // <prefix>/<model_id>/URDF_CHUNK
  rdtf::description_t description;
};
DescriptionMessages make_description(const ModelRecord& record, const LiveTexts& texts, std::size_t max_message_bytes);

// The inertia table of the live revision: one message, or several with consecutive links when
// one would not fit in max_message_bytes (together they hold every link once, in order).
std::vector<rdtf::inertia_table_t> make_inertia_tables(const ModelRecord& record, std::size_t max_message_bytes);

// Reports with more diagnostics than fit in max_message_bytes keep the first ones and say how
// many were left out (DIAGNOSTICS_TRUNCATED).
rdtf::model_error_t make_model_error(const ModelRecord& record, const std::string& content_hash,
                                     const Diagnostics& diagnostics, std::size_t max_message_bytes);

rdtf::model_removed_t make_model_removed(const ModelRecord& record);
rdtf::model_saving_t make_model_saving(const ModelRecord& record, std::chrono::milliseconds settle);

rdtf::validation_report_t make_validation_report(const std::string& model_id, std::int64_t revision,
                                                 const std::string& content_hash,
                                                 const ValidationSummary& summary,
                                                 std::size_t max_message_bytes);

std::vector<rdtf::diagnostic_t> to_messages(const Diagnostics& diagnostics);

}  // namespace rdtf::daemon
