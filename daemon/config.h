// rdtfd's settings: a JSON file (config/rdtfd.json documents every key), overridden by the
// command line. Reloaded on SIGHUP.
#pragma once

#include <chrono>
#include <filesystem>
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
  std::filesystem::path output;              // Where RDTF and URDF files go (events there are ignored).
  std::string lcm_url;                       // "" = LCM's default (LCM_DEFAULT_URL or udpm).
  std::string channel_prefix = "RDTF";
  std::chrono::milliseconds settle{50};      // Quiet time after the last event of a model.
  std::chrono::milliseconds max_open_wait{5000};  // Longest wait for a writer to close a file.
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
};

// "auto", "world_step" or "quick_step"; nothing for another name.
std::optional<Stepper> parse_stepper(std::string_view name);

// The dynamics settings as the core library takes them: the gate's, and the live simulation's.
ValidationOptions validation_options(const DaemonConfig& config);
SimulationOptions simulation_options(const DaemonConfig& config);

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

// Checks the settings make sense (folders exist or can be made, every number within its range). Creates
// missing watch and output folders and makes every folder absolute and canonical.
bool check_config(DaemonConfig& config, std::string& error);

}  // namespace rdtf::daemon
