#include "config.h"

#include <cstdlib>
#include <fstream>

#include <nlohmann/json.hpp>

namespace rdtf::daemon {
namespace {

std::filesystem::path xdg_folder(const char* variable, const char* fallback) {
  if (const char* value = std::getenv(variable); value != nullptr && *value == '/') return value;
  const char* home = std::getenv("HOME");
  return std::filesystem::path(home != nullptr ? home : "/tmp") / fallback;
}

template <typename T>
bool read_key(const nlohmann::json& json, const char* key, T& out, std::string& error) {
  if (!json.contains(key)) return true;
  try {
    out = json[key].get<T>();
    return true;
  } catch (const nlohmann::json::exception&) {
    error = std::string("\"") + key + "\" has the wrong type";
    return false;
  }
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

DaemonConfig default_config() {
  DaemonConfig config;
  config.watch = {xdg_folder("XDG_DATA_HOME", ".local/share") / "rdtf" / "models"};
  config.output = xdg_folder("XDG_STATE_HOME", ".local/state") / "rdtf" / "output";
  return config;
}

std::optional<DaemonConfig> load_config(const std::filesystem::path& path, DaemonConfig config,
                                        std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = path.string() + ": cannot read the config file";
    return std::nullopt;
  }
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    error = path.string() + ": invalid JSON: " + e.what();
    return std::nullopt;
  }
  if (!json.is_object()) {
    error = path.string() + ": the config must be a JSON object";
    return std::nullopt;
  }
  static const char* const kKeys[] = {
      "watch", "output", "lcm_url", "channel_prefix", "settle_ms", "max_open_wait_ms",
      "republish_period_ms", "status_period_ms", "workers", "max_chunk_bytes",
      "chunk_rate_bytes_per_s", "default_density", "max_file_bytes", "max_buffer_bytes",
      "max_accessor_count", "max_triangles", "_comment"};
  for (const auto& [key, value] : json.items()) {
    if (std::find(std::begin(kKeys), std::end(kKeys), key) == std::end(kKeys)) {
      error = path.string() + ": unknown key \"" + key + "\"";
      return std::nullopt;
    }
  }
  // Relative folders are relative to the config file's folder.
  const auto base = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
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
            read_key(json, "max_triangles", config.convert.limits.max_triangles, error);
  if (!ok) {
    error = path.string() + ": " + error;
    return std::nullopt;
  }
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

}  // namespace rdtf::daemon
