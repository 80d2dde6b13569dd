// rdtfd's settings: a JSON file (config/rdtfd.json documents every key), overridden by the
// command line. Reloaded on SIGHUP.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "rdtf/convert.h"
#include "rdtf/dynamics.h"

namespace rdtf::daemon {

struct DaemonConfig {
  std::vector<std::filesystem::path> watch;  // Folders watched recursively.
  // Not a setting: the watch folders check_config made because they did not exist, so that the
  // log says so (a typo in --watch became a new, empty, silently watched folder; s100java D1).
  std::vector<std::filesystem::path> created_watch_folders;
  std::filesystem::path output;              // Where RDTF and URDF files go (events there are ignored).
  std::string lcm_url;                       // "" = LCM's default (LCM_DEFAULT_URL or udpm).
  std::string channel_prefix = "RDTF";
  std::chrono::milliseconds settle{50};      // Quiet time after the last event of a model.
  std::chrono::milliseconds max_open_wait{5000};  // Longest wait for a writer to close a file.
  // Convert a model whose files are closed during its settle period, publish at its end.
  bool convert_while_settling = true;
  std::chrono::milliseconds republish_period{5000};  // Descriptions again, for late subscribers.
  std::chrono::milliseconds status_period{1000};
  int workers = 2;                           // Conversion threads.
  std::size_t max_chunk_bytes = 60000;       // Largest LCM payload per description chunk.
  double chunk_rate_bytes_per_s = 32e6;      // Pacing of chunks, so receivers keep up.
  ConvertOptions convert;
  // What one conversion may read (the model and every file it names, each time it is named), and
  // what every conversion in flight may read together.
  std::uint64_t max_read_bytes = std::uint64_t{1} << 30;
  std::uint64_t max_read_bytes_in_flight = std::uint64_t{2} << 30;

  // Dynamics (docs/dynamics.md): every revision is validated in ODE before it is published.
  bool validate = true;
  double validation_seconds = 3.0;        // Simulated time of the validation run.
  bool publish_failed = false;            // Publish a revision that fails validation (marked failed).
  bool simulate = true;                   // Run every live model and publish its joint states.
  double state_rate_hz = 100;             // Joint-state messages per second and model.
  double real_time_factor = 1.0;
  // A joint whose commands stop arriving for this long (s of the daemon's clock) is released:
  // passive again (docs/controller.md, "Command lifetime").
  double joint_command_timeout_s = 0.5;
  bool floating_root = false;             // Default: root links are fixed to the world.
  Eigen::Vector3d gravity{0, -9.80665, 0};  // Scene frame; glTF is Y up. Z-up content: {0, 0, -9.80665}.
  double time_step = 1e-3;                // s, of the validation run and the live simulation.
  Stepper stepper = Stepper::kAuto;       // "auto", "world_step" or "quick_step".
  // The gate's checks and thresholds (ValidationOptions in core/include/rdtf/dynamics.h).
  double max_mass_ratio = 1e3;            // Across a joint.
  double validation_start_offset_rad = 0; // Revolute joints start this far from rest (0: rest pose).
  double energy_tolerance = 0.01;         // Relative rise of the total energy.
  double joint_separation_tolerance_m = 1e-3;
  double limit_tolerance_rad = 1e-2;
  double limit_tolerance_m = 1e-3;
  // A moving body without mass is simulated with this mass and inertia when both are > 0 (MuJoCo's
  // boundmass/boundinertia); off (0) by default, when such a link fails the check.
  double bound_mass_kg = 0;
  double bound_inertia_kgm2 = 0;
  bool massless_link_error = false;       // "massless_link_severity": "warning" (default) or "error"
  double validation_cpu_budget_s = 30;    // CPU seconds one check may take (0: no limit).

  // URDF beside each RDTF output (docs/urdf.md), and its text in the description.
  bool urdf = true;
  bool urdf_y_up = false;                 // Keep glTF's Y up instead of ROS's Z up.

  // Results kept across restarts (daemon/result_cache.h): at most this many entries; 0: no cache.
  std::size_t max_cached_results = 20000;
};

// "auto", "world_step" or "quick_step"; nothing for another name.
std::optional<Stepper> parse_stepper(std::string_view name);

// The dynamics settings as the core library takes them: the gate's, and the live simulation's.
ValidationOptions validation_options(const DaemonConfig& config);
SimulationOptions simulation_options(const DaemonConfig& config);

// What a reload that changes a key does (bits; 0 = applied live, nothing else happens).
enum ReloadEffect : unsigned {
  kApplyLive = 0,
  kReconvert = 1u << 0,          // Every model is converted again (a same result keeps its revision).
  kRestartSimulation = 1u << 1,  // The live simulations are started again.
  kReconnect = 1u << 2,          // LCM is opened again.
  kFoldersChanged = 1u << 3,     // The rescan after the reload says the folders changed.
  kNeedsRestart = 1u << 4,       // Not applied by a reload: the running value stays until a restart.
};

// How a key's value is written: picks the JSON type checked and how command-line text is read.
enum class ValueKind { kBoolean, kInteger, kNumber, kString, kName, kFolder, kFolders, kVector3 };

// One setting: everything about it that is not the DaemonConfig field itself. The registry of these
// (daemon/config_keys.cc) is the one place a setting is described: parsing of the file and of
// --set, the command-line options, the range check, the reload comparison, the defaults test of
// config/rdtfd.json and the settings table of docs/daemon.md all come from it.
struct ConfigKey {
  std::string name;                // As in the file, e.g. "settle_ms".
  ValueKind kind = ValueKind::kNumber;
  std::string unit;                // "ms", "kg/m^3", ... ("" for none).
  std::optional<double> min;       // The valid range, both ends included (each component of a vector).
  std::optional<double> max;
  std::string range_text;          // For the docs when the range is more than [min, max] ("0 (off) or ...").
  unsigned reload = kApplyLive;    // ReloadEffect bits.
  std::string flag;                // Command-line option ("-w,--watch"), "" for --set only.
  std::string flag_help;
  std::optional<nlohmann::json> flag_sets;  // For a switch (--no-urdf): the value it sets.
  std::string default_text;        // For the docs when the default depends on the environment.
  std::string doc;                 // The docs' meaning column.
  // Filled in by the registry from the field's codec:
  std::function<nlohmann::json(const DaemonConfig&)> get;
  std::function<bool(const nlohmann::json& value, const std::filesystem::path& base, DaemonConfig& config,
                     std::string& error)>
      set;  // Checks the JSON type (error names the key); relative folders relative to `base`.
  std::function<std::vector<double>(const DaemonConfig&)> numbers;  // What the range check checks.
};

// Every key, in the order of config/rdtfd.json and docs/daemon.md.
const std::vector<ConfigKey>& config_registry();
const ConfigKey* find_config_key(std::string_view name);

// Every key a config object may have ("_comment" is allowed too, and ignored).
const std::vector<std::string>& config_keys();

// Built-in defaults: watch $XDG_DATA_HOME/rdtf/models (~/.local/share/rdtf/models), write to
// $XDG_STATE_HOME/rdtf/output (~/.local/state/rdtf/output).
DaemonConfig default_config();

// The largest config file read (a config is a few hundred bytes).
inline constexpr std::uint64_t kMaxConfigFileBytes = 1 << 20;

// The valid range of a numeric key, both ends included (docs/daemon.md lists them).
struct KeyRange {
  const char* key;
  double min;
  double max;
};
const std::vector<KeyRange>& config_ranges();

// Reads a config file over `base`. Unknown keys and wrong types are errors naming the key. Only a
// regular file of at most kMaxConfigFileBytes is read (opened without blocking: a FIFO or a
// device given as the config is refused, never waited on).
std::optional<DaemonConfig> load_config(const std::filesystem::path& path, DaemonConfig base,
                                        std::string& error);

// The keys of a config object (as in the file) over `config`; relative folders are relative to
// `base`. What load_config does after parsing, and what `rdtfd --set KEY=VALUE` does.
std::optional<DaemonConfig> apply_config_json(const nlohmann::json& json, const std::filesystem::path& base,
                                              DaemonConfig config, std::string& error);

// A key's value from command-line text (--set KEY=TEXT, or the key's option): JSON where the key
// takes a number, a boolean or a list (else the text as a string, which the type check refuses);
// the text itself for a string, a name or a folder, so paths and prefixes need no quotes.
nlohmann::json value_from_text(const ConfigKey& key, const std::vector<std::string>& texts);

// Checks the settings make sense (folders exist or can be made, every number within its range). Creates
// missing watch and output folders and makes every folder absolute and canonical.
bool check_config(DaemonConfig& config, std::string& error);

// What a reload from `running` to `fresh` changes: the keys whose value differs and the union of
// their ReloadEffect bits.
struct ConfigChange {
  std::vector<std::string> keys;
  unsigned effects = 0;
  bool has(ReloadEffect effect) const { return (effects & effect) != 0; }
};
ConfigChange compare_configs(const DaemonConfig& running, const DaemonConfig& fresh);
// The keys a reload changed, each with what it does ("settle_ms (live)", "lcm_url (reopens LCM,
// restarts the simulations)"), and those kept until a restart; for the reload's log line.
std::string change_text(const ConfigChange& change);

// Puts the running value of every kNeedsRestart key into `fresh` (a reload does not apply them).
void keep_restart_settings(const DaemonConfig& running, DaemonConfig& fresh);

// docs/daemon.md's settings table, generated from the registry (a test keeps the docs equal to it).
std::string settings_table_markdown();

}  // namespace rdtf::daemon
