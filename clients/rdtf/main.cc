// rdtf: the one-shot command line over librdtf. `rdtf --help` lists the commands.
// Exit codes: 0 success, 2 invalid input (diagnostics on stderr), 1 internal error.
#include <exception>
#include <iostream>
#include <string>

#include "commands.h"
#include "rdtf/version.h"

int main(int argc, char** argv) {
  CLI::App app{"rdtf: turns glTF 2.0 models into RDTF robot descriptions (glTF + extras.RDTF)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", rdtf::version_line("rdtf"));
  int exit_code = rdtf::cli::kExitOk;
  rdtf::cli::add_convert_command(app, exit_code);
  rdtf::cli::add_inspect_command(app, exit_code);
  rdtf::cli::add_urdf_command(app, exit_code);
  rdtf::cli::add_import_command(app, exit_code);
  rdtf::cli::add_validate_command(app, exit_code);
  rdtf::cli::add_pull_command(app, exit_code);
  // A first word that is no command is named (CLI11 answers "A subcommand is required", which
  // leaves a script's author guessing which word it did not know).
  if (argc > 1) {
    const std::string first = argv[1];
    const bool flag = first == "-h" || first == "--help" || first == "--version";
    bool known = flag;
    std::string commands;
    for (const CLI::App* command : app.get_subcommands({})) {
      known = known || command->check_name(first);
      commands += (commands.empty() ? "" : ", ") + command->get_name();
    }
    if (!known) {
      std::cerr << "rdtf: " << (first.rfind('-', 0) == 0 ? "unknown option '" : "unknown command '") << first
                << "'; the commands are " << commands << " (rdtf --help; rdtf COMMAND --help)\n";
      return static_cast<int>(CLI::ExitCodes::ExtrasError);
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  } catch (const std::exception& error) {
    std::cerr << "rdtf: internal error: " << error.what() << "\n";
    return rdtf::cli::kExitInternalError;
  }
  return exit_code;
}
