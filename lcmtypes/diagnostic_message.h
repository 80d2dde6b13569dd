// rdtf::Diagnostic (core) <-> rdtf::diagnostic_t (LCM): the one mapping of their fields, so that
// every diagnostic_t sent has every field set (LCM's C++ types leave fields uninitialised).
#pragma once

#include <cstdint>
#include <string>
#include <utility>

#include <rdtf/diagnostic_t.hpp>

#include "rdtf/diagnostics.h"

namespace rdtf {

// `text` for an LCM string field. LCM ends a string at its first NUL while sizing it whole, so
// one NUL makes the whole message undecodable; a NUL from a model (a name or URI written
// \u0000 in its JSON) is sent as the four characters \x00, as the log shows it.
inline std::string lcm_text(std::string text) {
  for (std::size_t at = text.find('\0'); at != std::string::npos; at = text.find('\0', at + 4)) {
    text.replace(at, 1, "\\x00");
  }
  return text;
}

inline diagnostic_t to_message(const Diagnostic& d) {
  diagnostic_t m;
  m.severity = d.severity == Severity::kError     ? diagnostic_t::ERROR
               : d.severity == Severity::kWarning ? diagnostic_t::WARNING
                                                  : diagnostic_t::INFO;
  m.code = lcm_text(d.code);
  m.file = lcm_text(d.file);
  m.pointer = lcm_text(d.pointer);
  m.line = d.line > 0 ? static_cast<std::int32_t>(d.line) : 0;
  m.byte_offset = d.byte_offset ? static_cast<std::int64_t>(*d.byte_offset) : -1;
  m.message = lcm_text(d.message);
  return m;
}

// A diagnostic about no file (the daemon's own findings: a rejected command, a failed simulation).
inline diagnostic_t to_message(Severity severity, std::string code, std::string message) {
  Diagnostic d;
  d.severity = severity;
  d.code = std::move(code);
  d.message = std::move(message);
  return to_message(d);
}

// What a received diagnostic_t says; a severity outside INFO..ERROR reads as an error.
inline Diagnostic from_message(const diagnostic_t& m) {
  Diagnostic d;
  d.severity = m.severity == diagnostic_t::INFO      ? Severity::kInfo
               : m.severity == diagnostic_t::WARNING ? Severity::kWarning
                                                     : Severity::kError;
  d.code = m.code;
  d.file = m.file;
  d.pointer = m.pointer;
  d.line = m.line > 0 ? m.line : 0;
  if (m.byte_offset >= 0) d.byte_offset = static_cast<std::uint64_t>(m.byte_offset);
  d.message = m.message;
  return d;
}

}  // namespace rdtf
