// A file name in JSON that reads back byte for byte. A Linux file name is any bytes but '/' and
// NUL, and a JSON string holds UTF-8 only: rdtfd's own state (revision numbers, the result cache)
// wrote such a name with U+FFFD in place of the bad bytes, so it never matched the file again and
// every restart numbered the model anew and published a DELTA of everything "added".
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "rdtf/utf8.h"

namespace rdtf::daemon {

// UTF-8 stays readable text; anything else becomes {"hex": "<two digits a byte>"}.
inline nlohmann::json bytes_to_json(const std::string& bytes) {
  if (is_utf8(bytes)) return bytes;
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string hex;
  hex.reserve(2 * bytes.size());
  for (const char c : bytes) {
    const auto byte = static_cast<unsigned char>(c);
    hex += kDigits[byte >> 4];
    hex += kDigits[byte & 0xF];
  }
  return {{"hex", hex}};
}

// The bytes bytes_to_json wrote, or nothing when `j` is neither form.
inline std::optional<std::string> bytes_from_json(const nlohmann::json& j) {
  if (j.is_string()) return j.get<std::string>();
  if (!j.is_object() || j.size() != 1 || !j.contains("hex") || !j["hex"].is_string()) return std::nullopt;
  const std::string& hex = j["hex"].get_ref<const std::string&>();
  if (hex.size() % 2 != 0) return std::nullopt;
  const auto digit = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    return -1;
  };
  std::string bytes;
  bytes.reserve(hex.size() / 2);
  for (std::size_t i = 0; i < hex.size(); i += 2) {
    const int high = digit(hex[i]), low = digit(hex[i + 1]);
    if (high < 0 || low < 0) return std::nullopt;
    bytes += static_cast<char>(high * 16 + low);
  }
  return bytes;
}

}  // namespace rdtf::daemon
