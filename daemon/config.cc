#include "config.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>
#include <type_traits>

#include <nlohmann/json.hpp>

namespace rdtf::daemon {
namespace {

std::filesystem::path xdg_folder(const char* variable, const char* fallback) {
  if (const char* value = std::getenv(variable); value != nullptr && *value == '/') return value;
  const char* home = std::getenv("HOME");
  return std::filesystem::path(home != nullptr ? home : "/tmp") / fallback;
}

// JSON's own type must match the setting's: a boolean is no number, -1 is no count.
template <typename T>
bool json_type_matches(const nlohmann::json& value) {
  if constexpr (std::is_same_v<T, bool>) {
    return value.is_boolean();
  } else if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T>) {
    return value.is_number_unsigned();
  } else if constexpr (std::is_integral_v<T>) {
    return value.is_number_integer();
  } else if constexpr (std::is_floating_point_v<T>) {
    return value.is_number();
  } else if constexpr (std::is_same_v<T, std::string>) {
    return value.is_string();
  } else {
    return true;  // Containers: checked element by element by get<T>() below.
  }
}

template <typename T>
bool read_key(const nlohmann::json& json, const char* key, T& out, std::string& error) {
  if (!json.contains(key)) return true;
  const nlohmann::json& value = json[key];
  bool ok = json_type_matches<T>(value);
  if constexpr (std::is_same_v<T, std::vector<std::string>>) {
    ok = value.is_array() && std::all_of(value.begin(), value.end(), [](const auto& v) { return v.is_string(); });
  } else if constexpr (std::is_same_v<T, std::vector<double>>) {
    ok = value.is_array() && std::all_of(value.begin(), value.end(), [](const auto& v) { return v.is_number(); });
  }
  if (!ok) {
    error = std::string("\"") + key + "\" has the wrong type (" + value.type_name() + ")";
    return false;
  }
  out = value.get<T>();
  return true;
}

bool read_ms(const nlohmann::json& json, const char* key, std::chrono::milliseconds& out,
             std::string& error) {
  double value = static_cast<double>(out.count());
  if (!read_key(json, key, value, error)) return false;
  if (!(value >= 0)) {
    error = std::string("\"") + key + "\" must be a number of milliseconds >= 0";
    return false;
  }
  out = std::chrono::milliseconds(static_cast<long long>(value));
  return true;
}

}  // namespace

const std::vector<std::string>& config_keys() {
  static const std::vector<std::string> keys{
      "watch", "output", "lcm_url", "channel_prefix", "settle_ms", "max_open_wait_ms",
      "republish_period_ms", "status_period_ms", "workers", "max_chunk_bytes",
      "chunk_rate_bytes_per_s", "default_density", "max_file_bytes", "max_buffer_bytes",
      "max_accessor_count", "max_triangles", "validate", "validation_seconds", "publish_failed",
      "simulate", "state_rate_hz", "real_time_factor", "floating_root", "gravity", "time_step",
      "stepper", "max_mass_ratio", "validation_start_offset_rad", "energy_tolerance",
      "joint_separation_tolerance_m", "limit_tolerance_rad", "limit_tolerance_m", "bound_mass_kg",
      "bound_inertia_kgm2", "massless_link_severity", "validation_cpu_budget_s", "urdf", "urdf_y_up",
      "max_read_bytes", "max_read_bytes_in_flight", "joint_command_timeout_s"};
  return keys;
}

const std::vector<KeyRange>& config_ranges() {
  constexpr double kTiB = 1099511627776.0;
  static const std::vector<KeyRange> ranges{
      {"settle_ms", 1, 60000},
      {"max_open_wait_ms", 0, 600000},
      {"republish_period_ms", 0, 86400000},  // And 0 or at least 10.
      {"status_period_ms", 10, 60000},
      {"workers", 1, 64},
      {"max_chunk_bytes", 1024, 65000},
      {"chunk_rate_bytes_per_s", 1e4, 1e10},
      {"default_density", 1e-3, 1e6},
      {"max_file_bytes", 1, kTiB},
      {"max_buffer_bytes", 1, kTiB},
      {"max_accessor_count", 1, 4294967296.0},
      {"max_triangles", 1, 4294967296.0},
      {"max_read_bytes", 1, kTiB},
      {"max_read_bytes_in_flight", 1, 4 * kTiB},  // And at least max_read_bytes.
      {"validation_seconds", 1e-3, 60},
      {"state_rate_hz", 0.1, 10000},
      {"real_time_factor", 0.01, 100},
      {"joint_command_timeout_s", 0.01, 60},
      {"time_step", 1e-4, 0.1},
      {"max_mass_ratio", 1, 1e12},
      {"validation_start_offset_rad", -6.2832, 6.2832},
      {"energy_tolerance", 1e-12, 1e6},
      {"joint_separation_tolerance_m", 1e-12, 1e3},
      {"limit_tolerance_rad", 1e-12, 6.2832},
      {"limit_tolerance_m", 1e-12, 1e3},
      {"bound_mass_kg", 0, 1e6},              // 0: off.
      {"bound_inertia_kgm2", 0, 1e6},         // 0: off.
      {"validation_cpu_budget_s", 0, 86400},  // 0: no limit.
      {"gravity", -1e3, 1e3},  // Each component, m/s^2.
  };
  return ranges;
}

namespace {

// The value of each ranged key in `config`, as checked.
std::vector<double> ranged_values(const DaemonConfig& c, const char* key) {
  const std::string k = key;
  const auto& l = c.convert.limits;
  if (k == "settle_ms") return {static_cast<double>(c.settle.count())};
  if (k == "max_open_wait_ms") return {static_cast<double>(c.max_open_wait.count())};
  if (k == "republish_period_ms") return {static_cast<double>(c.republish_period.count())};
  if (k == "status_period_ms") return {static_cast<double>(c.status_period.count())};
  if (k == "workers") return {static_cast<double>(c.workers)};
  if (k == "max_chunk_bytes") return {static_cast<double>(c.max_chunk_bytes)};
  if (k == "chunk_rate_bytes_per_s") return {c.chunk_rate_bytes_per_s};
  if (k == "default_density") return {c.convert.default_density};
  if (k == "max_file_bytes") return {static_cast<double>(l.max_file_bytes)};
  if (k == "max_buffer_bytes") return {static_cast<double>(l.max_buffer_bytes)};
  if (k == "max_accessor_count") return {static_cast<double>(l.max_accessor_count)};
  if (k == "max_triangles") return {static_cast<double>(l.max_triangles)};
  if (k == "max_read_bytes") return {static_cast<double>(c.max_read_bytes)};
  if (k == "max_read_bytes_in_flight") return {static_cast<double>(c.max_read_bytes_in_flight)};
  if (k == "validation_seconds") return {c.validation_seconds};
  if (k == "state_rate_hz") return {c.state_rate_hz};
  if (k == "real_time_factor") return {c.real_time_factor};
  if (k == "joint_command_timeout_s") return {c.joint_command_timeout_s};
  if (k == "time_step") return {c.time_step};
  if (k == "max_mass_ratio") return {c.max_mass_ratio};
  if (k == "validation_start_offset_rad") return {c.validation_start_offset_rad};
  if (k == "energy_tolerance") return {c.energy_tolerance};
  if (k == "joint_separation_tolerance_m") return {c.joint_separation_tolerance_m};
  if (k == "limit_tolerance_rad") return {c.limit_tolerance_rad};
  if (k == "limit_tolerance_m") return {c.limit_tolerance_m};
  if (k == "bound_mass_kg") return {c.bound_mass_kg};
  if (k == "bound_inertia_kgm2") return {c.bound_inertia_kgm2};
  if (k == "validation_cpu_budget_s") return {c.validation_cpu_budget_s};
  if (k == "gravity") return {c.gravity.x(), c.gravity.y(), c.gravity.z()};
  return {};
}

std::string number_text(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// Every ranged key within its range (NaN is in none).
bool check_ranges(const DaemonConfig& config, std::string& error) {
  for (const KeyRange& range : config_ranges()) {
    for (const double value : ranged_values(config, range.key)) {
      if (!(value >= range.min && value <= range.max)) {
        error = std::string("\"") + range.key + "\" is " + number_text(value) + ", outside its valid range [" +
                number_text(range.min) + ", " + number_text(range.max) + "] (docs/daemon.md)";
        return false;
      }
    }
  }
  if (config.republish_period.count() > 0 && config.republish_period.count() < 10) {
    error = "\"republish_period_ms\" must be 0 (off) or at least 10";
    return false;
  }
  if (config.max_read_bytes > config.max_read_bytes_in_flight) {
    error = "\"max_read_bytes\" (" + std::to_string(config.max_read_bytes) +
            ") must not exceed \"max_read_bytes_in_flight\" (" + std::to_string(config.max_read_bytes_in_flight) + ")";
    return false;
  }
  return true;
}

// The config file's text: a regular file only, opened without blocking and read up to a cap.
std::optional<std::string> read_config_text(const std::filesystem::path& path, std::string& error) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) {
    error = path.string() + ": cannot read the config file: " + std::strerror(errno);
    return std::nullopt;
  }
  struct stat info {};
  std::optional<std::string> text;
  if (::fstat(fd, &info) != 0) {
    error = path.string() + ": cannot read the config file: " + std::strerror(errno);
  } else if (!S_ISREG(info.st_mode)) {
    error = path.string() + ": the config is " +
            (S_ISDIR(info.st_mode) ? std::string("a directory") : std::string("not a regular file (a FIFO, device or socket)")) +
            ", not a file";
  } else if (static_cast<std::uint64_t>(info.st_size) > kMaxConfigFileBytes) {
    error = path.string() + ": the config file is " + std::to_string(info.st_size) + " bytes, over the limit of " +
            std::to_string(kMaxConfigFileBytes);
  } else {
    std::string bytes;
    char buffer[65536];
    for (;;) {
      const ssize_t n = ::read(fd, buffer, sizeof(buffer));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        error = path.string() + ": cannot read the config file: " + std::strerror(errno);
        break;
      }
      if (n == 0) {
        text = std::move(bytes);
        break;
      }
      bytes.append(buffer, static_cast<std::size_t>(n));
      if (bytes.size() > kMaxConfigFileBytes) {
        error = path.string() + ": the config file grew over the limit of " + std::to_string(kMaxConfigFileBytes) + " bytes";
        break;
      }
    }
  }
  ::close(fd);
  return text;
}

}  // namespace

DaemonConfig default_config() {
  DaemonConfig config;
  config.watch = {xdg_folder("XDG_DATA_HOME", ".local/share") / "rdtf" / "models"};
  config.output = xdg_folder("XDG_STATE_HOME", ".local/state") / "rdtf" / "output";
  return config;
}

std::optional<DaemonConfig> load_config(const std::filesystem::path& path, DaemonConfig config,
                                        std::string& error) {
  const auto text = read_config_text(path, error);
  if (!text) return std::nullopt;
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(*text);
  } catch (const nlohmann::json::parse_error& e) {
    error = path.string() + ": invalid JSON: " + e.what();
    return std::nullopt;
  }
  if (!json.is_object()) {
    error = path.string() + ": the config must be a JSON object";
    return std::nullopt;
  }
  // Relative folders are relative to the config file's folder.
  auto applied = apply_config_json(json, path.has_parent_path() ? path.parent_path() : std::filesystem::path("."),
                                   std::move(config), error);
  if (!applied) error = path.string() + ": " + error;
  return applied;
}

std::optional<DaemonConfig> apply_config_json(const nlohmann::json& json, const std::filesystem::path& base,
                                              DaemonConfig config, std::string& error) {

  const auto& keys = config_keys();
  for (const auto& [key, value] : json.items()) {
    if (key != "_comment" && std::find(keys.begin(), keys.end(), key) == keys.end()) {
      error = "unknown key \"" + key + "\"";
      return std::nullopt;
    }
  }
  std::vector<std::string> watch;
  std::string output;
  bool ok = read_key(json, "watch", watch, error) && read_key(json, "output", output, error) &&
            read_key(json, "lcm_url", config.lcm_url, error) &&
            read_key(json, "channel_prefix", config.channel_prefix, error) &&
            read_ms(json, "settle_ms", config.settle, error) &&
            read_ms(json, "max_open_wait_ms", config.max_open_wait, error) &&
            read_ms(json, "republish_period_ms", config.republish_period, error) &&
            read_ms(json, "status_period_ms", config.status_period, error) &&
            read_key(json, "workers", config.workers, error) &&
            read_key(json, "max_chunk_bytes", config.max_chunk_bytes, error) &&
            read_key(json, "chunk_rate_bytes_per_s", config.chunk_rate_bytes_per_s, error) &&
            read_key(json, "default_density", config.convert.default_density, error) &&
            read_key(json, "max_file_bytes", config.convert.limits.max_file_bytes, error) &&
            read_key(json, "max_buffer_bytes", config.convert.limits.max_buffer_bytes, error) &&
            read_key(json, "max_accessor_count", config.convert.limits.max_accessor_count, error) &&
            read_key(json, "max_triangles", config.convert.limits.max_triangles, error) &&
            read_key(json, "validate", config.validate, error) &&
            read_key(json, "validation_seconds", config.validation_seconds, error) &&
            read_key(json, "publish_failed", config.publish_failed, error) &&
            read_key(json, "simulate", config.simulate, error) &&
            read_key(json, "state_rate_hz", config.state_rate_hz, error) &&
            read_key(json, "real_time_factor", config.real_time_factor, error) &&
            read_key(json, "joint_command_timeout_s", config.joint_command_timeout_s, error) &&
            read_key(json, "floating_root", config.floating_root, error) &&
            read_key(json, "time_step", config.time_step, error) &&
            read_key(json, "max_mass_ratio", config.max_mass_ratio, error) &&
            read_key(json, "validation_start_offset_rad", config.validation_start_offset_rad, error) &&
            read_key(json, "energy_tolerance", config.energy_tolerance, error) &&
            read_key(json, "joint_separation_tolerance_m", config.joint_separation_tolerance_m, error) &&
            read_key(json, "limit_tolerance_rad", config.limit_tolerance_rad, error) &&
            read_key(json, "limit_tolerance_m", config.limit_tolerance_m, error) &&
            read_key(json, "bound_mass_kg", config.bound_mass_kg, error) &&
            read_key(json, "bound_inertia_kgm2", config.bound_inertia_kgm2, error) &&
            read_key(json, "validation_cpu_budget_s", config.validation_cpu_budget_s, error) &&
            read_key(json, "urdf", config.urdf, error) &&
            read_key(json, "urdf_y_up", config.urdf_y_up, error) &&
            read_key(json, "max_read_bytes", config.max_read_bytes, error) &&
            read_key(json, "max_read_bytes_in_flight", config.max_read_bytes_in_flight, error);
  if (ok && json.contains("massless_link_severity")) {
    std::string severity;
    ok = read_key(json, "massless_link_severity", severity, error);
    if (ok && severity != "warning" && severity != "error") {
      error = "\"massless_link_severity\" must be \"warning\" or \"error\"";
      ok = false;
    }
    if (ok) config.massless_link_error = severity == "error";
  }
  if (ok && json.contains("gravity")) {
    std::vector<double> gravity;
    ok = read_key(json, "gravity", gravity, error);
    if (ok && gravity.size() != 3) {
      error = "\"gravity\" must be three numbers (m/s^2, scene frame)";
      ok = false;
    }
    if (ok) config.gravity = Eigen::Vector3d(gravity[0], gravity[1], gravity[2]);
  }
  if (ok && json.contains("stepper")) {
    std::string stepper;
    ok = read_key(json, "stepper", stepper, error);
    if (ok) {
      const auto parsed = parse_stepper(stepper);
      if (parsed) {
        config.stepper = *parsed;
      } else {
        error = "\"stepper\" must be \"auto\", \"world_step\" or \"quick_step\", not \"" + stepper + "\"";
        ok = false;
      }
    }
  }
  if (!ok) return std::nullopt;
  if (json.contains("watch")) {
    config.watch.clear();
    for (const auto& folder : watch) config.watch.push_back(base / folder);
  }
  if (json.contains("output")) config.output = base / output;
  return config;
}

bool check_config(DaemonConfig& config, std::string& error) {
  if (config.watch.empty()) {
    error = "nothing to watch: give --watch DIR or \"watch\" in the config";
    return false;
  }
  std::error_code ec;
  for (auto& folder : config.watch) {
    std::filesystem::create_directories(folder, ec);
    if (!std::filesystem::is_directory(folder)) {
      error = "watch folder " + folder.string() + " is not a directory";
      return false;
    }
    folder = std::filesystem::canonical(folder);
  }
  std::filesystem::create_directories(config.output, ec);
  if (!std::filesystem::is_directory(config.output)) {
    error = "output folder " + config.output.string() + " cannot be created";
    return false;
  }
  config.output = std::filesystem::canonical(config.output);
  if (!check_ranges(config, error)) return false;
  if (!(config.validation_seconds > 0) || !(config.state_rate_hz > 0) || !(config.real_time_factor > 0)) {
    error = "validation_seconds, state_rate_hz and real_time_factor must be > 0";
    return false;
  }
  // Written so that NaN fails too; infinities are out (JSON has none, the command line does).
  const auto positive = [](double v) { return v > 0 && std::isfinite(v); };
  if (!positive(config.time_step) || config.time_step > 0.1 || !(config.max_mass_ratio >= 1) ||
      !positive(config.energy_tolerance) || !positive(config.joint_separation_tolerance_m) ||
      !positive(config.limit_tolerance_rad) || !positive(config.limit_tolerance_m) ||
      !std::isfinite(config.validation_start_offset_rad) || !config.gravity.allFinite() ||
      !(config.bound_mass_kg >= 0) || !std::isfinite(config.bound_mass_kg) || !(config.bound_inertia_kgm2 >= 0) ||
      !std::isfinite(config.bound_inertia_kgm2) || !(config.validation_cpu_budget_s >= 0) ||
      !std::isfinite(config.validation_cpu_budget_s)) {
    error = "time_step must be in (0, 0.1] s, max_mass_ratio >= 1, the tolerances finite and > 0, "
            "validation_start_offset_rad and gravity finite, bound_mass_kg, bound_inertia_kgm2 and "
            "validation_cpu_budget_s finite and >= 0";
    return false;
  }
  for (const auto& folder : config.watch) {
    // An output folder that contains a watched folder would hide every save in it.
    const auto relative = folder.lexically_relative(config.output);
    if (!relative.empty() && *relative.begin() != "..") {
      error = "output folder " + config.output.string() + " contains the watched folder " +
              folder.string() + ": choose an output folder outside it (or inside the watched one)";
      return false;
    }
  }
  if (config.settle.count() <= 0 || config.workers < 1 || config.max_chunk_bytes < 1024 ||
      config.max_chunk_bytes > 65000 || config.chunk_rate_bytes_per_s <= 0 ||
      config.status_period.count() <= 0) {
    error = "settle_ms and status_period_ms must be > 0, workers >= 1, max_chunk_bytes in "
            "1024..65000, chunk_rate_bytes_per_s > 0";
    return false;
  }
  if (config.channel_prefix.empty() || config.channel_prefix.size() > 16) {
    error = "channel_prefix must have 1 to 16 characters";
    return false;
  }
  return true;
}


std::optional<Stepper> parse_stepper(std::string_view name) {
  if (name == "auto") return Stepper::kAuto;
  if (name == "world_step") return Stepper::kWorldStep;
  if (name == "quick_step") return Stepper::kQuickStep;
  return std::nullopt;
}

SimulationOptions simulation_options(const DaemonConfig& config) {
  SimulationOptions simulation;
  simulation.gravity = config.gravity;
  simulation.floating_root = config.floating_root;
  simulation.time_step = config.time_step;
  simulation.stepper = config.stepper;
  simulation.bound_mass = config.bound_mass_kg;
  simulation.bound_inertia = config.bound_inertia_kgm2;
  return simulation;
}

ValidationOptions validation_options(const DaemonConfig& config) {
  ValidationOptions validation;
  validation.simulation = simulation_options(config);
  validation.duration = config.validation_seconds;
  validation.checks.max_mass_ratio = config.max_mass_ratio;
  validation.start_offset_angular = config.validation_start_offset_rad;
  validation.energy_tolerance = config.energy_tolerance;
  validation.joint_separation_tolerance = config.joint_separation_tolerance_m;
  validation.limit_tolerance_angular = config.limit_tolerance_rad;
  validation.limit_tolerance_linear = config.limit_tolerance_m;
  validation.checks.massless_link_error = config.massless_link_error;
  validation.cpu_budget = config.validation_cpu_budget_s;
  return validation;
}

}  // namespace rdtf::daemon
