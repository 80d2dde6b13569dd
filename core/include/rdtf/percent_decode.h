// RFC 3986 percent-decoding of a URI path, shared by the glTF reader (URIs of buffers and images)
// and rdtf-view (request paths). Header-only: rdtf-view uses it without linking rdtf_core.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace rdtf {

// `text` with every %XX decoded ('+' stays '+'). Nothing, with `why` set when given, on a
// malformed escape or an encoded NUL (%00): a NUL is never part of a valid path, and a string
// that hides one would be cut short by any C API it reaches.
inline std::optional<std::string> percent_decode(std::string_view text, std::string* why = nullptr) {
  const auto hex = [](char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '%') {
      out += text[i];
      continue;
    }
    const int high = i + 2 < text.size() ? hex(text[i + 1]) : -1;
    const int low = i + 2 < text.size() ? hex(text[i + 2]) : -1;
    if (high < 0 || low < 0) {
      if (why) *why = "malformed percent-escape at byte " + std::to_string(i);
      return std::nullopt;
    }
    if (high == 0 && low == 0) {
      if (why) *why = "the URI encodes a NUL byte (%00) at byte " + std::to_string(i);
      return std::nullopt;
    }
    out += static_cast<char>(high * 16 + low);
    i += 2;
  }
  return out;
}

}  // namespace rdtf
