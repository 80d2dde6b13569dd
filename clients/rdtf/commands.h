// The subcommands of `rdtf`, one file each. Each adds itself to the app; its callback runs the
// command and stores the process exit code.
#pragma once

#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>

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

// Options shared by every command that converts: density and the input limits.
void add_conversion_options(CLI::App& command, ConvertOptions& options);

// Diagnostics on stderr, one line each (infos only when asked).
void print_diagnostics(const Diagnostics& diag, bool include_infos);

// "<input>: not <verb> (N errors)" after the diagnostics, on stderr.
void report_failure(const std::string& input, const char* verb, const Diagnostics& diag);

// Writes a conversion's RDTF to `target` (.glb when `glb`), prints the diagnostics of the
// conversion and of the write, and a one-line summary. Returns the process exit code.
int write_conversion(const Conversion& conversion, const std::filesystem::path& target, bool glb,
                     const Diagnostics& diag, bool verbose);

// Converts `input`, printing diagnostics and a one-line verdict on failure.
std::optional<Conversion> convert_or_report(const std::string& input, const ConvertOptions& options,
                                            Diagnostics& diag);

}  // namespace rdtf::cli
