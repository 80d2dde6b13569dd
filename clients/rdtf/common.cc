#include <iostream>

#include "commands.h"
#include "rdtf/write.h"

namespace rdtf::cli {

void add_conversion_options(CLI::App& command, ConvertOptions& options) {
  command.add_option("--density", options.default_density,
                     "Density (kg/m^3) of meshes whose nodes set no rdtf_density")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command.add_option("--max-file-bytes", options.limits.max_file_bytes,
                     "Largest model or external file read")
      ->capture_default_str();
  command.add_option("--max-buffer-bytes", options.limits.max_buffer_bytes,
                     "Largest sum of buffer byteLengths")
      ->capture_default_str();
  command.add_option("--max-accessor-count", options.limits.max_accessor_count,
                     "Most elements in one accessor")
      ->capture_default_str();
  command.add_option("--max-triangles", options.limits.max_triangles,
                     "Most triangles in the whole model")
      ->capture_default_str();
}

void print_diagnostics(const Diagnostics& diag, bool include_infos) {
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kInfo && !include_infos) continue;
    std::cerr << format(d) << "\n";
  }
}

void report_failure(const std::string& input, const char* verb, const Diagnostics& diag) {
  print_diagnostics(diag, true);
  std::cerr << input << ": not " << verb << " (" << diag.error_count() << " error"
            << (diag.error_count() == 1 ? "" : "s") << ")\n";
}

int write_conversion(const Conversion& conversion, const std::filesystem::path& target, bool glb,
                     const Diagnostics& diag, bool verbose) {
  Diagnostics write_diag(target.string());
  const bool written = write_rdtf(conversion.asset, target,
                                  glb ? OutputFormat::kGlb : OutputFormat::kGltf, write_diag);
  print_diagnostics(diag, verbose);
  print_diagnostics(write_diag, verbose);
  if (!written) return kExitInternalError;
  std::cerr << "wrote " << target.string() << ": " << conversion.robot.links.size() << " links, "
            << conversion.robot.joints.size() << " joints\n";
  return kExitOk;
}

std::optional<Conversion> convert_or_report(const std::string& input, const ConvertOptions& options,
                                            Diagnostics& diag) {
  auto conversion = convert_file(input, options, diag);
  if (!conversion) report_failure(input, "converted", diag);
  return conversion;
}

}  // namespace rdtf::cli
