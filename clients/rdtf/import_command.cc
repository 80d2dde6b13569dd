#include "commands.h"
#include "rdtf/glb.h"
#include "rdtf/urdf.h"

namespace rdtf::cli {
namespace {

struct ImportArguments {
  UrdfImportOptions options;
  std::string input;
  std::string output;
  bool glb = false;
  bool verbose = false;
  bool sync = false;
};

int run_import(ImportArguments& args) {
  const std::filesystem::path target(args.output);
  const bool glb = args.glb || has_glb_extension(target);  // R2.GLB too
  // The output first: a folder given as the output would fail only after the .bin was written.
  Diagnostics output_diag(target.string());
  if (!check_output_file(target, glb ? "robot.glb" : "robot.gltf", output_diag)) {
    report_failure(args.input, "imported", output_diag);
    return kExitInvalidInput;
  }
  Diagnostics diag(args.input);
  auto conversion = import_urdf(args.input, args.options, diag);
  if (!conversion) {
    report_failure(args.input, "imported", diag);
    return kExitInvalidInput;
  }
  return write_conversion(*conversion, target, glb, diag, args.verbose,
                          args.sync ? Durability::kDurable : Durability::kAtomic);
}

}  // namespace

void add_import_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ImportArguments>();
  CLI::App* command = app.add_subcommand(
      "import", "Import a URDF as RDTF (glTF + extras.RDTF); STL, COLLADA and OBJ meshes, boxes, cylinders and spheres");
  command->add_option("input", args->input, "The URDF file")->required();
  command->add_option("-o,--output", args->output, "The .gltf or .glb to write (its folder is created when missing)")
      ->required();
  command->add_flag("--glb", args->glb, "Write a binary .glb (implied by a .glb name)");
  command->add_flag("--z-up", args->options.z_up,
                    "Keep URDF's Z-up axes (default: turn them to glTF's Y up, (x,y,z) -> (x,z,-y))");
  command->add_flag("-v,--verbose", args->verbose, "Also print info diagnostics");
  add_sync_flag(*command, args->sync);
  add_conversion_options(*command, args->options.convert);
  command->callback([args, &exit_code] { exit_code = run_import(*args); });
}

}  // namespace rdtf::cli
