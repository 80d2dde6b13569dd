#include "rdtf/diagnostics_json.h"

#include "rdtf/utf8.h"

namespace rdtf {

std::string json_safe(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t length = utf8_sequence_length(text, i);
    if (length == 0) {
      out += "\xEF\xBF\xBD";
      ++i;
    } else {
      out.append(text, i, length);
      i += length;
    }
  }
  return out;
}

Json diagnostic_json(const Diagnostic& d) {
  Json item = {{"severity", to_string(d.severity)}, {"code", json_safe(d.code)}, {"file", json_safe(d.file)},
               {"pointer", json_safe(d.pointer)}};
  if (d.line > 0) item["line"] = d.line;
  item["message"] = json_safe(d.message);
  if (d.byte_offset) item["byteOffset"] = *d.byte_offset;
  return item;
}

Json diagnostics_json(const Diagnostics& diagnostics) {
  Json out = Json::array();
  for (const Diagnostic& d : diagnostics.all()) out.push_back(diagnostic_json(d));
  return out;
}

}  // namespace rdtf
