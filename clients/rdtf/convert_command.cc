#include "commands.h"
#include "rdtf/glb.h"

namespace rdtf::cli {
namespace {

struct ConvertArguments {
  ConvertOptions options;
  std::string input;
  std::string output;
  bool glb = false;
  bool verbose = false;
  bool sync = false;
};

std::filesystem::path default_output(const std::filesystem::path& input, bool glb) {
  std::filesystem::path output = input;
  output.replace_extension(glb ? ".rdtf.glb" : ".rdtf.gltf");
  return output;
}

int run_convert(ConvertArguments& args) {
  bool glb = args.glb;
  if (!args.output.empty() && has_glb_extension(args.output)) glb = true;  // ARM.GLB too
  const std::filesystem::path target = args.output.empty() ? default_output(args.input, glb)
                                                           : std::filesystem::path(args.output);
  // The output first: a folder given as the output would fail only after the .bin was written.
  Diagnostics output_diag(target.string());
  if (!check_output_file(target, default_output(std::filesystem::path(args.input).filename(), glb).string(),
                         output_diag)) {
    report_failure(args.input, "converted", output_diag);
    return kExitInvalidInput;
  }
  Diagnostics diag(args.input);
  auto conversion = convert_or_report(args.input, args.options, diag);
  if (!conversion) return kExitInvalidInput;
  return write_conversion(*conversion, target, glb, diag, args.verbose,
                          args.sync ? Durability::kDurable : Durability::kAtomic);
}

}  // namespace

void add_convert_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ConvertArguments>();
  CLI::App* command = app.add_subcommand("convert", "Convert a glTF (.gltf or .glb) to RDTF");
  command->add_option("input", args->input, "The glTF model")->required();
  command->add_option("-o,--output", args->output,
                      "Where to write (default: beside the input, NAME.rdtf.gltf or .glb); a "
                      ".glb name implies --glb; its folder is created when missing");
  command->add_flag("--glb", args->glb, "Write a binary .glb with every buffer and image embedded");
  command->add_flag("-v,--verbose", args->verbose, "Also print info diagnostics");
  add_sync_flag(*command, args->sync);
  command->add_flag("--no-khr-physics{false}", args->options.khr_physics,
                    "Do not write KHR_physics_rigid_bodies (motion and joints) beside extras.RDTF");
  add_conversion_options(*command, args->options);
  command->callback([args, &exit_code] { exit_code = run_convert(*args); });
}

}  // namespace rdtf::cli
