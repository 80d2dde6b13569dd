#include <iostream>

#include "commands.h"
#include "rdtf/diagnostics_json.h"
#include "rdtf/summary.h"

namespace rdtf::cli {
namespace {

struct InspectArguments {
  ConvertOptions options;
  std::string input;
  bool json = false;
};

int run_inspect(const InspectArguments& args) {
  Diagnostics diag(args.input);
  const auto conversion = convert_or_report(args.input, args.options, diag);
  if (!conversion) {
    // A script reading --json gets the errors as JSON too, with their places as fields.
    if (args.json) {
      const Json out = {{"converted", false}, {"diagnostics", diagnostics_json(diag)}};
      std::cout << out.dump(2, ' ', false, Json::error_handler_t::replace) << "\n";
    }
    return kExitInvalidInput;
  }
  if (args.json) {
    Json out = robot_summary(conversion->robot, conversion->asset.document, diag);
    out["converted"] = true;
    std::cout << out.dump(2, ' ', false, Json::error_handler_t::replace) << "\n";
  } else {
    std::cout << robot_table(conversion->robot, diag);
  }
  return kExitOk;
}

}  // namespace

void add_inspect_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<InspectArguments>();
  CLI::App* command =
      app.add_subcommand("inspect", "Print the links, joints, mass, centre of mass and inertia");
  command->add_option("input", args->input, "The glTF or RDTF model")->required();
  command->add_flag("--json", args->json, "Print JSON for machines instead of a table");
  add_conversion_options(*command, args->options);
  command->callback([args, &exit_code] { exit_code = run_inspect(*args); });
}

}  // namespace rdtf::cli
