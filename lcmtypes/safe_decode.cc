#include "safe_decode.h"

#include <cctype>
#include <map>
#include <stdexcept>
#include <vector>

#include "lcm_schema_texts.h"

namespace rdtf::lcm_safe {
namespace {

// One field of an LCM struct as its .lcm file declares it.
struct Dimension {
  std::int64_t fixed = -1;  // A constant size, or -1 ...
  std::string field;        // ... the integer field of the same struct that holds it.
};
struct Field {
  std::string type;  // int8_t ... double, string, boolean, byte, or an rdtf struct's name.
  std::string name;
  std::vector<Dimension> dimensions;
};
using Schemas = std::map<std::string, std::vector<Field>, std::less<>>;

std::vector<std::string> tokens_of(const std::string& text) {
  std::vector<std::string> tokens;
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '/' && i + 1 < text.size() && text[i + 1] == '/') {
      while (i < text.size() && text[i] != '\n') ++i;
    } else if (c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
      const auto end = text.find("*/", i + 2);
      i = end == std::string::npos ? text.size() : end + 2;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (std::string_view("{}[];,=").find(c) != std::string_view::npos) {
      tokens.emplace_back(1, c);
      ++i;
    } else {
      const std::size_t start = i;
      while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i])) &&
             std::string_view("{}[];,=/").find(text[i]) == std::string_view::npos) {
        ++i;
      }
      tokens.push_back(text.substr(start, i - start));
    }
  }
  return tokens;
}

// The structs of one .lcm file. Throws on what this reader does not know (a test parses every
// file of lcmtypes/, so a new construct fails the build's tests, not a subscriber).
void parse_lcm(const std::string& text, Schemas& schemas) {
  const auto t = tokens_of(text);
  std::size_t i = 0;
  auto expect = [&](const char* what) {
    if (i >= t.size() || t[i] != what) throw std::runtime_error(std::string("lcm schema: expected ") + what);
    ++i;
  };
  while (i < t.size()) {
    if (t[i] == "package") {
      i += 2;
      expect(";");
      continue;
    }
    expect("struct");
    if (i >= t.size()) throw std::runtime_error("lcm schema: struct without a name");
    const std::string name = t[i++];
    expect("{");
    std::vector<Field> fields;
    while (i < t.size() && t[i] != "}") {
      if (t[i] == "const") {
        while (i < t.size() && t[i] != ";") ++i;
        expect(";");
        continue;
      }
      Field field;
      field.type = t[i++];
      if (const auto dot = field.type.rfind('.'); dot != std::string::npos) field.type.erase(0, dot + 1);
      if (i >= t.size()) throw std::runtime_error("lcm schema: field without a name");
      field.name = t[i++];
      while (i < t.size() && t[i] == "[") {
        ++i;
        if (i >= t.size()) throw std::runtime_error("lcm schema: unterminated dimension");
        Dimension d;
        if (std::isdigit(static_cast<unsigned char>(t[i][0]))) {
          d.fixed = std::stoll(t[i]);
        } else {
          d.field = t[i];
        }
        ++i;
        expect("]");
        field.dimensions.push_back(std::move(d));
      }
      expect(";");
      fields.push_back(std::move(field));
    }
    expect("}");
    schemas[name] = std::move(fields);
  }
}

const Schemas& schemas() {
  static const Schemas all = [] {
    Schemas parsed;
    for (std::size_t k = 0; k < kLcmSchemaTextCount; ++k) parse_lcm(kLcmSchemaTexts[k], parsed);
    return parsed;
  }();
  return all;
}

std::size_t primitive_size(std::string_view type) {
  if (type == "int8_t" || type == "byte" || type == "boolean") return 1;
  if (type == "int16_t") return 2;
  if (type == "int32_t" || type == "float") return 4;
  if (type == "int64_t" || type == "double") return 8;
  return 0;
}

std::int64_t read_big_endian(const std::uint8_t* p, std::size_t n) {
  std::uint64_t v = 0;
  for (std::size_t k = 0; k < n; ++k) v = (v << 8) | p[k];
  // Sign-extend from n bytes.
  const unsigned shift = static_cast<unsigned>(64 - 8 * n);
  return static_cast<std::int64_t>(v << shift) >> shift;
}

// Walks one struct's encoding from `pos`; false with `why` on the first thing that does not fit.
class Walker {
 public:
  Walker(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  bool walk(std::string_view type, std::size_t& pos, std::string& why, int depth) {
    const auto found = schemas().find(type);
    if (found == schemas().end() || depth > 8) {
      why = "unknown type " + std::string(type);
      return false;
    }
    std::map<std::string, std::int64_t, std::less<>> integers;  // Values of the fields walked so far.
    for (const Field& field : found->second) {
      std::uint64_t count = 1;
      for (const Dimension& d : field.dimensions) {
        std::int64_t n = d.fixed;
        if (d.fixed < 0) {
          const auto value = integers.find(d.field);
          if (value == integers.end()) {
            why = "no length field " + d.field;
            return false;
          }
          n = value->second;
        }
        if (n < 0) {
          why = field.name + ": length " + std::to_string(n) + " (from " + d.field + ") is negative";
          return false;
        }
        // Every element takes at least one byte, so a count above the bytes left cannot fit (and
        // the product of two such counts stays far below 2^64). An outer dimension of 0 leaves
        // no element at all, whatever the inner ones (position[num_links][3] with num_links 0).
        if (count != 0 &&
            (static_cast<std::uint64_t>(n) > size_ - pos || count * static_cast<std::uint64_t>(n) > size_ - pos)) {
          why = field.name + ": " + std::to_string(n) + " elements (from " +
                (d.field.empty() ? std::string("a constant") : d.field) + ") in " + std::to_string(size_ - pos) +
                " bytes left";
          return false;
        }
        count *= static_cast<std::uint64_t>(n);
      }
      if (const std::size_t width = primitive_size(field.type)) {
        if (count > (size_ - pos) / width) {
          why = field.name + ": " + std::to_string(count) + " x " + std::to_string(width) + " bytes in " +
                std::to_string(size_ - pos) + " bytes left";
          return false;
        }
        if (field.dimensions.empty() && field.type != "double" && field.type != "float" && field.type != "boolean") {
          integers[field.name] = read_big_endian(data_ + pos, width);
        }
        pos += count * width;
        continue;
      }
      for (std::uint64_t k = 0; k < count; ++k) {
        if (field.type == "string") {
          if (!string_at(field, pos, why)) return false;
        } else if (!walk(field.type, pos, why, depth + 1)) {
          return false;
        }
      }
    }
    return true;
  }

 private:
  bool string_at(const Field& field, std::size_t& pos, std::string& why) {
    if (size_ - pos < 4) {
      why = field.name + ": string length past the end";
      return false;
    }
    const std::int64_t length = read_big_endian(data_ + pos, 4);
    pos += 4;
    if (length < 1 || static_cast<std::uint64_t>(length) > size_ - pos) {
      why = field.name + ": string length " + std::to_string(length) + " with " + std::to_string(size_ - pos) +
            " bytes left (must be 1 .. bytes left, the NUL included)";
      return false;
    }
    if (data_[pos + static_cast<std::size_t>(length) - 1] != 0) {
      why = field.name + ": string not NUL-terminated";
      return false;
    }
    // LCM strings are C strings: a NUL inside one decodes (lcm-gen keeps it) but encodes cut at
    // it, so a subscriber that sends the string on (a controller, a joint's name) sent a message
    // whose lengths no longer match its bytes (found by fuzz/bus_fuzzer.cc).
    if (std::memchr(data_ + pos, 0, static_cast<std::size_t>(length) - 1) != nullptr) {
      why = field.name + ": NUL inside the string";
      return false;
    }
    pos += static_cast<std::size_t>(length);
    return true;
  }

  const std::uint8_t* data_;
  std::size_t size_;
};

}  // namespace

std::string check_encoded(std::string_view type_name, std::int64_t fingerprint, const void* data, std::size_t size) {
  if (data == nullptr || size < 8) return "shorter than a fingerprint (" + std::to_string(size) + " bytes)";
  if (size > kMaxMessageBytes) return std::to_string(size) + " bytes, above the limit of " + std::to_string(kMaxMessageBytes);
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  if (read_big_endian(bytes, 8) != fingerprint) return "not a " + std::string(type_name) + " (fingerprint)";
  std::size_t pos = 8;
  std::string why;
  if (!Walker(bytes, size).walk(type_name, pos, why, 0)) return std::string(type_name) + ": " + why;
  if (pos != size) return std::string(type_name) + ": " + std::to_string(size - pos) + " bytes after the message";
  return "";
}

bool is_message_type(std::string_view type_name) {
  // A struct that another rdtf struct contains (diagnostic_t, link_inertia_t) is only ever
  // encoded inside it, without a fingerprint: one at a datagram's start is no rdtf message, and
  // no subscriber has a handler for it.
  for (const auto& [name, fields] : schemas()) {
    for (const auto& field : fields) {
      if (field.type == type_name) return false;
    }
  }
  return schemas().find(type_name) != schemas().end();
}

std::vector<std::string_view> lcm_type_names() {
  std::vector<std::string_view> names;
  for (std::size_t k = 0; k < kLcmTypeCount; ++k) names.emplace_back(kLcmTypes[k].name);
  return names;
}

std::string_view type_of(const void* data, std::size_t size) {
  if (data == nullptr || size < 8) return "";
  const std::int64_t fingerprint = read_big_endian(static_cast<const std::uint8_t*>(data), 8);
  for (std::size_t k = 0; k < kLcmTypeCount; ++k) {
    if (kLcmTypes[k].fingerprint == fingerprint) return is_message_type(kLcmTypes[k].name) ? kLcmTypes[k].name : "";
  }
  return "";
}

std::string check_known(const void* data, std::size_t size) {
  const std::string_view type = type_of(data, size);
  if (type.empty()) return "not an rdtf type";
  return check_encoded(type, read_big_endian(static_cast<const std::uint8_t*>(data), 8), data, size);
}

namespace {

std::string escaped(std::string_view text, std::size_t max_bytes, bool double_backslashes) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  const std::size_t shown = std::min(text.size(), max_bytes);
  out.reserve(shown + 16);
  for (std::size_t k = 0; k < shown; ++k) {
    const auto c = static_cast<unsigned char>(text[k]);
    if (c == '\\' && double_backslashes) {
      out += "\\\\";
    } else if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  if (shown < text.size()) out += "...(" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace

std::string printable(std::string_view text, std::size_t max_bytes) { return escaped(text, max_bytes, true); }

std::string printable_kept(std::string_view text, std::size_t max_bytes) { return escaped(text, max_bytes, false); }

std::optional<std::string> DropCounter::drop(std::string_view channel, std::string_view why, Clock::time_point now) {
  ++total_;
  ++unreported_;
  if (now < next_line_) {
    // Kept for the line that flush() writes if this burst ends here. Bounded: escaped, at most
    // 80 and 200 bytes shown.
    latest_channel_ = printable(channel, 80);
    latest_why_ = printable_kept(why, 200);
    return std::nullopt;
  }
  latest_channel_ = printable(channel, 80);
  latest_why_ = printable_kept(why, 200);
  return line(now);
}

std::optional<std::string> DropCounter::flush(Clock::time_point now) {
  if (unreported_ == 0 || now < next_line_) return std::nullopt;
  return line(now);
}

std::string DropCounter::line(Clock::time_point now) {
  next_line_ = now + period_;
  std::string text = "dropped " + std::to_string(unreported_) + " message" + (unreported_ == 1 ? "" : "s") +
                     " from the bus (" + std::to_string(total_) + " since start); latest on " + latest_channel_ + ": " +
                     latest_why_;
  unreported_ = 0;
  return text;
}

}  // namespace rdtf::lcm_safe
