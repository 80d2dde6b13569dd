// Files as the tests write them (in place, by rename, piecewise) and read the daemon's outputs.
#pragma once

#include <fcntl.h>

#include <map>
#include <string>

#include "support/harness/basics.h"

namespace rdtf::itest {

inline std::string read(const fs::path& path) { return testing::read_file(path); }

// Writes in place (open with O_TRUNC, write, close), as Blender does.
void write_in_place(const fs::path& path, const std::string& bytes);

// Writes `temp` in full, then renames it over `path` (what most editors do).
void write_by_rename(const fs::path& path, const std::string& bytes, const std::string& temp_name);

// An open file written in several pieces, closed at the end (or by the destructor).
class OpenFile {
 public:
  explicit OpenFile(const fs::path& path, int flags = O_WRONLY | O_CREAT | O_TRUNC);
  ~OpenFile() { close(); }
  OpenFile(const OpenFile&) = delete;
  OpenFile& operator=(const OpenFile&) = delete;
  void write(const std::string& bytes);
  void close();

 private:
  int fd_;
};

// Every regular file below `folder` (relative path -> bytes): what a reader of the outputs finds.
// The daemon's revision state (<output>/.rdtfd-state, docs/daemon.md) is no output: left out.
std::map<std::string, std::string> snapshot(const fs::path& folder);

// A fixture (tests/data/blender/<stem>.gltf and its .bin) copied into `folder`.
fs::path copy_fixture(const fs::path& folder, const std::string& stem, const std::string& as = "");

// The daemon's content_hash of a fixture.
std::string fixture_hash(const std::string& stem);

// `rdtf inspect --json` of a file: {"links": [{"name", "mass", ...}], ...}.
Json inspect(const fs::path& model, const std::string& options = "");

}  // namespace rdtf::itest
