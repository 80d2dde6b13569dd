// rdtf validate IN: the dynamics gate (docs/dynamics.md) on the command line. Exit code 0 when
// the model passes, 2 when it fails or cannot be converted, 1 on an internal error.
#include <iostream>
#include <map>

#include "../cli_numbers.h"
#include "commands.h"
#include "rdtf/diagnostics_json.h"
#include "rdtf/dynamics.h"

namespace rdtf::cli {
namespace {

struct ValidateArguments {
  ConvertOptions options;
  ValidationOptions validation;
  std::string input;
  std::vector<double> gravity;
  std::string massless_links = "warning";
  bool json = false;
  bool verbose = false;
};

int run_validate(ValidateArguments& args) {
  Diagnostics diag(args.input);
  const auto conversion = convert_or_report(args.input, args.options, diag);
  if (!conversion) {
    // Not converted, so not checked: the report a script reads says so, with the errors.
    if (args.json) {
      Json out = {{"passed", false}, {"converted", false}, {"simulated", false},
                  {"diagnostics", Json::array()}, {"conversionDiagnostics", Json::array()}};
      for (const Diagnostic& d : diag.all()) {
        if (d.severity != Severity::kInfo || args.verbose) out["conversionDiagnostics"].push_back(diagnostic_json(d));
      }
      std::cout << out.dump(2, ' ', false, Json::error_handler_t::replace) << "\n";
    }
    return kExitInvalidInput;
  }
  args.validation.checks.massless_link_error = args.massless_links == "error";
  if (!args.gravity.empty()) {
    args.validation.simulation.gravity = {args.gravity[0], args.gravity[1], args.gravity[2]};
  }
  const ValidationReport report = validate_dynamics(*conversion, args.validation, args.input);
  if (args.json) {
    Json out = validation_report_json(report);
    out["converted"] = true;
    out["conversionDiagnostics"] = Json::array();
    for (const Diagnostic& d : diag.all()) {
      if (d.severity != Severity::kInfo || args.verbose) {
        out["conversionDiagnostics"].push_back(diagnostic_json(d));
      }
    }
    std::cout << out.dump(2, ' ', false, Json::error_handler_t::replace) << "\n";
  } else {
    print_diagnostics(diag, args.verbose);
    print_diagnostics(report.diagnostics, args.verbose);
    std::cout << args.input << ": " << validation_summary_line(report) << "\n";
  }
  return report.passed ? kExitOk : kExitInvalidInput;
}

}  // namespace

void add_validate_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ValidateArguments>();
  CLI::App* command = app.add_subcommand(
      "validate", "Check the physics and simulate the model in ODE (exit 0 pass, 2 fail)");
  command->add_option("input", args->input, "The glTF or RDTF model")->required();
  command->add_flag("--json", args->json, "Print the report as JSON");
  command->add_option("--seconds", args->validation.duration, "Simulated time of the passive run")
      ->check(rdtf::cli_numbers::kNonNegative)
      ->capture_default_str();
  command->add_option("--start-offset", args->validation.start_offset_angular,
                      "Start every revolute and continuous joint this far (rad, either sign) from rest, or "
                      "the other way where its limits do not allow it; 0: the rest pose (rdtfd's "
                      "validation_start_offset_rad)")
      ->check(CLI::Range(-6.2832, 6.2832))
      ->capture_default_str();
  command->add_option("--time-step", args->validation.simulation.time_step, "ODE time step (s)")
      ->check(rdtf::cli_numbers::kPositive)
      ->capture_default_str();
  command->add_option("--stepper", args->validation.simulation.stepper,
                      "auto (dWorldStep while the largest island has fewer than 27 bodies, QuickStep from "
                      "27, and dWorldStep again up to 100 bodies if QuickStep's run fails), world_step or "
                      "quick_step (rdtfd's stepper)")
      ->transform(CLI::CheckedTransformer(std::map<std::string, Stepper>{{"auto", Stepper::kAuto},
                                                                          {"world_step", Stepper::kWorldStep},
                                                                          {"quick_step", Stepper::kQuickStep}}))
      ->default_str("auto");
  command->add_flag("--floating", args->validation.simulation.floating_root,
                    "Let the root link float instead of fixing it to the world");
  command->add_option("--gravity", args->gravity,
                      "Gravity in the scene frame, m/s^2 (default 0 -9.80665 0: glTF is Y up; "
                      "a Z-up model: 0 0 -9.80665)")
      ->expected(3);
  command->add_option("--max-mass-ratio", args->validation.checks.max_mass_ratio,
                      "Largest mass ratio across a joint")
      ->check(rdtf::cli_numbers::kPositive)
      ->capture_default_str();
  command->add_option("--bound-mass", args->validation.simulation.bound_mass,
                      "Mass (kg) given to a moving body without mass, with --bound-inertia "
                      "(MuJoCo's boundmass); 0: off, such a link fails")
      ->check(rdtf::cli_numbers::kNonNegative)
      ->capture_default_str();
  command->add_option("--bound-inertia", args->validation.simulation.bound_inertia,
                      "Inertia (kg m^2 about each axis) given to a moving body without mass, with "
                      "--bound-mass (MuJoCo's boundinertia); 0: off")
      ->check(rdtf::cli_numbers::kNonNegative)
      ->capture_default_str();
  command->add_option("--massless-links", args->massless_links,
                      "With a bound mass, a massless moving link is a warning or still an error")
      ->check(CLI::IsMember({"warning", "error"}))
      ->capture_default_str();
  command->add_option("--cpu-budget", args->validation.cpu_budget,
                      "CPU seconds the check may take; beyond, it fails with SIM_BUDGET_EXCEEDED (0: no limit)")
      ->check(rdtf::cli_numbers::kNonNegative)
      ->capture_default_str();
  command->add_flag("-v,--verbose", args->verbose, "Also print info diagnostics");
  add_conversion_options(*command, args->options);
  command->callback([args, &exit_code] { exit_code = run_validate(*args); });
}

}  // namespace rdtf::cli
