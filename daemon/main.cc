// rdtfd: watches model folders, converts every saved glTF to RDTF and publishes it over LCM.
// `rdtfd --help` lists the options; config/rdtfd.json documents the config file.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cerrno>
#include <csignal>
#include <cstddef>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>

#include <pthread.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "daemon.h"
#include "lcm_url.h"
#include "rdtf/version.h"

namespace {

// The command line: the named options of the registry's keys (config.cc) and --set KEY=VALUE.
struct Overrides {
  std::map<std::string, std::vector<std::string>> options;  // Key -> the texts its option was given.
  std::map<std::string, bool> switches;                      // Key -> whether its switch was given.
  std::vector<std::string> settings;  // --set KEY=VALUE: any key of the config file.
};

// "--set KEY=VALUE" as the config file's {"KEY": VALUE} (value_from_text reads VALUE by the key's kind).
std::optional<nlohmann::json> settings_json(const std::vector<std::string>& settings, std::string& error) {
  nlohmann::json json = nlohmann::json::object();
  for (const std::string& setting : settings) {
    const auto equals = setting.find('=');
    if (equals == std::string::npos || equals == 0) {
      error = "--set " + setting + ": expected KEY=VALUE";
      return std::nullopt;
    }
    const std::string name = setting.substr(0, equals);
    const std::string value = setting.substr(equals + 1);
    const auto* key = rdtf::daemon::find_config_key(name);
    json[name] = key != nullptr ? rdtf::daemon::value_from_text(*key, {value})
                                : (nlohmann::json::accept(value) ? nlohmann::json::parse(value) : nlohmann::json(value));
  }
  return json;
}

// Applies `json` over `config`; an error is prefixed with `what` (the option).
bool apply(const nlohmann::json& json, const std::string& what, rdtf::daemon::DaemonConfig& config,
           std::string& error) {
  auto applied = rdtf::daemon::apply_config_json(json, std::filesystem::current_path(), std::move(config), error);
  if (!applied) {
    error = what + ": " + error;
    return false;
  }
  config = std::move(*applied);
  return true;
}

std::optional<rdtf::daemon::DaemonConfig> load(const std::string& config_file,
                                               const Overrides& overrides, std::string& error) {
  auto config = rdtf::daemon::default_config();
  if (!config_file.empty()) {
    auto loaded = rdtf::daemon::load_config(config_file, config, error);
    if (!loaded) return std::nullopt;
    config = std::move(*loaded);
  }
  if (const char* url = std::getenv("LCM_DEFAULT_URL"); url != nullptr && config.lcm_url.empty()) {
    // Named as what the user set (review s90rev R7), when the command line does not replace it.
    const auto option = overrides.options.find("lcm_url");
    const bool replaced = option != overrides.options.end() && !option->second.empty();
    if (!replaced && !rdtf::daemon::check_lcm_url(url, error, "LCM_DEFAULT_URL")) {
      return std::nullopt;
    }
    config.lcm_url = url;
  }
  if (!overrides.settings.empty()) {
    const auto settings = settings_json(overrides.settings, error);
    if (!settings || !apply(*settings, "--set", config, error)) return std::nullopt;
  }
  // The named options win over --set; each is applied alone so that an error names its option.
  for (const auto& key : rdtf::daemon::config_registry()) {
    const std::string option = key.flag.empty() ? "" : key.flag.substr(key.flag.find("--"));
    nlohmann::json json;
    if (const auto it = overrides.options.find(key.name); it != overrides.options.end() && !it->second.empty()) {
      json[key.name] = rdtf::daemon::value_from_text(key, it->second);
    } else if (const auto on = overrides.switches.find(key.name); on != overrides.switches.end() && on->second) {
      json[key.name] = *key.flag_sets;
    } else {
      continue;
    }
    if (!apply(json, option, config, error)) return std::nullopt;
  }
  if (!rdtf::daemon::check_config(config, error)) return std::nullopt;
  return config;
}

// systemd's readiness protocol (sd_notify(3)) without libsystemd: one datagram "READY=1" to the
// socket named in $NOTIFY_SOCKET. Under Type=notify, `systemctl start` returns, and a reload is
// sent, only once rdtfd reads its signals: a SIGHUP in its first milliseconds (library loading
// alone takes 20-45 ms, before main can hold any signal) killed it, and systemd counted that as
// a clean exit (s80cfg D6, s80rev R1).
void notify_ready() {
  const char* socket_path = std::getenv("NOTIFY_SOCKET");
  if (socket_path == nullptr || (socket_path[0] != '/' && socket_path[0] != '@')) return;
  const std::string name = socket_path;
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (name.size() >= sizeof(address.sun_path)) return;
  std::memcpy(address.sun_path, name.data(), name.size());
  if (name[0] == '@') address.sun_path[0] = '\0';  // An abstract socket.
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return;
  static constexpr char kReady[] = "READY=1";
  const auto length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + name.size());
  if (::sendto(fd, kReady, sizeof(kReady) - 1, MSG_NOSIGNAL, reinterpret_cast<const sockaddr*>(&address), length) < 0) {
    std::cerr << "rdtfd: could not tell systemd it is ready (NOTIFY_SOCKET " << name << "): " << std::strerror(errno) << "\n";
  }
  ::close(fd);
}

}  // namespace

int main(int argc, char** argv) {
  // First thing: SIGTERM, SIGINT and SIGHUP are read from a signalfd once the loop runs
  // (Daemon::start), and held until then; a SIGHUP in the first milliseconds (`systemctl reload`
  // right after `start`) killed rdtfd, which systemd counts as a clean exit (s80cfg D6). A log
  // reader that goes away (`rdtfd 2>&1 | head`) must not kill it either: the write fails instead.
  sigset_t held;
  sigemptyset(&held);
  for (int s : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&held, s);
  pthread_sigmask(SIG_BLOCK, &held, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
  // A file-size limit (ulimit -f, systemd's LimitFSIZE) fails an output's write with EFBIG, which
  // rejects that revision (WRITE_FAILED, retried later) and keeps the last good one served; its
  // signal would kill the daemon, and again on the same model after every restart.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"rdtfd: watches folders of glTF models, converts each save to RDTF and publishes "
               "it over LCM"};
  app.set_version_flag("--version", rdtf::version_line("rdtfd"));
  std::string config_file;
  Overrides overrides;
  // Checked by load_config, which names the file and what is wrong with it (missing, a directory,
  // a FIFO) and exits 2 as for any other bad setting.
  app.add_option("-c,--config", config_file, "JSON config file (see config/rdtfd.json)");
  for (const auto& key : rdtf::daemon::config_registry()) {
    if (key.flag.empty()) continue;
    if (key.flag_sets) {
      app.add_flag(key.flag, overrides.switches[key.name], key.flag_help);
    } else {
      auto* option = app.add_option(key.flag, overrides.options[key.name], key.flag_help);
      using rdtf::daemon::ValueKind;
      option->type_name(key.kind == ValueKind::kFolders || key.kind == ValueKind::kFolder ? "DIR"
                        : key.kind == ValueKind::kString || key.kind == ValueKind::kName ? "TEXT"
                        : key.kind == ValueKind::kInteger                                ? "INT"
                                                                                         : "NUMBER");
      if (key.kind == rdtf::daemon::ValueKind::kVector3) {
        option->expected(3);
      } else if (key.kind != rdtf::daemon::ValueKind::kFolders) {
        option->expected(1)->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
      }
    }
  }
  app.add_option("--set", overrides.settings,
                 "KEY=VALUE: any key of the config file (config/rdtfd.json), VALUE as JSON or a plain string; "
                 "repeatable; applied over the file, under the options above")
      ->type_name("KEY=VALUE");
  CLI11_PARSE(app, argc, argv);

  std::string error;
  try {
    std::optional<rdtf::daemon::DaemonConfig> config;
    try {
      config = load(config_file, overrides, error);
    } catch (const std::exception& e) {
      // A value JSON cannot hold (1e400) throws from the parser: a bad config all the same, which
      // systemd must not restart (exit 2: RestartPreventExitStatus), not an internal error.
      error = (config_file.empty() ? std::string("the settings") : config_file) + ": " + e.what();
    }
    if (!config) {
      std::cerr << "rdtfd: " << error << "\n";
      return 2;
    }
    rdtf::daemon::Daemon daemon(std::move(*config), [config_file, overrides](std::string& reload_error) {
      return load(config_file, overrides, reload_error);
    });
    if (!daemon.start(error)) {
      std::cerr << "rdtfd: " << error << "\n";
      return 1;
    }
    notify_ready();
    return daemon.run();
  } catch (const std::exception& e) {
    std::cerr << "rdtfd: internal error: " << e.what() << "\n";
    return 1;
  }
}
