#include <iostream>

#include "commands.h"
#include "rdtf/atomic_file.h"
#include "rdtf/urdf.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::cli {
namespace {

struct UrdfArguments {
  ConvertOptions options;
  UrdfOptions urdf;
  std::string input;
  std::string output;
  bool no_mujoco = false;
  bool verbose = false;
  bool sync = false;
};

int run_urdf(UrdfArguments& args) {
  const std::filesystem::path dir(args.output);
  // What can be checked before converting: DIR is a folder (or nothing yet), robot.urdf no folder.
  Diagnostics output_diag(dir.string());
  if (!check_output_folder(dir, {"robot.urdf"}, output_diag)) {
    print_diagnostics(output_diag, true);
    std::cerr << args.input << ": no URDF written (1 error)\n";
    return kExitInvalidInput;
  }
  Diagnostics diag(args.input);
  auto conversion = convert_or_report(args.input, args.options, diag);
  if (!conversion) return kExitInvalidInput;
  args.urdf.mujoco_compiler = !args.no_mujoco;
  Diagnostics urdf_diag(args.input);
  // In memory first, so that every file's place is checked before the first is written.
  auto exported = export_urdf(*conversion, args.urdf, urdf_diag);
  std::vector<std::string> files{"robot.urdf"};
  if (exported) {
    for (const UrdfMeshFile& mesh : exported->meshes) files.push_back(mesh.path);
  }
  const bool usable = exported && check_output_folder(dir, files, output_diag);
  bool written = usable;
  if (usable) {
    // Meshes first, then the URDF that names them (as write_urdf does); a failure takes back
    // what this run created.
    OutputFiles output;
    Diagnostics write_diag(dir.string());
    written = output.make_folder(dir / "meshes", write_diag);
    const Durability durability = args.sync ? Durability::kDurable : Durability::kAtomic;
    for (std::size_t i = 0; written && i <= exported->meshes.size(); ++i) {
      const bool urdf = i == exported->meshes.size();
      const std::filesystem::path path = dir / (urdf ? std::string("robot.urdf") : exported->meshes[i].path);
      output.will_write(path);
      std::string why;
      written = urdf ? write_file_atomically(path, exported->text, why, durability)
                     : write_file_atomically(path, exported->meshes[i].bytes, why, durability);
      if (!written) write_diag.error(codes::WRITE_FAILED, "", "cannot write " + path.string() + ": " + why);
    }
    if (!written) output.roll_back();
    urdf_diag.append(write_diag);
  }
  print_diagnostics(diag, args.verbose);
  print_diagnostics(urdf_diag, args.verbose || !written);
  print_diagnostics(output_diag, true);
  if (!written) {
    const std::size_t errors = urdf_diag.error_count() + output_diag.error_count();
    std::cerr << args.input << ": no URDF written (" << errors << " error" << (errors == 1 ? "" : "s") << ")\n";
    return urdf_diag.contains(codes::WRITE_FAILED) ? kExitInternalError : kExitInvalidInput;
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
  command->add_option("-o,--output", args->output, "The folder to write into (created when missing)")->required();
  command->add_flag("--y-up", args->urdf.y_up,
                    "Keep glTF's Y-up axes (default: turn them to ROS's Z up, (x,y,z) -> (x,-z,y))");
  command->add_option("--mesh-prefix", args->urdf.mesh_uri_prefix,
                      "Put before meshes/<link>.stl in the URDF, e.g. package://my_robot/urdf/ or "
                      "file:///abs/dir/ (a folder: '/' is added when missing; default: a relative path)");
  command->add_flag("--no-mujoco", args->no_mujoco,
                    "Leave out the <mujoco><compiler meshdir=.../></mujoco> element");
  command->add_flag("-v,--verbose", args->verbose, "Also print info diagnostics");
  add_sync_flag(*command, args->sync);
  add_conversion_options(*command, args->options);
  command->callback([args, &exit_code] { exit_code = run_urdf(*args); });
}

}  // namespace rdtf::cli
