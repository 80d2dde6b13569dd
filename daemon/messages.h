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
#include <rdtf/status_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "registry.h"

namespace rdtf::daemon {

std::int64_t now_utime();

// The description of a record's live revision. When the RDTF JSON exceeds max_inline_bytes it
// goes into chunks (returned in order) and the description announces them.
rdtf::description_t make_description(const ModelRecord& record, std::size_t max_inline_bytes,
                                     std::vector<rdtf::description_chunk_t>& chunks);

rdtf::inertia_table_t make_inertia_table(const ModelRecord& record);

rdtf::model_error_t make_model_error(const ModelRecord& record, const std::string& content_hash,
                                     const Diagnostics& diagnostics);

rdtf::model_removed_t make_model_removed(const ModelRecord& record);

rdtf::validation_report_t make_validation_report(const std::string& model_id, std::int64_t revision,
                                                 const std::string& content_hash,
                                                 const ValidationSummary& summary);

std::vector<rdtf::diagnostic_t> to_messages(const Diagnostics& diagnostics);

}  // namespace rdtf::daemon
