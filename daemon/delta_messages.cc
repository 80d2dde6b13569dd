#include "delta_messages.h"

#include "diagnostic_message.h"
#include "message_parts.h"

namespace rdtf::daemon {

std::vector<rdtf::delta_t> make_deltas(const DeltaHeader& header, const std::vector<ElementChange>& changes,
                                       std::int64_t utime, std::size_t max_message_bytes) {
  rdtf::delta_t empty;
  empty.utime = utime;
  empty.model_id = header.model_id;
  empty.previous_revision = header.previous_revision;
  empty.previous_content_hash = header.previous_content_hash;
  empty.revision = header.revision;
  empty.content_hash = header.content_hash;
  empty.part = 0;
  empty.num_parts = 1;
  empty.total_changes = static_cast<std::int32_t>(changes.size());
  empty.num_changes = 0;
  std::vector<rdtf::delta_change_t> rows;
  rows.reserve(changes.size());
  for (const ElementChange& change : changes) {
    rdtf::delta_change_t& row = rows.emplace_back();
    row.element = to_string(change.element);
    row.change = to_string(change.kind);
    row.name = lcm_text(change.name);  // As LINK_STATE and JOINT_STATE carry it.
    row.urdf_name = change.urdf_name;
    row.aspects = aspect_names(change.aspects);
    row.num_aspects = static_cast<std::int32_t>(row.aspects.size());
  }
  return split_into_parts(empty, std::move(rows), &rdtf::delta_t::changes, &rdtf::delta_t::num_changes,
                          max_message_bytes);
}

}  // namespace rdtf::daemon
