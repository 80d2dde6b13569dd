// The subcommands of `rdtf`, one file each. Each adds itself to the app; its callback runs the
// command and stores the process exit code.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "rdtf/atomic_file.h"
#include "rdtf/convert.h"
#include "rdtf/diagnostics.h"

namespace rdtf::cli {

inline constexpr int kExitOk = 0;
inline constexpr int kExitInternalError = 1;
inline constexpr int kExitInvalidInput = 2;

void add_convert_command(CLI::App& app, int& exit_code);
void add_inspect_command(CLI::App& app, int& exit_code);
void add_urdf_command(CLI::App& app, int& exit_code);
void add_import_command(CLI::App& app, int& exit_code);
void add_validate_command(CLI::App& app, int& exit_code);
void add_pull_command(CLI::App& app, int& exit_code);

// Options shared by every command that converts: density and the input limits.
void add_conversion_options(CLI::App& command, ConvertOptions& options);

// Diagnostics on stderr, one line each (infos only when asked).
void print_diagnostics(const Diagnostics& diag, bool include_infos);

// "<input>: not <verb> (N errors)" after the diagnostics, on stderr.
void report_failure(const std::string& input, const char* verb, const Diagnostics& diag);

// Output paths, checked before anything is converted or written, so that a predictable failure
// writes nothing: an error OUTPUT_PATH_INVALID (exit 2) names the path.
// A file: not one ending in '/', not an existing folder or device, not below a file (folders that
// do not exist yet are fine: they are created). `example` names a file for the message.
bool check_output_file(const std::filesystem::path& target, const std::string& example, Diagnostics& diag);
// A folder (`rdtf urdf`): not an existing file, not below a file; and each of `files` (relative to
// it) can be written: not a folder or device, not below a file.
bool check_output_folder(const std::filesystem::path& dir, const std::vector<std::string>& files,
                         Diagnostics& diag);

// What one command's output created, so that a failed write takes it back: no partial output.
class OutputFiles {
 public:
  // Notes `path` before it is written: when it does not exist yet, roll_back removes it.
  void will_write(const std::filesystem::path& path);
  // Creates `folder` and any missing folder above it (WRITE_FAILED when it cannot), noting them.
  bool make_folder(const std::filesystem::path& folder, Diagnostics& diag);
  // Removes the new files, then the new folders that are empty.
  void roll_back();

 private:
  std::vector<std::filesystem::path> new_files_;
  std::vector<std::filesystem::path> new_folders_;  // Deepest first.
};

// Writes a conversion's RDTF to `target` (.glb when `glb`), prints the diagnostics of the
// conversion and of the write, and a one-line summary. Creates the target's folder; checks that
// every file of the output can be written first (exit 2 when one cannot, nothing written); takes
// back what it created when a write fails (exit 1). Returns the process exit code. `durability`:
// whether the output is fsynced before the command returns (--sync), or only renamed into place.
int write_conversion(const Conversion& conversion, const std::filesystem::path& target, bool glb,
                     const Diagnostics& diag, bool verbose, Durability durability);

// Adds --sync: the output made durable (fsynced) before the command returns.
void add_sync_flag(CLI::App& command, bool& sync);

// Converts `input`, printing diagnostics and a one-line verdict on failure.
std::optional<Conversion> convert_or_report(const std::string& input, const ConvertOptions& options,
                                            Diagnostics& diag);

}  // namespace rdtf::cli
