// Small helpers shared by the glTF checks (validate_*.cc): glTF's numeric enums, overflow-checked
// arithmetic, and untrusted JSON values read or quoted without throwing.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <utility>

#include "rdtf/completion.h"
#include "rdtf/gltf.h"

namespace rdtf::internal {

// "node 3 'elbow'" (its name when it has one; any document, however malformed): users know their
// nodes by name.
inline std::string node_named(const Json& document, std::size_t i) {
  std::string label = "node " + std::to_string(i);
  const auto nodes = document.find("nodes");
  if (nodes == document.end() || !nodes->is_array() || i >= nodes->size() || !(*nodes)[i].is_object()) return label;
  const auto name = (*nodes)[i].find("name");
  if (name != (*nodes)[i].end() && name->is_string() && !name->get_ref<const std::string&>().empty()) {
    label += " " + value_text(*name);
  }
  return label;
}

inline constexpr std::uint64_t kByte = 5120, kUnsignedByte = 5121, kShort = 5122,
                               kUnsignedShort = 5123, kUnsignedInt = 5125, kFloat = 5126;
// bufferView.target: vertex attributes, indices.
inline constexpr std::uint64_t kArrayBuffer = 34962, kElementArrayBuffer = 34963;

// Columns and rows of an accessor type ("VEC3": 1 x 3, "MAT4": 4 x 4); {0, 0} when unknown.
inline std::pair<std::uint64_t, std::uint64_t> accessor_type_shape(const std::string& type) {
  if (type == "SCALAR") return {1, 1};
  if (type == "VEC2") return {1, 2};
  if (type == "VEC3") return {1, 3};
  if (type == "VEC4") return {1, 4};
  if (type == "MAT2") return {2, 2};
  if (type == "MAT3") return {3, 3};
  if (type == "MAT4") return {4, 4};
  return {0, 0};
}

// Bytes of one component; 0 for a value that is no glTF componentType.
inline std::uint64_t component_size(std::uint64_t component_type) {
  switch (component_type) {
    case kByte:
    case kUnsignedByte:
      return 1;
    case kShort:
    case kUnsignedShort:
      return 2;
    case kUnsignedInt:
    case kFloat:
      return 4;
    default:
      return 0;
  }
}

inline std::optional<std::uint64_t> checked_add(std::uint64_t a, std::uint64_t b) {
  if (b > std::numeric_limits<std::uint64_t>::max() - a) return std::nullopt;
  return a + b;
}

inline std::optional<std::uint64_t> checked_mul(std::uint64_t a, std::uint64_t b) {
  if (a != 0 && b > std::numeric_limits<std::uint64_t>::max() / a) return std::nullopt;
  return a * b;
}

inline std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b) {
  return checked_add(a, b).value_or(std::numeric_limits<std::uint64_t>::max());
}

// A non-negative integer; an integral float (3.0) counts, as JavaScript readers see it.
inline std::optional<std::uint64_t> as_uint(const Json& value) {
  if (value.is_number_unsigned()) return value.get<std::uint64_t>();
  if (value.is_number_integer() && value.get<std::int64_t>() >= 0) {
    return value.get<std::uint64_t>();
  }
  if (value.is_number_float()) {
    const double d = value.get<double>();
    if (d >= 0 && d < 18446744073709551616.0 && d == std::floor(d)) {
      return static_cast<std::uint64_t>(d);
    }
  }
  return std::nullopt;
}

// object[key] as a non-negative integer, or nothing (absent, or no such integer).
inline std::optional<std::uint64_t> uint_at(const Json& object, const char* key) {
  if (!object.is_object() || !object.contains(key)) return std::nullopt;
  return as_uint(object[key]);
}

// The object at document[array][index], or null.
inline const Json* element_at(const Json& document, const char* array, std::optional<std::uint64_t> index) {
  if (!index || !document.contains(array) || !document[array].is_array() || *index >= document[array].size()) {
    return nullptr;
  }
  const Json& element = document[array][static_cast<std::size_t>(*index)];
  return element.is_object() ? &element : nullptr;
}

// Text from the file, shortened for a message without splitting a UTF-8 character.
inline std::string quote(const std::string& text) {
  constexpr std::size_t kMax = 40;
  if (text.size() <= kMax) return text;
  std::size_t end = kMax - 3;
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xC0) == 0x80) --end;
  return text.substr(0, end) + "...";
}

// A JSON value as it appears in the file, shortened; never throws (invalid UTF-8 is replaced).
inline std::string describe(const Json& value) {
  return quote(value.dump(-1, ' ', false, Json::error_handler_t::replace));
}

// A number as a modeller reads it: "0", "1.5", "0.100000001" (enough digits for a float).
inline std::string number_text(double value) { return format_number(value, 9); }

}  // namespace rdtf::internal
