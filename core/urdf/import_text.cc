// The URDF's text made unambiguous before either XML reader sees it. urdfdom parses with TinyXML's
// default (legacy) encoding, which turns a character reference such as "&#xE9;" into one byte,
// 0xE9, while the structural scan reads UTF-8: the two would disagree about a name like "caf&#xE9;"
// and import would look up a link urdfdom never made. Writing references beyond ASCII out as UTF-8
// gives both readers the same bytes, and a check of the whole text makes every name valid UTF-8
// (glTF's JSON must be).
#include <string>
#include <string_view>

#include "import_internal.h"
#include "rdtf/utf8.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::urdf_internal {
namespace {

// Line, column and byte (all 1-based, as for glTF's JSON) of the byte at offset `at`.
std::string place_of(std::string_view text, std::size_t at) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < at && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column) + " (byte " + std::to_string(at + 1) + ")";
}

void append_utf8(std::string& out, std::uint32_t c) {
  if (c < 0x800) {
    out += static_cast<char>(0xC0 | (c >> 6));
  } else if (c < 0x10000) {
    out += static_cast<char>(0xE0 | (c >> 12));
    out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (c >> 18));
    out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
  }
  out += static_cast<char>(0x80 | (c & 0x3F));
}

// The numeric character reference at `at` ("&#233;" or "&#xE9;"): its code point (or a value
// above U+10FFFF when too large) and its length; nullopt when `at` does not start one.
struct Reference {
  std::uint64_t code = 0;
  std::size_t length = 0;
};
std::optional<Reference> reference_at(std::string_view text, std::size_t at) {
  if (text.substr(at, 2) != "&#") return std::nullopt;
  std::size_t i = at + 2;
  const bool hex = i < text.size() && (text[i] == 'x' || text[i] == 'X');
  if (hex) ++i;
  const std::size_t digits_start = i;
  std::uint64_t code = 0;
  for (; i < text.size() && text[i] != ';'; ++i) {
    const char c = text[i];
    int digit = -1;
    if (c >= '0' && c <= '9') digit = c - '0';
    if (hex && c >= 'a' && c <= 'f') digit = c - 'a' + 10;
    if (hex && c >= 'A' && c <= 'F') digit = c - 'A' + 10;
    if (digit < 0) return std::nullopt;  // Not a reference: left to the XML parser to judge.
    code = std::min<std::uint64_t>(code * (hex ? 16 : 10) + static_cast<std::uint64_t>(digit), 0x7FFFFFFF);
  }
  if (i == digits_start || i >= text.size()) return std::nullopt;
  return Reference{code, i + 1 - at};
}

}  // namespace

std::optional<std::string> urdf_text_as_utf8(std::string_view text, Diagnostics& diag) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t n = utf8_sequence_length(text, at);
    if (n == 0) {
      diag.error(codes::URDF_NOT_UTF8, "",
                 place_of(text, at) + ": byte 0x" + "0123456789ABCDEF"[static_cast<unsigned char>(text[at]) >> 4] +
                     "0123456789ABCDEF"[static_cast<unsigned char>(text[at]) & 0xF] +
                     " is not UTF-8 (URDF names become glTF names, which must be UTF-8)");
      return std::nullopt;
    }
    if (n == 1 && text[at] == '&') {
      if (const auto ref = reference_at(text, at); ref && ref->code >= 0x80) {
        const bool surrogate = ref->code >= 0xD800 && ref->code <= 0xDFFF;
        if (surrogate || ref->code > 0x10FFFF) {
          diag.error(codes::URDF_NOT_UTF8, "",
                     place_of(text, at) + ": the character reference '" + std::string(text.substr(at, ref->length)) +
                         "' is not a Unicode character (a surrogate or beyond U+10FFFF)");
          return std::nullopt;
        }
        append_utf8(out, static_cast<std::uint32_t>(ref->code));
        at += ref->length;
        continue;
      }
    }
    out.append(text.substr(at, n));
    at += n;
  }
  return out;
}

}  // namespace rdtf::urdf_internal
