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

// RFC 4648 base64 with padding: the payload of a glTF data: URI.
std::string base64(const std::vector<std::uint8_t>& bytes);

}  // namespace rdtf::testing
