// A revision's DELTA (docs/lcm.md, "Deltas") as LCM messages that each encode to at most
// max_message_bytes: one, or several parts with the next changes in order.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <rdtf/delta_t.hpp>

#include "rdtf/diff.h"

namespace rdtf::daemon {

struct DeltaHeader {
  std::string model_id;
  std::int64_t previous_revision = 0;  // 0: none known (every element is then "added")
  std::string previous_content_hash;
  std::int64_t revision = 0;
  std::string content_hash;
};

std::vector<rdtf::delta_t> make_deltas(const DeltaHeader& header, const std::vector<ElementChange>& changes,
                                       std::int64_t utime, std::size_t max_message_bytes);

}  // namespace rdtf::daemon
