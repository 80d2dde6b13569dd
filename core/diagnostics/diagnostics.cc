#include "rdtf/diagnostics.h"

#include <algorithm>
#include <cstdio>

namespace rdtf {

std::string_view to_string(Severity severity) {
  switch (severity) {
    case Severity::kInfo:
      return "info";
    case Severity::kWarning:
      return "warning";
    case Severity::kError:
      return "error";
  }
  return "error";
}

std::string format_number(double value, int significant_digits) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.*g", significant_digits, value);
  return text;
}

std::string format(const Diagnostic& d) {
  std::string place = d.file.empty() ? std::string("<input>") : d.file;
  if (!d.pointer.empty()) {
    place += ":" + d.pointer;
  } else if (d.byte_offset) {
    place += ":@" + std::to_string(*d.byte_offset);
  }
  return place + ": " + std::string(to_string(d.severity)) + " " + d.code + ": " + d.message;
}

void Diagnostics::add(Severity severity, std::string code, std::string pointer,
                      std::string message) {
  Diagnostic d;
  d.severity = severity;
  d.code = std::move(code);
  d.file = file_;
  d.pointer = std::move(pointer);
  d.message = std::move(message);
  if (severity == Severity::kError) ++error_count_;
  items_.push_back(std::move(d));
}

void Diagnostics::add_at_line(Severity severity, std::string code, std::string pointer, int line,
                              const std::string& message) {
  add(severity, std::move(code), std::move(pointer), "line " + std::to_string(line) + ": " + message);
  items_.back().line = line;
}

void Diagnostics::error_at_offset(std::string code, std::uint64_t offset, std::string message) {
  Diagnostic d;
  d.severity = Severity::kError;
  d.code = std::move(code);
  d.file = file_;
  d.byte_offset = offset;
  d.message = std::move(message);
  ++error_count_;
  items_.push_back(std::move(d));
}

void Diagnostics::append(const Diagnostics& other) {
  for (const Diagnostic& d : other.items_) {
    if (d.severity == Severity::kError) ++error_count_;
    items_.push_back(d);
  }
}

bool Diagnostics::contains(std::string_view code) const {
  return std::any_of(items_.begin(), items_.end(),
                     [&](const Diagnostic& d) { return d.code == code; });
}

const Diagnostic* Diagnostics::first_error() const {
  const auto error = std::find_if(items_.begin(), items_.end(),
                                  [](const Diagnostic& d) { return d.severity == Severity::kError; });
  return error == items_.end() ? nullptr : &*error;
}

std::string json_pointer(std::string_view base, std::string_view token) {
  std::string out(base);
  out += '/';
  for (char c : token) {
    if (c == '~') {
      out += "~0";
    } else if (c == '/') {
      out += "~1";
    } else {
      out += c;
    }
  }
  return out;
}

std::string json_pointer(std::string_view base, std::size_t index) {
  return std::string(base) + "/" + std::to_string(index);
}

}  // namespace rdtf
