// Any rdtf LCM message as JSON: decoded by the type fingerprint at its start, so the channel
// name does not matter.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace rdtf::clients {

// {"type": "rdtf.description_t", ...fields}; nothing when the bytes are no rdtf type or do not
// decode.
std::optional<nlohmann::ordered_json> message_to_json(const void* data, std::uint32_t size);

}  // namespace rdtf::clients
