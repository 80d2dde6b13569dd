#include "support/harness/process.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace rdtf::itest {
namespace {

void kill_and_reap(pid_t pid) {
  if (pid <= 0) return;
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
}

// Reaps `pid` if it has exited: its exit code (128 + signal when killed), else nothing.
std::optional<int> reaped(pid_t pid) {
  int status = 0;
  if (pid <= 0 || ::waitpid(pid, &status, WNOHANG) != pid) return std::nullopt;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace

DaemonProcess::DaemonProcess(DaemonOptions options) : options_(std::move(options)) {
  config_path_ = files_ / "rdtfd.json";
  log_path_ = files_ / "rdtfd.log";
  write_config(options_.config);
  start();
}

DaemonProcess::~DaemonProcess() { kill_and_reap(pid_); }

std::string DaemonProcess::log() const {
  std::ifstream in(log_path_);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void DaemonProcess::write_config(const Json& config) {
  Json full = options_.defaults;
  full.update(config);
  testing::write_file(config_path_, full.dump(2));
}

void DaemonProcess::signal(int number) const {
  if (pid_ > 0) ::kill(pid_, number);
}

std::optional<int> DaemonProcess::stop(Clock::duration timeout) {
  signal(SIGTERM);
  return wait_exit(timeout);
}

void DaemonProcess::restart() {
  if (running()) throw std::runtime_error("restart: rdtfd is still running");
  start();
}

bool DaemonProcess::wait_log(const std::string& text, Clock::duration timeout) const {
  return wait_until([&] { return log().find(text) != std::string::npos; }, timeout);
}

bool DaemonProcess::running() {
  if (pid_ <= 0) return false;
  if (const auto code = reaped(pid_)) {
    exit_code_ = *code;
    pid_ = -1;
    return false;
  }
  return true;
}

std::optional<int> DaemonProcess::wait_exit(Clock::duration timeout) {
  wait_until([&] { return !running(); }, timeout);
  if (pid_ > 0) return std::nullopt;
  return exit_code_;
}

void DaemonProcess::start() {
  std::vector<std::string> args = {RDTFD_PATH, "--config", config_path_.string()};
  if (options_.folders_on_command_line) {
    for (const auto& folder : options_.watch) {
      args.push_back("--watch");
      args.push_back(folder.string());
    }
    args.push_back("--output");
    args.push_back(options_.output.string());
  }
  if (options_.settle_ms) {
    args.push_back("--settle-ms");
    args.push_back(std::to_string(*options_.settle_ms));
  }
  if (options_.republish_ms) {
    args.push_back("--republish-ms");
    args.push_back(std::to_string(*options_.republish_ms));
  }
  args.insert(args.end(), options_.extra_args.begin(), options_.extra_args.end());
  std::vector<char*> argv;
  for (auto& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  if (!options_.working_directory.empty()) {
    posix_spawn_file_actions_addchdir_np(&actions, options_.working_directory.c_str());
  }
  std::vector<std::string> environment = options_.environment;
  for (char** entry = environ; *entry != nullptr; ++entry) environment.emplace_back(*entry);
  std::vector<char*> envp;
  for (auto& entry : environment) envp.push_back(entry.data());
  envp.push_back(nullptr);
  const int error = posix_spawn(&pid_, RDTFD_PATH, &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) throw std::runtime_error(std::string("cannot start rdtfd: ") + std::strerror(error));
  last_pid_ = pid_;
}

ChildProcess::ChildProcess(std::vector<std::string> args, const fs::path& output) : output_(output) {
  std::vector<char*> argv;
  for (auto& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  const int error = posix_spawnp(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) throw std::runtime_error("cannot start " + args[0] + ": " + std::strerror(error));
}

ChildProcess::~ChildProcess() { kill_and_reap(pid_); }

void ChildProcess::signal(int number) const {
  if (pid_ > 0) ::kill(pid_, number);
}

std::optional<int> ChildProcess::wait_exit(Clock::duration timeout) {
  wait_until(
      [&] {
        if (const auto code = reaped(pid_)) {
          exit_code_ = *code;
          pid_ = -1;
        }
        return pid_ <= 0;
      },
      timeout);
  if (pid_ > 0) return std::nullopt;
  return exit_code_;
}

long status_kb(pid_t pid, const std::string& field) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(field + ":", 0) == 0) return std::stol(line.substr(field.size() + 1));
  }
  return -1;
}

}  // namespace rdtf::itest
