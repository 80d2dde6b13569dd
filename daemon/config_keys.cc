// The registry of rdtfd's settings: one row per key of config/rdtfd.json.
//
// To add a setting:
//   1. add its field to DaemonConfig (daemon/config.h) with the built-in default;
//   2. add one row below: key<Codec>({name, kind, unit, range, reload effects, option, doc}, field);
//      the codec is Plain (bool, integers, double, string), Millis, Folders, Folder, StepperName,
//      MasslessSeverity or Vector3 - or a new one of a few lines for a new kind of value;
//   3. add the key with its default to config/rdtfd.json, and regenerate docs/daemon.md's settings
//      table: `RDTF_UPDATE_DOCS=1 build/tests/rdtf_tests --gtest_filter='DaemonConfigRegistry.*'`.
// Tests fail until 3 is done: DaemonConfig.RepositoryConfigFileListsEveryKeyWithItsDefault and
// DaemonConfigRegistry.DocsTableIsGeneratedFromTheRegistry.
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>

#include "config.h"

namespace rdtf::daemon {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

std::string wrong_type(const std::string& name, const json& value) {
  return "\"" + name + "\" has the wrong type (" + value.type_name() + ")";
}

// JSON's own type must match the setting's: a boolean is no number, -1 is no count.
template <typename T>
struct Plain {
  static constexpr ValueKind kind = std::is_same_v<T, bool>                ? ValueKind::kBoolean
                                    : std::is_integral_v<T>                ? ValueKind::kInteger
                                    : std::is_floating_point_v<T>          ? ValueKind::kNumber
                                                                           : ValueKind::kString;
  static bool decode(const std::string& name, const json& value, const fs::path&, T& out, std::string& error) {
    bool ok = false;
    if constexpr (std::is_same_v<T, bool>) {
      ok = value.is_boolean();
    } else if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T>) {
      ok = value.is_number_unsigned();
      // A count beyond the type wrapped silently (workers 4294967298 ran 2: s80cfg D9).
      if (ok && value.get<std::uint64_t>() > std::numeric_limits<T>::max()) {
        error = "\"" + name + "\" is " + value.dump() + ", more than " + std::to_string(std::numeric_limits<T>::max());
        return false;
      }
    } else if constexpr (std::is_integral_v<T>) {
      ok = value.is_number_integer();
      if (ok && (value.get<std::int64_t>() > std::numeric_limits<T>::max() ||
                 value.get<std::int64_t>() < std::numeric_limits<T>::min())) {
        error = "\"" + name + "\" is " + value.dump() + ", beyond what it can hold";
        return false;
      }
    } else if constexpr (std::is_floating_point_v<T>) {
      ok = value.is_number();
    } else {
      ok = value.is_string();
    }
    if (!ok) {
      error = wrong_type(name, value);
      return false;
    }
    out = value.get<T>();
    return true;
  }
  static json encode(const T& value) { return value; }
  static std::vector<double> numbers(const T& value) {
    if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
      return {static_cast<double>(value)};
    } else {
      return {};
    }
  }
};

// Whole milliseconds, given as a JSON number. A fraction was cut without a word (0.5 turned
// republishing off, 60000.9 passed a maximum of 60000: s80cfg D11), and a value beyond 2^63 came
// out negative: both refused.
struct Millis {
  static constexpr ValueKind kind = ValueKind::kNumber;
  static bool decode(const std::string& name, const json& value, const fs::path& base, std::chrono::milliseconds& out,
                     std::string& error) {
    double ms = 0;
    if (!Plain<double>::decode(name, value, base, ms, error)) return false;
    if (!(ms >= 0) || ms != std::floor(ms)) {
      error = "\"" + name + "\" is " + value.dump() + ": it must be a whole number of milliseconds, 0 or more";
      return false;
    }
    if (ms >= 9.2e18) {
      error = "\"" + name + "\" is " + value.dump() + " ms, beyond any setting's range (docs/daemon.md)";
      return false;
    }
    out = std::chrono::milliseconds(static_cast<long long>(ms));
    return true;
  }
  static json encode(std::chrono::milliseconds value) { return value.count(); }
  static std::vector<double> numbers(std::chrono::milliseconds value) { return {static_cast<double>(value.count())}; }
};

bool all_strings(const json& value) {
  return value.is_array() && std::all_of(value.begin(), value.end(), [](const json& v) { return v.is_string(); });
}

struct Folders {
  static constexpr ValueKind kind = ValueKind::kFolders;
  static bool decode(const std::string& name, const json& value, const fs::path& base, std::vector<fs::path>& out,
                     std::string& error) {
    if (!all_strings(value)) {
      error = wrong_type(name, value);
      return false;
    }
    out.clear();
    for (const json& folder : value) out.push_back(base / folder.get<std::string>());
    return true;
  }
  static json encode(const std::vector<fs::path>& folders) {
    json out = json::array();
    for (const auto& folder : folders) out.push_back(folder.string());
    return out;
  }
  static std::vector<double> numbers(const std::vector<fs::path>&) { return {}; }
};

struct Folder {
  static constexpr ValueKind kind = ValueKind::kFolder;
  static bool decode(const std::string& name, const json& value, const fs::path& base, fs::path& out,
                     std::string& error) {
    std::string folder;
    if (!Plain<std::string>::decode(name, value, base, folder, error)) return false;
    out = base / folder;
    return true;
  }
  static json encode(const fs::path& folder) { return folder.string(); }
  static std::vector<double> numbers(const fs::path&) { return {}; }
};

struct StepperName {
  static constexpr ValueKind kind = ValueKind::kName;
  static bool decode(const std::string& name, const json& value, const fs::path& base, Stepper& out,
                     std::string& error) {
    std::string text;
    if (!Plain<std::string>::decode(name, value, base, text, error)) return false;
    const auto parsed = parse_stepper(text);
    if (!parsed) {
      error = "\"" + name + "\" must be \"auto\", \"world_step\" or \"quick_step\", not \"" + text + "\"";
      return false;
    }
    out = *parsed;
    return true;
  }
  static json encode(Stepper stepper) {
    return stepper == Stepper::kWorldStep ? "world_step" : stepper == Stepper::kQuickStep ? "quick_step" : "auto";
  }
  static std::vector<double> numbers(Stepper) { return {}; }
};

// "warning" or "error", kept as DaemonConfig::massless_link_error.
struct MasslessSeverity {
  static constexpr ValueKind kind = ValueKind::kName;
  static bool decode(const std::string& name, const json& value, const fs::path& base, bool& is_error,
                     std::string& error) {
    std::string text;
    if (!Plain<std::string>::decode(name, value, base, text, error)) return false;
    if (text != "warning" && text != "error") {
      error = "\"" + name + "\" must be \"warning\" or \"error\"";
      return false;
    }
    is_error = text == "error";
    return true;
  }
  static json encode(bool is_error) { return is_error ? "error" : "warning"; }
  static std::vector<double> numbers(bool) { return {}; }
};

struct Vector3 {
  static constexpr ValueKind kind = ValueKind::kVector3;
  static bool decode(const std::string& name, const json& value, const fs::path&, Eigen::Vector3d& out,
                     std::string& error) {
    if (!value.is_array() || !std::all_of(value.begin(), value.end(), [](const json& v) { return v.is_number(); })) {
      error = wrong_type(name, value);
      return false;
    }
    if (value.size() != 3) {
      error = "\"" + name + "\" must be three numbers (m/s^2, scene frame)";
      return false;
    }
    out = Eigen::Vector3d(value[0].get<double>(), value[1].get<double>(), value[2].get<double>());
    return true;
  }
  static json encode(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }
  static std::vector<double> numbers(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
};

// A row: the key's description plus the field, reached by `field(config)` for a const or a mutable
// config, read and written through the codec.
template <typename Codec, typename Field>
ConfigKey key(ConfigKey row, Field field) {
  row.kind = Codec::kind;
  row.get = [field](const DaemonConfig& config) { return Codec::encode(field(config)); };
  row.set = [field, name = row.name](const json& value, const fs::path& base, DaemonConfig& config,
                                     std::string& error) { return Codec::decode(name, value, base, field(config), error); };
  row.numbers = [field](const DaemonConfig& config) { return Codec::numbers(field(config)); };
  return row;
}

template <typename Field>
ConfigKey plain(ConfigKey row, Field field) {
  using T = std::remove_cvref_t<decltype(field(std::declval<DaemonConfig&>()))>;
  return key<Plain<T>>(std::move(row), field);
}

#define RDTF_FIELD(member) [](auto& c) -> auto& { return c.member; }

constexpr double kTiB = 1099511627776.0;
constexpr unsigned kDynamics = kReconvert | kRestartSimulation;  // The check and the live simulation.

// A row names only what it has: the fields it leaves out keep ConfigKey's defaults, by design.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
std::vector<ConfigKey> make_registry() {
  return {
      key<Folders>({.name = "watch", .reload = kFoldersChanged, .flag = "-w,--watch",
                    .flag_help = "Folder to watch, recursively (repeatable; default ~/.local/share/rdtf/models)",
                    .default_text = "`[\"~/.local/share/rdtf/models\"]` ($XDG_DATA_HOME)",
                    .doc = "folders watched recursively (relative paths: relative to the config file)"},
                   RDTF_FIELD(watch)),
      key<Folder>({.name = "output", .reload = kFoldersChanged | kReconvert, .flag = "-o,--output",
                   .flag_help = "Folder for RDTF outputs (default ~/.local/state/rdtf/output)",
                   .default_text = "`\"~/.local/state/rdtf/output\"` ($XDG_STATE_HOME)",
                   .doc = "outputs: `<output>/<model_id>/<name>.rdtf.gltf` and its buffers (see Outputs); events "
                          "inside it are ignored, even when it lies inside a watched folder"},
                  RDTF_FIELD(output)),
      plain({.name = "lcm_url", .reload = kReconnect | kRestartSimulation, .flag = "--lcm-url",
             .flag_help = "LCM URL (default: LCM_DEFAULT_URL, else LCM's default)",
             .doc = "LCM URL, `\"\"` for `LCM_DEFAULT_URL`, else LCM's default"},
            RDTF_FIELD(lcm_url)),
      plain({.name = "channel_prefix", .range_text = "1 .. 16 letters, digits, `_`, `-`, `.`", .reload = kReconnect | kRestartSimulation,
             .flag = "--channel-prefix", .flag_help = "First part of every channel (default RDTF)",
             .doc = "first part of every channel"},
            RDTF_FIELD(channel_prefix)),
      key<Millis>({.name = "settle_ms", .unit = "ms", .min = 1, .max = 60000, .flag = "--settle-ms",
                   .flag_help = "Quiet time after a save before converting (default 50)",
                   .doc = "quiet time after a model's last event before it is converted"},
                  RDTF_FIELD(settle)),
      key<Millis>({.name = "max_open_wait_ms", .unit = "ms", .min = 0, .max = 600000,
                   .doc = "longest wait for a writer that modified a file to close it"},
                  RDTF_FIELD(max_open_wait)),
      plain({.name = "convert_while_settling", .flag = "--no-convert-while-settling",
             .flag_help = "Convert a save only once it has settled, not during the settle period", .flag_sets = false,
             .doc = "once a settling model's files are closed, convert it and stage its outputs during the settle "
                    "period, and publish them at its end unless a file changed meanwhile (then they are dropped: "
                    "\"Converting while settling\"); false: convert only after it, which spends less CPU on "
                    "bursts of saves"},
            RDTF_FIELD(convert_while_settling)),
      key<Millis>({.name = "republish_period_ms", .unit = "ms", .min = 0, .max = 86400000,
                   .range_text = "0 (off) or 10 .. 86400000", .flag = "--republish-ms",
                   .flag_help = "Period of republishing every description; 0 disables (default 5000)",
                   .doc = "every description again, for late subscribers; 0 disables"},
                  RDTF_FIELD(republish_period)),
      key<Millis>({.name = "status_period_ms", .unit = "ms", .min = 10, .max = 60000, .doc = "heartbeat period"},
                  RDTF_FIELD(status_period)),
      plain({.name = "workers", .min = 1, .max = 64, .reload = kNeedsRestart, .flag = "--workers",
             .flag_help = "Conversion threads (default 2)", .doc = "conversion threads, besides the express worker for small models (see above)"},
            RDTF_FIELD(workers)),
      plain({.name = "max_chunk_bytes", .unit = "bytes", .min = 1024, .max = 65000,
             .doc = "largest message sent (one UDP datagram): RDTF JSON and URDF that do not fit inline go in "
                    "chunks, a long inertia table in several messages (docs/lcm.md)"},
            RDTF_FIELD(max_chunk_bytes)),
      plain({.name = "chunk_rate_bytes_per_s", .unit = "bytes/s", .min = 1e4, .max = 1e10,
             .doc = "pacing of everything sent but joint and link states, in receive-buffer bytes (docs/lcm.md, "
                    "\"Large descriptions\")"},
            RDTF_FIELD(chunk_rate_bytes_per_s)),
      plain({.name = "default_density", .unit = "kg/m^3", .min = 1e-3, .max = 1e6, .reload = kReconvert,
             .flag = "--density", .flag_help = "Default density, kg/m^3 (default 1000)",
             .doc = "density of meshes without `rdtf_density`"},
            RDTF_FIELD(convert.default_density)),
      plain({.name = "max_file_bytes", .unit = "bytes", .min = 1, .max = kTiB, .reload = kReconvert,
             .doc = "input limit: largest model file (docs/format.md)"},
            RDTF_FIELD(convert.limits.max_file_bytes)),
      plain({.name = "max_buffer_bytes", .unit = "bytes", .min = 1, .max = kTiB, .reload = kReconvert,
             .doc = "input limit: largest buffer (docs/format.md)"},
            RDTF_FIELD(convert.limits.max_buffer_bytes)),
      plain({.name = "max_accessor_count", .min = 1, .max = 4294967296.0, .reload = kReconvert,
             .doc = "input limit: most elements in an accessor (docs/format.md)"},
            RDTF_FIELD(convert.limits.max_accessor_count)),
      plain({.name = "max_triangles", .min = 1, .max = 4294967296.0, .reload = kReconvert,
             .doc = "input limit: most triangles in a model, a mesh counted per node using it and a vertex a "
                    "weighed morph target moves as one (docs/format.md)"},
            RDTF_FIELD(convert.limits.max_triangles)),
      plain({.name = "max_read_bytes", .unit = "bytes", .min = 1, .max = kTiB, .reload = kReconvert,
             .doc = "bytes one conversion may read: the model plus every file it names, each counted as often as "
                    "it is named; checked (by size) before anything is read, refused with `LIMIT_EXCEEDED`"},
            RDTF_FIELD(max_read_bytes)),
      plain({.name = "max_read_bytes_in_flight", .unit = "bytes", .min = 1, .max = 4 * kTiB,
             .range_text = "`max_read_bytes` .. 4398046511104",
             .doc = "bytes every conversion in flight may read together: a worker whose model would go beyond it "
                    "waits until others finish (one conversion always runs)"},
            RDTF_FIELD(max_read_bytes_in_flight)),
      plain({.name = "validate", .reload = kReconvert, .flag = "--no-validate",
             .flag_help = "Publish without the ODE dynamics check", .flag_sets = false,
             .doc = "check every revision in ODE (docs/dynamics.md) before publishing it"},
            RDTF_FIELD(validate)),
      plain({.name = "validation_seconds", .unit = "s", .min = 1e-3, .max = 60, .reload = kReconvert,
             .doc = "simulated time of that check"},
            RDTF_FIELD(validation_seconds)),
      plain({.name = "publish_failed", .reload = kReconvert, .flag = "--publish-failed",
             .flag_help = "Publish revisions that fail the dynamics check (marked failed) instead of keeping the "
                          "last good one",
             .flag_sets = true,
             .doc = "publish a revision that fails the check, marked failed, instead of keeping the last good one"},
            RDTF_FIELD(publish_failed)),
      plain({.name = "time_step", .unit = "s", .min = 1e-4, .max = 0.1, .reload = kDynamics,
             .doc = "step of the check and of the live simulation"},
            RDTF_FIELD(time_step)),
      key<StepperName>({.name = "stepper", .reload = kDynamics,
                        .doc = "`auto` (dWorldStep while the largest island, bodies joined by joints, has fewer than 27 bodies; QuickStep from 27, and dWorldStep again, in the check and live, for a model of up to 100 bodies in one island whose QuickStep run fails: SIM_QUICKSTEP_FAILED), `world_step` or `quick_step`"},
                       RDTF_FIELD(stepper)),
      plain({.name = "max_mass_ratio", .min = 1, .max = 1e12, .reload = kReconvert,
             .doc = "largest mass ratio across a joint before the check fails"},
            RDTF_FIELD(max_mass_ratio)),
      plain({.name = "validation_start_offset_rad", .unit = "rad", .min = -6.2832, .max = 6.2832, .reload = kReconvert,
             .doc = "how far from rest revolute and continuous joints start the check (0: the rest pose)"},
            RDTF_FIELD(validation_start_offset_rad)),
      plain({.name = "energy_tolerance", .min = 1e-12, .max = 1e6, .reload = kReconvert,
             .doc = "relative energy rise that fails the check"},
            RDTF_FIELD(energy_tolerance)),
      plain({.name = "joint_separation_tolerance_m", .unit = "m", .min = 1e-12, .max = 1e3, .reload = kReconvert,
             .doc = "joint separation that fails it (plus a share of the model's size, docs/dynamics.md)"},
            RDTF_FIELD(joint_separation_tolerance_m)),
      plain({.name = "limit_tolerance_rad", .unit = "rad", .min = 1e-12, .max = 6.2832, .reload = kReconvert,
             .doc = "how far beyond a limit a revolute joint may go"},
            RDTF_FIELD(limit_tolerance_rad)),
      plain({.name = "limit_tolerance_m", .unit = "m", .min = 1e-12, .max = 1e3, .reload = kReconvert,
             .doc = "how far beyond a limit a prismatic joint may go"},
            RDTF_FIELD(limit_tolerance_m)),
      plain({.name = "bound_mass_kg", .unit = "kg", .min = 0, .max = 1e6, .range_text = "0 (off) .. 1e+06",
             .reload = kDynamics,
             .doc = "a moving body without mass (a link, with the links fixed to it, that has none) is checked and "
                    "simulated with this mass and `bound_inertia_kgm2` when both are > 0, as MuJoCo's "
                    "`boundmass`/`boundinertia`; 0: off, and such a link fails the check with `LINK_MASS_ZERO` "
                    "(docs/dynamics.md)"},
            RDTF_FIELD(bound_mass_kg)),
      plain({.name = "bound_inertia_kgm2", .unit = "kg m^2", .min = 0, .max = 1e6, .range_text = "0 (off) .. 1e+06",
             .reload = kDynamics, .doc = "the inertia about each axis that goes with `bound_mass_kg`"},
            RDTF_FIELD(bound_inertia_kgm2)),
      key<MasslessSeverity>({.name = "massless_link_severity", .reload = kReconvert,
                             .doc = "with the bound above, a massless moving link is a `warning` or still an `error`"},
                            RDTF_FIELD(massless_link_error)),
      plain({.name = "validation_cpu_budget_s", .unit = "s", .min = 0, .max = 86400,
             .range_text = "0 (no limit) .. 86400", .reload = kReconvert,
             .doc = "CPU seconds one check may take (checks, model and run); beyond, it stops with "
                    "`SIM_BUDGET_EXCEEDED` and the revision fails; 0: no limit. On shutdown a check in progress is "
                    "cancelled, not waited for"},
            RDTF_FIELD(validation_cpu_budget_s)),
      plain({.name = "simulate", .reload = kRestartSimulation, .flag = "--no-simulate",
             .flag_help = "Run no live simulation (no joint states)", .flag_sets = false,
             .doc = "run every live model in ODE and publish its joint states"},
            RDTF_FIELD(simulate)),
      plain({.name = "state_rate_hz", .unit = "Hz", .min = 0.1, .max = 10000, .reload = kRestartSimulation,
             .flag = "--state-rate-hz", .flag_help = "Joint-state messages per second and model (default 100)",
             .doc = "joint-state messages per wall-clock second and model, at most one per step (`real_time_factor` / "
                    "`time_step`, 1,000 with the defaults; a higher rate is logged and gives one per step)"},
            RDTF_FIELD(state_rate_hz)),
      plain({.name = "real_time_factor", .min = 0.01, .max = 100, .reload = kRestartSimulation,
             .doc = "simulated seconds per wall-clock second"},
            RDTF_FIELD(real_time_factor)),
      plain({.name = "joint_command_timeout_s", .unit = "s", .min = 0.01, .max = 60, .reload = kRestartSimulation,
             .doc = "lifetime of a joint command: a joint no accepted command has named for this long is "
                    "released (passive again; docs/controller.md)"},
            RDTF_FIELD(joint_command_timeout_s)),
      plain({.name = "floating_root", .reload = kDynamics, .flag = "--floating-root",
             .flag_help = "Root links float instead of being fixed to the world", .flag_sets = true,
             .doc = "root links float instead of being fixed to the world"},
            RDTF_FIELD(floating_root)),
      key<Vector3>({.name = "gravity", .unit = "m/s^2", .min = -1e3, .max = 1e3, .range_text = "-1000 .. 1000 each",
                    .reload = kDynamics, .flag = "--gravity",
                    .flag_help = "Gravity in the scene frame, m/s^2 (default 0 -9.80665 0: glTF is Y up)",
                    .doc = "in the scene frame; glTF is Y up, so Z-up content sets `[0, 0, -9.80665]`"},
                   RDTF_FIELD(gravity)),
      plain({.name = "urdf", .reload = kReconvert, .flag = "--no-urdf",
             .flag_help = "Write no URDF beside the RDTF outputs", .flag_sets = false,
             .doc = "write `<output>/<model_id>/urdf/robot.urdf` (+ meshes) and put the URDF text in the description"},
            RDTF_FIELD(urdf)),
      plain({.name = "urdf_y_up", .reload = kReconvert, .doc = "keep glTF's Y up in the URDF instead of ROS's Z up"},
            RDTF_FIELD(urdf_y_up)),
      plain({.name = "max_cached_results", .min = 0, .max = 1e7, .range_text = "0 (off) .. 10000000",
             .reload = kNeedsRestart,
             .doc = "results kept across restarts in `<output>/.rdtfd-state/results/` (one entry per model file, a "
                    "few KiB for a small robot), so that a restart publishes unchanged models without converting "
                    "them; beyond this many the least recently used go (see Result cache); 0: no cache"},
            RDTF_FIELD(max_cached_results)),
  };
}
#pragma GCC diagnostic pop

#undef RDTF_FIELD

}  // namespace

const std::vector<ConfigKey>& config_registry() {
  static const std::vector<ConfigKey> registry = make_registry();
  return registry;
}

}  // namespace rdtf::daemon
