#include "delta_messages.h"

#include "diagnostic_message.h"

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
  const std::size_t fields = static_cast<std::size_t>(empty.getEncodedSize());
  std::vector<rdtf::delta_t> parts;
  rdtf::delta_t part = empty;
  std::size_t size = fields;
  for (const ElementChange& change : changes) {
    rdtf::delta_change_t row;
    row.element = to_string(change.element);
    row.change = to_string(change.kind);
    row.name = lcm_text(change.name);  // As LINK_STATE and JOINT_STATE carry it.
    row.urdf_name = change.urdf_name;
    row.aspects = aspect_names(change.aspects);
    row.num_aspects = static_cast<std::int32_t>(row.aspects.size());
    const std::size_t row_size = static_cast<std::size_t>(row._getEncodedSizeNoHash());
    // A part holds at least one change, so that even a change larger than the limit (a name of
    // kilobytes) makes progress; the publisher sends what the limit would not.
    if (!part.changes.empty() && size + row_size > max_message_bytes) {
      part.num_changes = static_cast<std::int32_t>(part.changes.size());
      parts.push_back(std::move(part));
      part = empty;
      size = fields;
    }
    part.changes.push_back(std::move(row));
    size += row_size;
  }
  part.num_changes = static_cast<std::int32_t>(part.changes.size());
  parts.push_back(std::move(part));
  for (std::size_t i = 0; i < parts.size(); ++i) {
    parts[i].part = static_cast<std::int32_t>(i);
    parts[i].num_parts = static_cast<std::int32_t>(parts.size());
  }
  return parts;
}

}  // namespace rdtf::daemon
