#include <iostream>

#include "commands.h"
#include "rdtf/urdf.h"
#include "rdtf/write.h"

namespace rdtf::cli {
namespace {

struct ImportArguments {
  UrdfImportOptions options;
  std::string input;
  std::string output;
  bool glb = false;
  bool verbose = false;
};

int run_import(ImportArguments& args) {
  Diagnostics diag(args.input);
  auto conversion = import_urdf(args.input, args.options, diag);
  if (!conversion) {
    print_diagnostics(diag, true);
    std::cerr << args.input << ": not imported (" << diag.error_count() << " error"
              << (diag.error_count() == 1 ? "" : "s") << ")\n";
    return kExitInvalidInput;
  }
  const std::filesystem::path target(args.output);
  const bool glb = args.glb || target.extension() == ".glb";
  Diagnostics write_diag(target.string());
  const bool written = write_rdtf(conversion->asset, target,
                                  glb ? OutputFormat::kGlb : OutputFormat::kGltf, write_diag);
  print_diagnostics(diag, args.verbose);
  print_diagnostics(write_diag, args.verbose);
  if (!written) return kExitInternalError;
  std::cerr << "wrote " << target.string() << ": " << conversion->robot.links.size() << " links, "
            << conversion->robot.joints.size() << " joints\n";
  return kExitOk;
}

}  // namespace

void add_import_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ImportArguments>();
  CLI::App* command = app.add_subcommand(
      "import", "Import a URDF as RDTF (glTF + extras.RDTF); STL, box, cylinder and sphere geometry");
  command->add_option("input", args->input, "The URDF file")->required();
  command->add_option("-o,--output", args->output, "The .gltf or .glb to write")->required();
  command->add_flag("--glb", args->glb, "Write a binary .glb (implied by a .glb name)");
  command->add_flag("--z-up", args->options.z_up,
                    "Keep URDF's Z-up axes (default: turn them to glTF's Y up, (x,y,z) -> (x,z,-y))");
  command->add_flag("-v,--verbose", args->verbose, "Also print info diagnostics");
  add_conversion_options(*command, args->options.convert);
  command->callback([args, &exit_code] { exit_code = run_import(*args); });
}

}  // namespace rdtf::cli
