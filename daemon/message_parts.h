// Rows of a list (a manifest's files, a delta's changes) split over as few LCM messages as keep
// each within a datagram's budget.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace rdtf::daemon {

// `rows` in order over parts copied from `header` (its list empty), each part's encoded size
// within `max_message_bytes` where rows allow: a part holds at least one row, so that even a row
// larger than the limit (a name of kilobytes) makes progress; the publisher sends what the limit
// would not. There is always one part, empty when `rows` is. Sets the list, its count and every
// part's part / num_parts.
template <typename Message, typename Row>
std::vector<Message> split_into_parts(const Message& header, std::vector<Row> rows, std::vector<Row> Message::*list,
                                      std::int32_t Message::*count, std::size_t max_message_bytes) {
  const std::size_t fields = static_cast<std::size_t>(header.getEncodedSize());
  std::vector<Message> parts;
  Message part = header;
  std::size_t size = fields;
  const auto close = [&] {
    part.*count = static_cast<std::int32_t>((part.*list).size());
    parts.push_back(std::move(part));
    part = header;
    size = fields;
  };
  for (Row& row : rows) {
    const std::size_t row_size = static_cast<std::size_t>(row._getEncodedSizeNoHash());
    if (!(part.*list).empty() && size + row_size > max_message_bytes) close();
    (part.*list).push_back(std::move(row));
    size += row_size;
  }
  close();
  for (std::size_t i = 0; i < parts.size(); ++i) {
    parts[i].part = static_cast<std::int32_t>(i);
    parts[i].num_parts = static_cast<std::int32_t>(parts.size());
  }
  return parts;
}

}  // namespace rdtf::daemon
