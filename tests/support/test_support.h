// Shared helpers for the tests: where the data is, temporary folders, and the Khronos validator.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rdtf::testing {

std::filesystem::path data_dir();  // tests/data

// A fresh folder under the system temp dir, removed when the object goes away.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

void write_file(const std::filesystem::path& path, const std::string& bytes);
std::string read_file(const std::filesystem::path& path);

// Runs the Khronos glTF validator (npm gltf-validator, through tools/gltf-validator/validate.mjs)
// on a file and returns its report. Fails the calling test if the validator cannot run.
nlohmann::json khronos_report(const std::filesystem::path& model);

struct CommandResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};
// Runs a shell command, capturing stdout and stderr.
CommandResult run_command(const std::string& command);

std::string cli_path();  // The built `rdtf` executable.

// Leaves the process exactly `headroom` descriptors free until destroyed: every free slot up to
// the highest descriptor open is filled (with /dev/null) and the open-file limit set `headroom`
// above. The headroom is then the same on any machine: a CI runner holds descriptors 0-3, a
// terminal may hold 255 with 250 free slots below it. The destructor restores limit and slots.
class DescriptorHeadroom {
 public:
  explicit DescriptorHeadroom(int headroom);
  ~DescriptorHeadroom();
  DescriptorHeadroom(const DescriptorHeadroom&) = delete;
  DescriptorHeadroom& operator=(const DescriptorHeadroom&) = delete;
  bool ok() const { return ok_; }  // false (and nothing changed) if the limit could not be set

 private:
  std::vector<int> fillers_;
  std::uint64_t limit_before_ = 0;
  bool ok_ = false;
};

// RFC 4648 base64 with padding: the payload of a glTF data: URI.
std::string base64(const std::vector<std::uint8_t>& bytes);

}  // namespace rdtf::testing
