// rdtfd: watches model folders, converts every saved glTF to RDTF and publishes it over LCM.
// `rdtfd --help` lists the options; config/rdtfd.json documents the config file.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "daemon.h"

namespace {

struct Overrides {
  std::vector<std::string> watch;
  std::string output;
  std::string lcm_url;
  std::string channel_prefix;
  std::optional<double> settle_ms;
  std::optional<double> republish_ms;
  std::optional<int> workers;
  std::optional<double> density;
  std::optional<double> state_rate_hz;
  std::vector<double> gravity;
  bool no_validate = false;
  bool no_simulate = false;
  bool no_urdf = false;
  bool publish_failed = false;
  bool floating_root = false;
  std::vector<std::string> settings;  // --set KEY=VALUE: any key of the config file.
};

// "--set KEY=VALUE" as the config file's {"KEY": VALUE}: VALUE is read as JSON (a number, true,
// [0, 0, -9.8]) and otherwise taken as a string, so that paths and URLs need no quotes.
std::optional<nlohmann::json> settings_json(const std::vector<std::string>& settings, std::string& error) {
  nlohmann::json json = nlohmann::json::object();
  for (const std::string& setting : settings) {
    const auto equals = setting.find('=');
    if (equals == std::string::npos || equals == 0) {
      error = "--set " + setting + ": expected KEY=VALUE";
      return std::nullopt;
    }
    const std::string key = setting.substr(0, equals);
    const std::string value = setting.substr(equals + 1);
    json[key] = nlohmann::json::accept(value) ? nlohmann::json::parse(value) : nlohmann::json(value);
  }
  return json;
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
    config.lcm_url = url;
  }
  if (!overrides.settings.empty()) {
    const auto settings = settings_json(overrides.settings, error);
    if (!settings) return std::nullopt;
    auto applied = rdtf::daemon::apply_config_json(*settings, std::filesystem::current_path(), std::move(config), error);
    if (!applied) {
      error = "--set: " + error;
      return std::nullopt;
    }
    config = std::move(*applied);
  }
  if (!overrides.watch.empty()) {
    config.watch.assign(overrides.watch.begin(), overrides.watch.end());
  }
  if (!overrides.output.empty()) config.output = overrides.output;
  if (!overrides.lcm_url.empty()) config.lcm_url = overrides.lcm_url;
  if (!overrides.channel_prefix.empty()) config.channel_prefix = overrides.channel_prefix;
  if (overrides.settle_ms) config.settle = std::chrono::milliseconds(static_cast<long long>(*overrides.settle_ms));
  if (overrides.republish_ms) {
    config.republish_period = std::chrono::milliseconds(static_cast<long long>(*overrides.republish_ms));
  }
  if (overrides.workers) config.workers = *overrides.workers;
  if (overrides.density) config.convert.default_density = *overrides.density;
  if (overrides.state_rate_hz) config.state_rate_hz = *overrides.state_rate_hz;
  if (overrides.gravity.size() == 3) {
    config.gravity = Eigen::Vector3d(overrides.gravity[0], overrides.gravity[1], overrides.gravity[2]);
  }
  if (overrides.no_validate) config.validate = false;
  if (overrides.no_simulate) config.simulate = false;
  if (overrides.no_urdf) config.urdf = false;
  if (overrides.publish_failed) config.publish_failed = true;
  if (overrides.floating_root) config.floating_root = true;
  if (!rdtf::daemon::check_config(config, error)) return std::nullopt;
  return config;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rdtfd: watches folders of glTF models, converts each save to RDTF and publishes "
               "it over LCM"};
  app.set_version_flag("--version", "rdtfd 0.1.0");
  std::string config_file;
  Overrides overrides;
  app.add_option("-c,--config", config_file, "JSON config file (see config/rdtfd.json)")
      ->check(CLI::ExistingFile);
  app.add_option("-w,--watch", overrides.watch,
                 "Folder to watch, recursively (repeatable; default ~/.local/share/rdtf/models)");
  app.add_option("-o,--output", overrides.output,
                 "Folder for RDTF outputs (default ~/.local/state/rdtf/output)");
  app.add_option("--lcm-url", overrides.lcm_url, "LCM URL (default: LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("--channel-prefix", overrides.channel_prefix, "First part of every channel (default RDTF)");
  app.add_option("--settle-ms", overrides.settle_ms, "Quiet time after a save before converting (default 50)");
  app.add_option("--republish-ms", overrides.republish_ms,
                 "Period of republishing every description; 0 disables (default 5000)");
  app.add_option("--workers", overrides.workers, "Conversion threads (default 2)")->check(CLI::PositiveNumber);
  app.add_option("--density", overrides.density, "Default density, kg/m^3 (default 1000)")
      ->check(CLI::PositiveNumber);
  app.add_option("--state-rate-hz", overrides.state_rate_hz, "Joint-state messages per second and model (default 100)")
      ->check(CLI::PositiveNumber);
  app.add_option("--gravity", overrides.gravity, "Gravity in the scene frame, m/s^2 (default 0 -9.80665 0: glTF is Y up)")
      ->expected(3);
  app.add_flag("--no-validate", overrides.no_validate, "Publish without the ODE dynamics check");
  app.add_flag("--no-simulate", overrides.no_simulate, "Run no live simulation (no joint states)");
  app.add_flag("--no-urdf", overrides.no_urdf, "Write no URDF beside the RDTF outputs");
  app.add_flag("--publish-failed", overrides.publish_failed,
               "Publish revisions that fail the dynamics check (marked failed) instead of keeping the last good one");
  app.add_flag("--floating-root", overrides.floating_root, "Root links float instead of being fixed to the world");
  app.add_option("--set", overrides.settings,
                 "KEY=VALUE: any key of the config file (config/rdtfd.json), VALUE as JSON or a plain string; "
                 "repeatable; applied over the file, under the options above")
      ->type_name("KEY=VALUE");
  CLI11_PARSE(app, argc, argv);

  std::string error;
  auto config = load(config_file, overrides, error);
  if (!config) {
    std::cerr << "rdtfd: " << error << "\n";
    return 2;
  }
  try {
    rdtf::daemon::Daemon daemon(std::move(*config), [config_file, overrides](std::string& reload_error) {
      return load(config_file, overrides, reload_error);
    });
    if (!daemon.start(error)) {
      std::cerr << "rdtfd: " << error << "\n";
      return 1;
    }
    return daemon.run();
  } catch (const std::exception& e) {
    std::cerr << "rdtfd: internal error: " << e.what() << "\n";
    return 1;
  }
}
