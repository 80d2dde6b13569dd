// Diagnostics: what went wrong (or is worth knowing) about untrusted input, as plain values.
//
// Every stage of the pipeline appends to a Diagnostics list instead of throwing; the caller decides
// what to do with them (print, publish on LCM, fail). Each diagnostic names the file and a place in
// it: a JSON pointer (RFC 6901) as the Khronos validator reports it, a byte offset in a GLB, or for
// URDF an XPath-like path and the line. docs/diagnostics.md lists every code.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rdtf {

enum class Severity { kInfo, kWarning, kError };

std::string_view to_string(Severity severity);

struct Diagnostic {
  Severity severity = Severity::kError;
  std::string code;     // Stable, machine-readable, e.g. "ACCESSOR_TOO_LONG" (docs/diagnostics.md).
  std::string file;     // The file the problem is in (may be empty for in-memory input).
  // The place in the file: for glTF a JSON pointer into the document ("/accessors/3/count"), for
  // URDF a path of elements and attributes ("/robot/joint[@name='elbow']/limit/@effort").
  std::string pointer;
  int line = 0;  // For text formats read by line (URDF): the line, from 1; 0 when none.
  std::optional<std::uint64_t> byte_offset;  // For GLB container problems.
  std::string message;  // Human-readable; says what is wrong and, where useful, what to do.
};

// "file:/pointer: error CODE: message" - one line, the form the CLI prints on stderr.
std::string format(const Diagnostic& diagnostic);

class Diagnostics {
 public:
  explicit Diagnostics(std::string file = {}) : file_(std::move(file)) {}

  // The file that diagnostics added from now on are about.
  void set_file(std::string file) { file_ = std::move(file); }
  const std::string& file() const { return file_; }

  void add(Severity severity, std::string code, std::string pointer, std::string message);
  void error(std::string code, std::string pointer, std::string message) {
    add(Severity::kError, std::move(code), std::move(pointer), std::move(message));
  }
  void warning(std::string code, std::string pointer, std::string message) {
    add(Severity::kWarning, std::move(code), std::move(pointer), std::move(message));
  }
  void info(std::string code, std::string pointer, std::string message) {
    add(Severity::kInfo, std::move(code), std::move(pointer), std::move(message));
  }
  void error_at_offset(std::string code, std::uint64_t offset, std::string message);
  // A problem on a line of a text file (URDF). The message starts with "line N: " too, so that it
  // reads whole where only the message is shown.
  void add_at_line(Severity severity, std::string code, std::string pointer, int line, const std::string& message);
  void error_at_line(std::string code, std::string pointer, int line, const std::string& message) {
    add_at_line(Severity::kError, std::move(code), std::move(pointer), line, message);
  }
  void warning_at_line(std::string code, std::string pointer, int line, const std::string& message) {
    add_at_line(Severity::kWarning, std::move(code), std::move(pointer), line, message);
  }
  void append(const Diagnostics& other);

  bool has_errors() const { return error_count_ > 0; }
  std::size_t error_count() const { return error_count_; }
  const std::vector<Diagnostic>& all() const { return items_; }
  bool contains(std::string_view code) const;
  // The first error added, or nullptr when there is none.
  const Diagnostic* first_error() const;

 private:
  std::string file_;
  std::vector<Diagnostic> items_;
  std::size_t error_count_ = 0;
};

// A number as a diagnostic or a report shows it: printf's %g with this many significant digits
// ("0.5", "1.2e+06"; 9 digits give every float back exactly). One helper for every message.
std::string format_number(double value, int significant_digits = 6);

// Appends a reference token to a JSON pointer, escaping '~' and '/' as RFC 6901 requires.
std::string json_pointer(std::string_view base, std::string_view token);
std::string json_pointer(std::string_view base, std::size_t index);

}  // namespace rdtf
