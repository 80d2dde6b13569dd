// rdtfd and other programs as child processes of a test: options, start, signals, exit codes,
// logs. Every child is killed by its destructor if a test ends early.
#pragma once

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

#include "support/harness/basics.h"

namespace rdtf::itest {

struct DaemonOptions {
  std::vector<fs::path> watch;
  fs::path output;
  std::optional<int> settle_ms = 50;     // --settle-ms; nothing: rdtfd's own default.
  std::optional<int> republish_ms = 0;   // --republish-ms; nothing: the config's.
  Json config = Json::object();  // Config file keys, over `defaults`.
  // The tests' defaults: heartbeats to synchronise on, and no dynamics check or live simulation
  // unless a test is about them.
  Json defaults = {{"status_period_ms", 100}, {"validate", false}, {"simulate", false}};
  std::vector<std::string> extra_args;
  bool folders_on_command_line = true;  // false: "watch" and "output" come from `config` only.
  fs::path working_directory;  // The daemon's; empty: the test's. "/" is what systemd gives.
  std::vector<std::string> environment;  // "NAME=value" entries added to the test's environment.

  DaemonOptions& with_settle(int ms) { settle_ms = ms; return *this; }
  DaemonOptions& with_republish(int ms) { republish_ms = ms; return *this; }
  DaemonOptions& with_output(fs::path folder) { output = std::move(folder); return *this; }
  DaemonOptions& with_watch(std::vector<fs::path> folders) { watch = std::move(folders); return *this; }
  DaemonOptions& with(const std::string& key, Json value) { config[key] = std::move(value); return *this; }
  DaemonOptions& with_args(std::vector<std::string> args) { extra_args = std::move(args); return *this; }
  DaemonOptions& with_folders_in_config() { folders_on_command_line = false; return *this; }
  DaemonOptions& in_directory(fs::path folder) { working_directory = std::move(folder); return *this; }
  DaemonOptions& with_env(std::string entry) { environment.push_back(std::move(entry)); return *this; }
};

// rdtfd (RDTFD_PATH) with a config file the test writes; its stdout and stderr go to a log file.
class DaemonProcess {
 public:
  explicit DaemonProcess(DaemonOptions options);
  ~DaemonProcess();
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  pid_t pid() const { return pid_; }
  pid_t last_pid() const { return last_pid_; }  // Still known after it exited.
  const fs::path& config_path() const { return config_path_; }
  std::string log() const;
  // Writes the config file: `config` over the options' defaults.
  void write_config(const Json& config);
  void signal(int number) const;
  // SIGTERM, then the exit code (nothing if it has not exited by the deadline).
  std::optional<int> stop(Clock::duration timeout = 5s);
  // Starts the daemon again with the same options (after it exited or was killed); the log
  // continues in the same file.
  void restart();
  // Waits until the log contains `text` (for events that send no message).
  bool wait_log(const std::string& text, Clock::duration timeout = 5s) const;
  bool running();
  // The exit code (128 + signal when killed) once it exits; nothing at the deadline.
  std::optional<int> wait_exit(Clock::duration timeout);

 private:
  void start();

  DaemonOptions options_;
  TempDir files_;
  fs::path config_path_;
  fs::path log_path_;
  pid_t pid_ = -1;
  pid_t last_pid_ = -1;
  int exit_code_ = -1;
};

// Any other program run by a test (lcm-logger, lcm-logplayer, rdtf-echo), stdout and stderr to
// `output`. Killed by the destructor if still running.
class ChildProcess {
 public:
  ChildProcess(std::vector<std::string> args, const fs::path& output);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  void signal(int number) const;
  std::optional<int> wait_exit(Clock::duration timeout);
  std::string output() const { return testing::read_file(output_); }

 private:
  fs::path output_;
  pid_t pid_ = -1;
  int exit_code_ = -1;
};

// A field of /proc/<pid>/status in kB (VmHWM: the peak resident set, VmRSS), or -1.
long status_kb(pid_t pid, const std::string& field);

}  // namespace rdtf::itest
