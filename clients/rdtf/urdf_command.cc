#include <iostream>

#include "commands.h"
#include "rdtf/urdf.h"

namespace rdtf::cli {
namespace {

struct UrdfArguments {
  ConvertOptions options;
  UrdfOptions urdf;
  std::string input;
  std::string output;
  bool no_mujoco = false;
  bool verbose = false;
};

int run_urdf(UrdfArguments& args) {
  Diagnostics diag(args.input);
  auto conversion = convert_or_report(args.input, args.options, diag);
  if (!conversion) return kExitInvalidInput;
  args.urdf.mujoco_compiler = !args.no_mujoco;
  const std::filesystem::path dir(args.output);
  Diagnostics urdf_diag(args.input);
  const bool written = write_urdf(*conversion, dir, args.urdf, urdf_diag);
  print_diagnostics(diag, args.verbose);
  print_diagnostics(urdf_diag, args.verbose || !written);
  if (!written) {
    const bool write_failed = urdf_diag.contains("WRITE_FAILED");
    std::cerr << args.input << ": no URDF written (" << urdf_diag.error_count() << " error"
              << (urdf_diag.error_count() == 1 ? "" : "s") << ")\n";
    return write_failed ? kExitInternalError : kExitInvalidInput;
  }
  std::cerr << "wrote " << (dir / "robot.urdf").string() << " and " << (dir / "meshes").string()
            << "/: " << conversion->robot.links.size() << " links, "
            << conversion->robot.joints.size() << " joints\n";
  return kExitOk;
}

}  // namespace

void add_urdf_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<UrdfArguments>();
  CLI::App* command = app.add_subcommand(
      "urdf", "Convert a glTF or RDTF model to URDF: DIR/robot.urdf and DIR/meshes/<link>.stl");
  command->add_option("input", args->input, "The glTF or RDTF model")->required();
  command->add_option("-o,--output", args->output, "The folder to write into")->required();
  command->add_flag("--y-up", args->urdf.y_up,
                    "Keep glTF's Y-up axes (default: turn them to ROS's Z up, (x,y,z) -> (x,-z,y))");
  command->add_option("--mesh-prefix", args->urdf.mesh_uri_prefix,
                      "Put before meshes/<link>.stl in the URDF, e.g. package://my_robot/urdf/ or "
                      "file:///abs/dir/ (default: a relative path)");
  command->add_flag("--no-mujoco", args->no_mujoco,
                    "Leave out the <mujoco><compiler meshdir=.../></mujoco> element");
  command->add_flag("-v,--verbose", args->verbose, "Also print info diagnostics");
  add_conversion_options(*command, args->options);
  command->callback([args, &exit_code] { exit_code = run_urdf(*args); });
}

}  // namespace rdtf::cli
