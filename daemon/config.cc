#include "config.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fcntl.h>
#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>

#include <nlohmann/json.hpp>

#include "lcm_url.h"
#include "safe_decode.h"

namespace rdtf::daemon {
namespace {

// The user's home folder: $HOME when it is an absolute path, else the password database's entry;
// nothing when neither is. (Without HOME the defaults were under /tmp/.local, which any local user
// can create first and fill with models of their own, and an empty HOME made them relative to the
// working folder: s103env D8.)
std::optional<std::filesystem::path> home_folder() {
  if (const char* home = std::getenv("HOME"); home != nullptr && *home == '/') return std::filesystem::path(home);
  std::vector<char> buffer(16384);
  passwd entry{};
  passwd* found = nullptr;
  if (getpwuid_r(geteuid(), &entry, buffer.data(), buffer.size(), &found) == 0 && found != nullptr &&
      found->pw_dir != nullptr && found->pw_dir[0] == '/') {
    return std::filesystem::path(found->pw_dir);
  }
  return std::nullopt;
}

// $variable when it is an absolute path (the XDG base directory rule), else `fallback` in the home
// folder; empty when there is no home folder either (check_config then asks for the folder).
std::filesystem::path xdg_folder(const char* variable, const char* fallback) {
  if (const char* value = std::getenv(variable); value != nullptr && *value == '/') return value;
  const auto home = home_folder();
  return home ? *home / fallback : std::filesystem::path();
}

constexpr const char* kNoHome =
    " (there is no default: HOME is unset or not an absolute path, the user has no home folder in the "
    "password database, and XDG_DATA_HOME / XDG_STATE_HOME are not set)";

}  // namespace

const ConfigKey* find_config_key(std::string_view name) {
  for (const ConfigKey& key : config_registry()) {
    if (key.name == name) return &key;
  }
  return nullptr;
}

const std::vector<std::string>& config_keys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> names;
    for (const ConfigKey& key : config_registry()) names.push_back(key.name);
    return names;
  }();
  return keys;
}

const std::vector<KeyRange>& config_ranges() {
  static const std::vector<KeyRange> ranges = [] {
    std::vector<KeyRange> out;
    for (const ConfigKey& key : config_registry()) {
      if (key.min && key.max) out.push_back({key.name.c_str(), *key.min, *key.max});
    }
    return out;
  }();
  return ranges;
}

namespace {

// As many digits as the value needs to be told apart from the bounds (17 at most): six showed
// 1.09951e+12 both for a value above the maximum and for the maximum (s80cfg D10).
std::string number_text(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  for (int digits = 6; digits < 17; ++digits) {
    std::ostringstream shorter;
    shorter.precision(digits);
    shorter << value;
    if (std::strtod(shorter.str().c_str(), nullptr) == value) return shorter.str();
  }
  return out.str();
}

// Every ranged key within its range (NaN and the infinities are in none), then what a range alone
// cannot say.
bool check_ranges(const DaemonConfig& config, std::string& error) {
  for (const ConfigKey& key : config_registry()) {
    if (!key.min || !key.max) continue;
    for (const double value : key.numbers(config)) {
      if (!(value >= *key.min && value <= *key.max)) {
        error = "\"" + key.name + "\" is " + number_text(value) + ", outside its valid range [" +
                number_text(*key.min) + ", " + number_text(*key.max) + "] (docs/daemon.md)";
        return false;
      }
    }
  }
  if (config.republish_period.count() > 0 && config.republish_period.count() < 10) {
    error = "\"republish_period_ms\" is " + std::to_string(config.republish_period.count()) +
            ": it must be 0 (off) or at least 10";
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
            (S_ISDIR(info.st_mode) ? std::string("a directory") : std::string("a FIFO, device or socket")) +
            ", not a regular file";
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
  const std::filesystem::path data = xdg_folder("XDG_DATA_HOME", ".local/share");
  const std::filesystem::path state = xdg_folder("XDG_STATE_HOME", ".local/state");
  config.watch.clear();
  if (!data.empty()) config.watch = {data / "rdtf" / "models"};
  config.output = state.empty() ? std::filesystem::path() : state / "rdtf" / "output";
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

  for (const auto& [name, value] : json.items()) {
    if (name != "_comment" && find_config_key(name) == nullptr) {
      error = "unknown key \"" + name + "\"";
      return std::nullopt;
    }
  }
  for (const ConfigKey& key : config_registry()) {
    if (json.contains(key.name) && !key.set(json[key.name], base, config, error)) return std::nullopt;
  }
  return config;
}

nlohmann::json value_from_text(const ConfigKey& key, const std::vector<std::string>& texts) {
  const auto parsed = [](const std::string& text) {
    return nlohmann::json::accept(text) ? nlohmann::json::parse(text) : nlohmann::json(text);
  };
  switch (key.kind) {
    case ValueKind::kString:
    case ValueKind::kName:
    case ValueKind::kFolder:
      return texts.size() == 1 ? nlohmann::json(texts[0]) : nlohmann::json(texts);
    case ValueKind::kFolders:
      // Several texts (--watch A --watch B) are folders; one is a JSON list or a single folder.
      if (texts.size() == 1 && nlohmann::json::accept(texts[0]) && nlohmann::json::parse(texts[0]).is_array()) {
        return nlohmann::json::parse(texts[0]);
      }
      return nlohmann::json(texts);
    case ValueKind::kVector3:
      if (texts.size() == 1) return parsed(texts[0]);
      {
        nlohmann::json out = nlohmann::json::array();
        for (const auto& text : texts) out.push_back(parsed(text));
        return out;
      }
    case ValueKind::kBoolean:
    case ValueKind::kInteger:
    case ValueKind::kNumber:
      break;
  }
  return texts.size() == 1 ? parsed(texts[0]) : nlohmann::json(texts);
}

bool check_config(DaemonConfig& config, std::string& error) {
  if (config.watch.empty()) {
    error = std::string("nothing to watch: give --watch DIR or \"watch\" in the config") +
            (xdg_folder("XDG_DATA_HOME", ".").empty() ? kNoHome : "");
    return false;
  }
  if (config.output.empty()) {
    error = std::string("no output folder: give --output DIR or \"output\" in the config") +
            (xdg_folder("XDG_STATE_HOME", ".").empty() ? kNoHome : "");
    return false;
  }
  // The checks of values first: a config refused for one of them (a reload, most often) must not
  // leave its new watch and output folders created (s80cfg D12).
  if (!check_ranges(config, error)) return false;
  if (config.channel_prefix.empty() || config.channel_prefix.size() > 16) {
    error = "channel_prefix \"" + lcm_safe::printable(config.channel_prefix, 40) + "\" has " +
            std::to_string(config.channel_prefix.size()) + " characters: it must have 1 to 16";
    return false;
  }
  // LCM subscribes by POSIX regular expression and '/' separates a channel's parts: a prefix such
  // as "lab+1" or "robot(1)" was accepted, and rdtfd then never heard a REQUEST or JOINT_COMMAND
  // (s80cfg D5). Letters, digits, '_', '-' and '.' (escaped where rdtfd subscribes).
  for (const char c : config.channel_prefix) {
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.') continue;
    error = "channel_prefix \"" + lcm_safe::printable(config.channel_prefix, 40) + "\" holds \"" +
            lcm_safe::printable(std::string(1, c), 8) +
            "\": only letters, digits, '_', '-' and '.' are allowed (channels are subscribed by regular "
            "expression, and '/' separates their parts)";
    return false;
  }
  if (!check_lcm_url(config.lcm_url, error)) return false;
  // The non-throwing calls throughout: a folder below one rdtfd cannot search (a 0700 home folder
  // under the packaged unit's user) threw filesystem_error out of the start, an abort and a core
  // dump (s80cfg D4); it is a bad setting, named with the system's reason.
  std::error_code ec;
  config.created_watch_folders.clear();
  for (auto& folder : config.watch) {
    std::error_code exists_error;
    const bool existed = std::filesystem::exists(std::filesystem::symlink_status(folder, exists_error));
    if (std::filesystem::create_directories(folder, ec) && !existed) config.created_watch_folders.push_back(folder);
    std::error_code status;
    if (!std::filesystem::is_directory(folder, status)) {
      error = "watch folder " + folder.string() +
              (status ? " cannot be looked at: " + status.message() : std::string(" is not a directory"));
      return false;
    }
    auto canonical = std::filesystem::canonical(folder, status);
    if (status) {
      error = "watch folder " + folder.string() + " cannot be resolved: " + status.message();
      return false;
    }
    folder = std::move(canonical);
  }
  std::filesystem::create_directories(config.output, ec);
  std::error_code status;
  if (!std::filesystem::is_directory(config.output, status)) {
    error = "output folder " + config.output.string() + " cannot be created: " +
            (status ? status.message() : ec ? ec.message() : std::string("it is not a directory"));
    return false;
  }
  auto output = std::filesystem::canonical(config.output, status);
  if (status) {
    error = "output folder " + config.output.string() + " cannot be resolved: " + status.message();
    return false;
  }
  config.output = std::move(output);
  for (const auto& folder : config.watch) {
    // An output folder that contains a watched folder would hide every save in it.
    const auto relative = folder.lexically_relative(config.output);
    if (!relative.empty() && *relative.begin() != "..") {
      error = "output folder " + config.output.string() + " contains the watched folder " +
              folder.string() + ": choose an output folder outside it (or inside the watched one)";
      return false;
    }
  }
  return true;
}

namespace {
std::string reload_text(unsigned effects);
}  // namespace

ConfigChange compare_configs(const DaemonConfig& running, const DaemonConfig& fresh) {
  ConfigChange change;
  for (const ConfigKey& key : config_registry()) {
    if (key.get(running) != key.get(fresh)) {
      change.keys.push_back(key.name);
      change.effects |= key.reload;
    }
  }
  return change;
}

std::string change_text(const ConfigChange& change) {
  if (change.keys.empty()) return "no setting changed";
  std::string applied, kept;
  for (const std::string& name : change.keys) {
    const ConfigKey* key = nullptr;
    for (const ConfigKey& k : config_registry()) {
      if (k.name == name) key = &k;
    }
    if (key == nullptr) continue;
    if ((key->reload & kNeedsRestart) != 0) {
      kept += (kept.empty() ? "" : ", ") + name;
    } else {
      applied += (applied.empty() ? "" : ", ") + name + " (" + reload_text(key->reload) + ")";
    }
  }
  std::string text = applied.empty() ? std::string() : "changed " + applied;
  if (!kept.empty()) text += (text.empty() ? "" : "; ") + std::string("kept until a restart: ") + kept;
  return text;
}

void keep_restart_settings(const DaemonConfig& running, DaemonConfig& fresh) {
  std::string error;
  for (const ConfigKey& key : config_registry()) {
    if ((key.reload & kNeedsRestart) != 0) key.set(key.get(running), "", fresh, error);
  }
}

namespace {

// The shortest text that reads back as `value`, but whole numbers below 1e9 and fractions down to
// 1e-4 written out (600000, 0.0001, 4294967296, 1e+10, 1e-12).
std::string shortest_text(double value) {
  char buffer[64];
  const double size = std::abs(value);
  const bool written_out = (value == std::floor(value) && size < 1e9) || (size >= 1e-4 && size < 1);
  const auto result = written_out ? std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::fixed)
                                  : std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string reload_text(unsigned effects) {
  if ((effects & kNeedsRestart) != 0) return "needs a restart";
  std::vector<std::string> parts;
  if ((effects & kFoldersChanged) != 0) parts.push_back("rescans the new folders");
  if ((effects & kReconnect) != 0) parts.push_back("reopens LCM");
  if ((effects & kReconvert) != 0) parts.push_back("converts every model again");
  if ((effects & kRestartSimulation) != 0) parts.push_back("restarts the simulations");
  if (parts.empty()) return "live";
  std::string text = parts[0];
  for (std::size_t i = 1; i < parts.size(); ++i) text += ", " + parts[i];
  return text;
}

}  // namespace

std::string settings_table_markdown() {
  const DaemonConfig defaults = default_config();
  std::string table =
      "| key | default | unit | range | on reload | meaning |\n"
      "| --- | --- | --- | --- | --- | --- |\n";
  for (const ConfigKey& key : config_registry()) {
    std::string range = key.range_text;
    if (range.empty() && key.min && key.max) range = shortest_text(*key.min) + " .. " + shortest_text(*key.max);
    std::string meaning = key.doc;
    if (!key.flag.empty()) meaning += " (`" + key.flag.substr(key.flag.find("--")) + "`)";
    table += "| `" + key.name + "` | " +
             (key.default_text.empty() ? "`" + key.get(defaults).dump() + "`" : key.default_text) + " | " +
             key.unit + " | " + range + " | " + reload_text(key.reload) + " | " + meaning + " |\n";
  }
  return table;
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
