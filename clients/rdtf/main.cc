// rdtf: the one-shot command line over librdtf. `rdtf --help` lists the commands.
// Exit codes: 0 success, 2 invalid input (diagnostics on stderr), 1 internal error.
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>

#include "commands.h"
#include "rdtf/version.h"

namespace {

// What a script reads from stdout must be whole: a report cut short by a full disk, /dev/full or a
// closed stdout is a failure (as coreutils' close_stdout makes it), not exit 0 with half a JSON.
int with_stdout_checked(int exit_code) {
  errno = 0;
  std::cout.flush();
  const bool failed = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout) != 0;
  if (!failed) return exit_code;
  const int error = errno;
  // errno is the flush's; a write that failed earlier (stdio's buffer filled) left no reason.
  std::cerr << "rdtf: could not write to standard output"
            << (error != 0 ? std::string(": ") + std::strerror(error) : " (a full disk, or stdout closed?)")
            << "; what was printed is incomplete\n";
  return exit_code == rdtf::cli::kExitOk ? rdtf::cli::kExitInternalError : exit_code;
}

}  // namespace

int main(int argc, char** argv) {
  // A file-size limit (ulimit -f, systemd's LimitFSIZE) fails the write with EFBIG, which is
  // reported (WRITE_FAILED) and leaves no half-written output; its signal would kill the process
  // mid-write.
  std::signal(SIGXFSZ, SIG_IGN);
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
    const int code = app.exit(error);
    // A file whose name starts with '-' is read as an option, and CLI11 then says the input is
    // missing: name the file, and how to give it.
    for (int i = 2; i < argc; ++i) {
      const std::string word = argv[i];
      std::error_code ignored;
      if (word.size() > 1 && word[0] == '-' && std::filesystem::exists(word, ignored)) {
        std::cerr << "rdtf: '" << word << "' was read as an option; for the file of that name write ./" << word
                  << " (or put -- before it)\n";
        break;
      }
    }
    return with_stdout_checked(code);
  } catch (const std::exception& error) {
    std::cerr << "rdtf: internal error: " << error.what() << "\n";
    return rdtf::cli::kExitInternalError;
  }
  return with_stdout_checked(exit_code);
}
