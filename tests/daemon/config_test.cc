// rdtfd's config file (daemon/config.h): every key read, unknown keys and wrong types refused
// with the key named, relative folders relative to the file, and the sanity checks.
#include "config.h"
#include "lcm_url.h"

#include <sys/stat.h>

#include <gtest/gtest.h>
#include <pwd.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <map>
#include <optional>

#include "support/test_support.h"

namespace rdtf::daemon {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

// Writes `json` to <folder>/rdtfd.json and loads it over the defaults.
std::optional<DaemonConfig> load_text(const testing::TempDir& folder, const std::string& json,
                                      std::string& error, DaemonConfig base = default_config()) {
  const auto path = folder / "rdtfd.json";
  testing::write_file(path, json);
  return load_config(path, std::move(base), error);
}

TEST(DaemonConfig, RepositoryConfigFileLoads) {
  const fs::path file = testing::data_dir() / ".." / ".." / "config" / "rdtfd.json";
  std::string error;
  auto config = load_config(file, default_config(), error);
  ASSERT_TRUE(config) << error;
  EXPECT_EQ(config->channel_prefix, "RDTF");
  EXPECT_EQ(config->settle, 50ms);
  EXPECT_EQ(config->republish_period, 5000ms);
  EXPECT_EQ(config->workers, 2);
  EXPECT_EQ(config->max_chunk_bytes, 60000u);
  ASSERT_EQ(config->watch.size(), 1u);
  // "../examples/models" relative to config/.
  EXPECT_EQ(fs::weakly_canonical(config->watch[0]),
            fs::weakly_canonical(testing::data_dir() / ".." / ".." / "examples" / "models"));
}

TEST(DaemonConfig, EveryKeyIsRead) {
  testing::TempDir folder;
  std::string error;
  auto config = load_text(folder, R"({
    "watch": ["/abs/models", "/abs/more"], "output": "/abs/out", "lcm_url": "udpm://239.255.76.67:7668?ttl=0",
    "channel_prefix": "ROBOTS", "settle_ms": 120, "max_open_wait_ms": 900,
    "republish_period_ms": 0, "status_period_ms": 250, "workers": 3, "max_chunk_bytes": 30000,
    "chunk_rate_bytes_per_s": 1e6, "default_density": 2700, "max_file_bytes": 1000,
    "max_buffer_bytes": 2000, "max_accessor_count": 3000, "max_triangles": 4000,
    "_comment": "ignored"})", error);
  ASSERT_TRUE(config) << error;
  EXPECT_EQ(config->watch, (std::vector<fs::path>{"/abs/models", "/abs/more"}));
  EXPECT_EQ(config->output, fs::path("/abs/out"));
  EXPECT_EQ(config->lcm_url, "udpm://239.255.76.67:7668?ttl=0");
  EXPECT_EQ(config->channel_prefix, "ROBOTS");
  EXPECT_EQ(config->settle, 120ms);
  EXPECT_EQ(config->max_open_wait, 900ms);
  EXPECT_EQ(config->republish_period, 0ms);
  EXPECT_EQ(config->status_period, 250ms);
  EXPECT_EQ(config->workers, 3);
  EXPECT_EQ(config->max_chunk_bytes, 30000u);
  EXPECT_DOUBLE_EQ(config->chunk_rate_bytes_per_s, 1e6);
  EXPECT_DOUBLE_EQ(config->convert.default_density, 2700);
  EXPECT_EQ(config->convert.limits.max_file_bytes, 1000u);
  EXPECT_EQ(config->convert.limits.max_buffer_bytes, 2000u);
  EXPECT_EQ(config->convert.limits.max_accessor_count, 3000u);
  EXPECT_EQ(config->convert.limits.max_triangles, 4000u);
}

TEST(DaemonConfig, MissingKeysKeepTheBaseValues) {
  testing::TempDir folder;
  DaemonConfig base = default_config();
  base.watch = {"/base/watch"};
  base.settle = 77ms;
  base.convert.default_density = 500;
  std::string error;
  auto config = load_text(folder, R"({"workers": 4})", error, base);
  ASSERT_TRUE(config) << error;
  EXPECT_EQ(config->workers, 4);
  EXPECT_EQ(config->watch, std::vector<fs::path>{"/base/watch"});
  EXPECT_EQ(config->settle, 77ms);
  EXPECT_DOUBLE_EQ(config->convert.default_density, 500);
  auto empty = load_text(folder, "{}", error, base);
  ASSERT_TRUE(empty) << error;
  EXPECT_EQ(empty->settle, 77ms);
}

TEST(DaemonConfig, UnknownKeyIsAnErrorNamingIt) {
  testing::TempDir folder;
  std::string error;
  EXPECT_FALSE(load_text(folder, R"({"settle_ms": 50, "setle_ms": 80})", error));
  EXPECT_NE(error.find("\"setle_ms\""), std::string::npos) << error;
  EXPECT_NE(error.find("unknown"), std::string::npos) << error;
  EXPECT_NE(error.find((folder / "rdtfd.json").string()), std::string::npos) << error;
}

TEST(DaemonConfig, WrongTypeIsAnErrorNamingTheKey) {
  testing::TempDir folder;
  const std::pair<const char*, const char*> cases[] = {
      {R"({"settle_ms": "fast"})", "settle_ms"},
      {R"({"watch": "/one/folder"})", "watch"},
      {R"({"watch": [1, 2]})", "watch"},
      {R"({"output": ["/a"]})", "output"},
      {R"({"lcm_url": 7667})", "lcm_url"},
      {R"({"channel_prefix": null})", "channel_prefix"},
      {R"({"workers": "two"})", "workers"},
      {R"({"default_density": {"steel": 7850}})", "default_density"},
      {R"({"max_triangles": "many"})", "max_triangles"},
      {R"({"republish_period_ms": [5000]})", "republish_period_ms"},
  };
  for (const auto& [json, key] : cases) {
    std::string error;
    EXPECT_FALSE(load_text(folder, json, error)) << json;
    EXPECT_NE(error.find(std::string("\"") + key + "\""), std::string::npos) << json << " -> " << error;
  }
}

TEST(DaemonConfig, BooleanForANumberIsAWrongType) {
  // nlohmann::json converts true to 1 when asked for a number: "workers": true must not quietly
  // mean one worker, nor "settle_ms": true one millisecond.
  testing::TempDir folder;
  for (const char* key : {"workers", "settle_ms", "default_density", "max_file_bytes"}) {
    std::string error;
    const auto config = load_text(folder, std::string(R"({")") + key + R"(": true})", error);
    EXPECT_FALSE(config) << key << ": true was accepted";
    if (!config) {
      EXPECT_NE(error.find(key), std::string::npos) << error;
    }
  }
}

TEST(DaemonConfig, NegativeLimitIsAnError) {
  // The limits are unsigned: -1 must not wrap around to 18446744073709551615 (no limit at all).
  testing::TempDir folder;
  for (const char* key : {"max_file_bytes", "max_buffer_bytes", "max_accessor_count", "max_triangles"}) {
    std::string error;
    const auto config = load_text(folder, std::string(R"({")") + key + R"(": -1})", error);
    if (config) {
      const auto& l = config->convert.limits;
      ADD_FAILURE() << key << ": -1 was accepted; limits now max_file_bytes " << l.max_file_bytes
                    << ", max_buffer_bytes " << l.max_buffer_bytes << ", max_accessor_count "
                    << l.max_accessor_count << ", max_triangles " << l.max_triangles;
    }
    if (!config) {
      EXPECT_NE(error.find(key), std::string::npos) << error;
    }
  }
}

TEST(DaemonConfig, NegativePeriodIsAnError) {
  testing::TempDir folder;
  std::string error;
  EXPECT_FALSE(load_text(folder, R"({"settle_ms": -5})", error));
  EXPECT_NE(error.find("settle_ms"), std::string::npos) << error;
}

TEST(DaemonConfig, BadFilesAreErrorsNamingTheFile) {
  testing::TempDir folder;
  std::string error;
  EXPECT_FALSE(load_text(folder, R"({"settle_ms": 50,)", error));
  EXPECT_NE(error.find("invalid JSON"), std::string::npos) << error;
  EXPECT_NE(error.find("rdtfd.json"), std::string::npos) << error;
  EXPECT_FALSE(load_text(folder, R"(["settle_ms", 50])", error));
  EXPECT_NE(error.find("object"), std::string::npos) << error;
  EXPECT_FALSE(load_config(folder / "missing.json", default_config(), error));
  EXPECT_NE(error.find("missing.json"), std::string::npos) << error;
}

TEST(DaemonConfig, RelativeFoldersAreRelativeToTheConfigFile) {
  testing::TempDir top;
  fs::create_directories(top / "etc");
  const auto path = top / "etc" / "rdtfd.json";
  testing::write_file(path, R"({"watch": ["../models", "more/models"], "output": "../out"})");
  std::string error;
  auto config = load_config(path, default_config(), error);
  ASSERT_TRUE(config) << error;
  ASSERT_EQ(config->watch.size(), 2u);
  EXPECT_EQ(config->watch[0].lexically_normal(), (top / "models").lexically_normal());
  EXPECT_EQ(config->watch[1].lexically_normal(), (top / "etc" / "more" / "models").lexically_normal());
  EXPECT_EQ(config->output.lexically_normal(), (top / "out").lexically_normal());
  // check_config creates them and makes every folder absolute and canonical.
  ASSERT_TRUE(check_config(*config, error)) << error;
  EXPECT_EQ(config->watch[0], fs::canonical(top / "models"));
  EXPECT_EQ(config->watch[1], fs::canonical(top / "etc" / "more" / "models"));
  EXPECT_EQ(config->output, fs::canonical(top / "out"));
  EXPECT_TRUE(fs::is_directory(top / "etc" / "more" / "models"));
  // Which watch folders it made is kept for the log (s100java D1); none the second time.
  ASSERT_EQ(config->created_watch_folders.size(), 2u);
  EXPECT_EQ(config->created_watch_folders[1].lexically_normal(), (top / "etc" / "more" / "models").lexically_normal());
  ASSERT_TRUE(check_config(*config, error)) << error;
  EXPECT_TRUE(config->created_watch_folders.empty());
}

TEST(DaemonConfig, CheckMakesCommandLineFoldersAbsolute) {
  // --watch models on the command line: relative to the working directory.
  testing::TempDir top;
  const auto previous = fs::current_path();
  fs::current_path(top.path());
  DaemonConfig config = default_config();
  config.watch = {"models", "./nested/../other"};
  config.output = "out";
  std::string error;
  const bool ok = check_config(config, error);
  fs::current_path(previous);
  ASSERT_TRUE(ok) << error;
  EXPECT_EQ(config.watch[0], fs::canonical(top / "models"));
  EXPECT_EQ(config.watch[1], fs::canonical(top / "other"));
  EXPECT_EQ(config.output, fs::canonical(top / "out"));
  EXPECT_TRUE(config.watch[0].is_absolute());
}

// A count beyond its type wrapped (workers 4294967298 ran 2), a fraction of a millisecond was cut
// (0.5 turned republishing off) and a range error showed six digits, the same for the value and
// the bound (s80cfg D9-D11).
TEST(DaemonConfig, NumbersAreTakenWholeOrRefusedNamingTheValue) {
  testing::TempDir folder;
  std::string error;
  EXPECT_FALSE(load_text(folder, R"({"workers": 4294967298})", error));
  EXPECT_NE(error.find("\"workers\" is 4294967298, beyond what it can hold"), std::string::npos) << error;
  EXPECT_FALSE(load_text(folder, R"({"republish_period_ms": 0.5})", error));
  EXPECT_NE(error.find("\"republish_period_ms\" is 0.5: it must be a whole number of milliseconds"), std::string::npos)
      << error;
  EXPECT_FALSE(load_text(folder, R"({"settle_ms": 1e19})", error));
  EXPECT_NE(error.find("settle_ms"), std::string::npos) << error;
  const auto whole = load_text(folder, R"({"settle_ms": 60000.0})", error);
  ASSERT_TRUE(whole) << error;
  EXPECT_EQ(whole->settle, std::chrono::milliseconds(60000));
  auto config = *whole;
  config.watch = {folder / "w"};
  config.output = folder / "o";
  config.convert.limits.max_file_bytes = 1099511627777ull;  // One above its maximum, 2^40.
  EXPECT_FALSE(check_config(config, error));
  EXPECT_NE(error.find("is 1099511627777, outside its valid range [1, 1099511627776]"), std::string::npos) << error;
}

// A config refused for a value (a reload, most often) leaves no new folder behind: it created its
// watch and output folders before its values were checked (s80cfg D12).
TEST(DaemonConfig, ARefusedConfigCreatesNoFolder) {
  testing::TempDir top;
  for (const auto& change : std::vector<std::function<void(DaemonConfig&)>>{
           [](DaemonConfig& c) { c.settle = std::chrono::milliseconds(0); },
           [](DaemonConfig& c) { c.channel_prefix = "lab+1"; }}) {
    DaemonConfig config = default_config();
    config.watch = {top / "new_watch"};
    config.output = top / "new_output";
    change(config);
    std::string error;
    EXPECT_FALSE(check_config(config, error));
    EXPECT_FALSE(std::filesystem::exists(top / "new_watch")) << error;
    EXPECT_FALSE(std::filesystem::exists(top / "new_output")) << error;
  }
}

// What LCM 1.3 refuses, and what it only warns about on stderr and then ignores (a misspelt or
// unreadable option: TTL 0, no datagram leaves the host), are all refused, naming the part.
TEST(DaemonConfig, LcmUrlsAreCheckedAsLcmReadsThem) {
  std::string error;
  // "udpm://" (with or without options) is LCM's default group and port (review s90rev R3).
  for (const char* good : {"", "udpm://239.255.76.67:7667", "udpm://239.255.76.67:7667?ttl=1", "udpm://",
                           "udpm://?ttl=1", "udpm://224.0.0.251:5353?ttl=0&recv_buf_size=2097152", "memq://",
                           "file:///tmp/x.lcmlog?mode=w"}) {
    EXPECT_TRUE(check_lcm_url(good, error)) << good << ": " << error;
  }
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"udpm://239.255.76.67:7667?tll=1", "option \"tll=1\" is not one LCM's udpm provider reads (ttl, recv_buf_size)"},
      {"udpm://239.255.76.67:7667?ttl=one", "option \"ttl=one\": ttl is a decimal whole number from 0 to 255"},
      {"udpm://239.255.76.67:7667?ttl=256", "option \"ttl=256\": ttl is a decimal whole number from 0 to 255"},
      {"udpm://239.255.76.67:7667?ttl=01", "ttl is a decimal whole number"},  // LCM: octal.
      {"udpm://239.255.76.67:7667?recv_buf_size=2M", "recv_buf_size is a decimal byte count"},
      {"udpm://10.0.0.1:7667", "10.0.0.1 is not a multicast group"},
      {"udpm://robots.local:7667", "\"robots.local\" is not an IPv4 address"},
      // LCM reads a group without a port as port 0, on which no send works (s90rev R1), and ports
      // with a leading 0 as octal or hexadecimal (R2: ":07667" joined port 4023).
      {"udpm://239.255.76.67", "no port: give the group's port (udpm://239.255.76.67:7667)"},
      {"udpm://239.255.76.67:07667", "port \"07667\" is not a decimal number from 1 to 65535"},
      {"udpm://239.255.76.67:0x1DF3", "port \"0x1DF3\" is not a decimal number from 1 to 65535"},
      {"udpm://239.255.76.67:99999", "port \"99999\" is not a decimal number from 1 to 65535"},
      {"udpm://239.255.76.67:", "port \"\" is not a decimal number from 1 to 65535"},
      {"239.255.76.67:7667", "is not an LCM URL"},
      {"udp://239.255.76.67:7667", "LCM has no provider \"udp\""},
  };
  for (const auto& [url, message] : bad) {
    error.clear();
    EXPECT_FALSE(check_lcm_url(url, error)) << url;
    EXPECT_NE(error.find(message), std::string::npos) << url << ": " << error;
    EXPECT_NE(error.find("lcm_url"), std::string::npos) << error;
  }
  // Named as the user set it.
  EXPECT_FALSE(check_lcm_url("udpm://239.255.76.67:7667?tll=1", error, "LCM_DEFAULT_URL"));
  EXPECT_EQ(error.rfind("LCM_DEFAULT_URL \"udpm://", 0), 0u) << error;
}

TEST(DaemonConfig, CheckRefusesSettingsThatCannotWork) {
  testing::TempDir top;
  auto good = [&] {
    DaemonConfig config = default_config();
    config.watch = {top / "w"};
    config.output = top / "o";
    return config;
  };
  std::string error;
  {
    auto config = good();
    EXPECT_TRUE(check_config(config, error)) << error;
  }
  {
    auto config = good();
    config.watch.clear();
    EXPECT_FALSE(check_config(config, error));
    EXPECT_NE(error.find("watch"), std::string::npos) << error;
  }
  {
    testing::write_file(top / "file", "x");
    auto config = good();
    config.watch = {top / "file"};
    EXPECT_FALSE(check_config(config, error));
    EXPECT_NE(error.find("not a directory"), std::string::npos) << error;
  }
  const std::pair<const char*, std::function<void(DaemonConfig&)>> bad[] = {
      {"settle 0", [](DaemonConfig& c) { c.settle = 0ms; }},
      {"status 0", [](DaemonConfig& c) { c.status_period = 0ms; }},
      {"workers 0", [](DaemonConfig& c) { c.workers = 0; }},
      {"chunk 100", [](DaemonConfig& c) { c.max_chunk_bytes = 100; }},
      {"chunk 70000", [](DaemonConfig& c) { c.max_chunk_bytes = 70000; }},
      {"rate 0", [](DaemonConfig& c) { c.chunk_rate_bytes_per_s = 0; }},
      {"prefix empty", [](DaemonConfig& c) { c.channel_prefix = ""; }},
      {"prefix 17", [](DaemonConfig& c) { c.channel_prefix = std::string(17, 'P'); }},
      // Regular-expression characters and '/' (s80cfg D5): rdtfd then heard no REQUEST.
      {"prefix lab+1", [](DaemonConfig& c) { c.channel_prefix = "lab+1"; }},
      {"prefix robot(1)", [](DaemonConfig& c) { c.channel_prefix = "robot(1)"; }},
      {"prefix R[1]", [](DaemonConfig& c) { c.channel_prefix = "R[1]"; }},
      {"prefix a/b", [](DaemonConfig& c) { c.channel_prefix = "a/b"; }},
      {"prefix a b", [](DaemonConfig& c) { c.channel_prefix = "a b"; }},
  };
  for (const auto& [what, change] : bad) {
    auto config = good();
    change(config);
    EXPECT_FALSE(check_config(config, error)) << what;
  }
  {
    auto config = good();
    config.channel_prefix = "lab-1.robot_A";
    EXPECT_TRUE(check_config(config, error)) << error;
    config.channel_prefix = "lab+1";
    EXPECT_FALSE(check_config(config, error));
    EXPECT_NE(error.find("channel_prefix \"lab+1\" holds \"+\""), std::string::npos) << error;
  }
  {
    auto config = good();
    config.republish_period = 0ms;  // 0 disables republishing: allowed.
    EXPECT_TRUE(check_config(config, error)) << error;
  }
}

TEST(DaemonConfig, OutputContainingAWatchedFolderIsRefused) {
  // Events inside the output folder are ignored: with --output equal to (or above) a watched
  // folder, every model there would be ignored and the daemon would silently do nothing.
  testing::TempDir top;
  std::string error;
  {
    DaemonConfig config = default_config();
    config.watch = {top / "models"};
    config.output = top / "models";
    EXPECT_FALSE(check_config(config, error)) << "output == watch accepted";
  }
  {
    DaemonConfig config = default_config();
    config.watch = {top / "all" / "models"};
    config.output = top / "all";
    EXPECT_FALSE(check_config(config, error)) << "output above watch accepted";
  }
  {
    // The supported case: the output inside a watched folder.
    DaemonConfig config = default_config();
    config.watch = {top / "models"};
    config.output = top / "models" / "out";
    EXPECT_TRUE(check_config(config, error)) << error;
  }
}

TEST(DaemonConfig, DefaultsFollowXdgFolders) {
  const char* data = std::getenv("XDG_DATA_HOME");
  const char* state = std::getenv("XDG_STATE_HOME");
  const std::string saved_data = data ? data : "";
  const std::string saved_state = state ? state : "";
  ::setenv("XDG_DATA_HOME", "/xdg/data", 1);
  ::setenv("XDG_STATE_HOME", "/xdg/state", 1);
  const DaemonConfig config = default_config();
  data ? ::setenv("XDG_DATA_HOME", saved_data.c_str(), 1) : ::unsetenv("XDG_DATA_HOME");
  state ? ::setenv("XDG_STATE_HOME", saved_state.c_str(), 1) : ::unsetenv("XDG_STATE_HOME");
  EXPECT_EQ(config.watch, std::vector<fs::path>{"/xdg/data/rdtf/models"});
  EXPECT_EQ(config.output, fs::path("/xdg/state/rdtf/output"));
  EXPECT_EQ(config.settle, 50ms);
  EXPECT_EQ(config.republish_period, 5000ms);
  EXPECT_EQ(config.lcm_url, "");
  EXPECT_EQ(config.channel_prefix, "RDTF");
}

// Without a usable HOME (unset under some service managers, empty, or relative) the defaults come
// from the user's entry in the password database: they were /tmp/.local/..., which any local user
// can create first and fill with models, or relative to the working folder. An empty output folder
// (no home at all) is refused by name.
TEST(DaemonConfig, DefaultsWithoutHomeUseThePasswordDatabase) {
  std::map<std::string, std::optional<std::string>> saved;
  for (const char* name : {"HOME", "XDG_DATA_HOME", "XDG_STATE_HOME"}) {
    const char* value = std::getenv(name);
    saved[name] = value ? std::optional<std::string>(value) : std::nullopt;
  }
  const passwd* user = getpwuid(geteuid());
  ASSERT_TRUE(user != nullptr && user->pw_dir != nullptr && user->pw_dir[0] == '/');
  const fs::path home = user->pw_dir;
  ::unsetenv("XDG_DATA_HOME");
  ::unsetenv("XDG_STATE_HOME");
  std::vector<DaemonConfig> configs;
  for (const char* value : {static_cast<const char*>(nullptr), "", "relative/home"}) {
    value ? ::setenv("HOME", value, 1) : ::unsetenv("HOME");
    configs.push_back(default_config());
  }
  for (const auto& [name, value] : saved) value ? ::setenv(name.c_str(), value->c_str(), 1) : ::unsetenv(name.c_str());
  for (const DaemonConfig& config : configs) {
    EXPECT_EQ(config.watch, std::vector<fs::path>{home / ".local/share/rdtf/models"});
    EXPECT_EQ(config.output, home / ".local/state/rdtf/output");
  }
  DaemonConfig no_output = configs[0];
  no_output.output.clear();
  std::string error;
  EXPECT_FALSE(check_config(no_output, error));
  EXPECT_EQ(error.rfind("no output folder: give --output DIR", 0), 0u) << error;
}

// The shipped file is the reference a user copies: it names every key, and apart from the folders
// it sets for scripts/run.sh, each with the built-in default.
TEST(DaemonConfig, RepositoryConfigFileListsEveryKeyWithItsDefault) {
  const fs::path file = testing::data_dir() / ".." / ".." / "config" / "rdtfd.json";
  const nlohmann::json json = nlohmann::json::parse(testing::read_file(file));
  for (const std::string& key : config_keys()) EXPECT_TRUE(json.contains(key)) << key << " missing from " << file;
  for (const auto& [key, value] : json.items()) {
    EXPECT_TRUE(key == "_comment" || std::find(config_keys().begin(), config_keys().end(), key) != config_keys().end())
        << key;
  }
  std::string error;
  const auto loaded = load_config(file, default_config(), error);
  ASSERT_TRUE(loaded) << error;
  DaemonConfig expected = default_config();
  expected.watch = loaded->watch;
  expected.output = loaded->output;
  // Every setting but the folders, compared through the config object the file gives back: the
  // registry reads each key of both configs.
  for (const ConfigKey& key : config_registry()) {
    EXPECT_EQ(key.get(*loaded), key.get(expected)) << key.name << " in " << file << " is not its default";
  }
}

TEST(DaemonConfig, DynamicsKeysReachTheGateAndTheLiveSimulation) {
  testing::TempDir folder;
  std::string error;
  auto config = load_text(folder, R"({
    "time_step": 0.002, "stepper": "quick_step", "max_mass_ratio": 50, "validation_start_offset_rad": 0.25,
    "energy_tolerance": 0.05, "joint_separation_tolerance_m": 0.002, "limit_tolerance_rad": 0.03,
    "limit_tolerance_m": 0.004, "validation_seconds": 1.5, "floating_root": true, "gravity": [0, 0, -9.81]})",
                          error);
  ASSERT_TRUE(config) << error;
  const ValidationOptions v = validation_options(*config);
  EXPECT_EQ(v.simulation.time_step, 0.002);
  EXPECT_EQ(v.simulation.stepper, Stepper::kQuickStep);
  EXPECT_TRUE(v.simulation.floating_root);
  EXPECT_EQ(v.simulation.gravity, Eigen::Vector3d(0, 0, -9.81));
  EXPECT_EQ(v.checks.max_mass_ratio, 50);
  EXPECT_EQ(v.start_offset_angular, 0.25);
  EXPECT_EQ(v.energy_tolerance, 0.05);
  EXPECT_EQ(v.joint_separation_tolerance, 0.002);
  EXPECT_EQ(v.limit_tolerance_angular, 0.03);
  EXPECT_EQ(v.limit_tolerance_linear, 0.004);
  EXPECT_EQ(v.duration, 1.5);
  const SimulationOptions live = simulation_options(*config);
  EXPECT_EQ(live.time_step, 0.002);
  EXPECT_EQ(live.stepper, Stepper::kQuickStep);
  EXPECT_TRUE(live.floating_root);
  // Defaults are the core library's.
  EXPECT_EQ(validation_options(default_config()).checks.max_mass_ratio, ValidationOptions{}.checks.max_mass_ratio);
  EXPECT_EQ(validation_options(default_config()).start_offset_angular, ValidationOptions{}.start_offset_angular);
  EXPECT_EQ(validation_options(default_config()).energy_tolerance, ValidationOptions{}.energy_tolerance);
  EXPECT_EQ(simulation_options(default_config()).stepper, SimulationOptions{}.stepper);
}

TEST(DaemonConfig, BadDynamicsSettingsAreRefused) {
  testing::TempDir folder;
  std::string error;
  EXPECT_FALSE(load_text(folder, R"({"stepper": "fast"})", error));
  EXPECT_NE(error.find("\"stepper\" must be \"auto\", \"world_step\" or \"quick_step\", not \"fast\""),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("rdtfd.json"), std::string::npos) << error;
  const std::pair<const char*, const char*> bad_values[] = {
      {R"({"time_step": 0})", "time_step"}, {R"({"time_step": 0.5})", "time_step"},
      {R"({"max_mass_ratio": 0.5})", "max_mass_ratio"}, {R"({"energy_tolerance": 0})", "energy_tolerance"},
      {R"({"limit_tolerance_m": -1})", "limit_tolerance_m"}};
  for (const auto& [bad, key] : bad_values) {
    auto config = load_text(folder, bad, error);
    ASSERT_TRUE(config) << bad << ": " << error;
    config->watch = {folder.path()};
    config->output = folder / "out";
    EXPECT_FALSE(check_config(*config, error)) << bad;
    EXPECT_NE(error.find(std::string("\"") + key + "\" is "), std::string::npos) << error;
    EXPECT_NE(error.find("outside its valid range"), std::string::npos) << error;
  }
}

// What `rdtfd --set KEY=VALUE` applies: the file's keys, folders relative to the given base.
TEST(DaemonConfig, ApplyingAnObjectOverridesOnlyItsKeys) {
  std::string error;
  const auto config = apply_config_json(nlohmann::json{{"output", "out"}, {"max_mass_ratio", 20}}, "/base",
                                        default_config(), error);
  ASSERT_TRUE(config) << error;
  EXPECT_EQ(config->output, fs::path("/base/out"));
  EXPECT_EQ(config->max_mass_ratio, 20);
  EXPECT_EQ(config->watch, default_config().watch);
  EXPECT_FALSE(apply_config_json(nlohmann::json{{"max_mass_ration", 20}}, "/base", default_config(), error));
  EXPECT_EQ(error, "unknown key \"max_mass_ration\"");
}

}  // namespace
}  // namespace rdtf::daemon

namespace rdtf::daemon {
namespace {

TEST(DaemonConfigRanges, EveryNumericKeyOutsideItsRangeIsRefusedNamingKeyAndRange) {
  testing::TempDir top;
  ASSERT_FALSE(config_ranges().empty());
  for (const KeyRange& range : config_ranges()) {
    SCOPED_TRACE(range.key);
    EXPECT_NE(std::find(config_keys().begin(), config_keys().end(), range.key), config_keys().end());
    const double above = range.max * 2 + 1;
    const bool whole = std::string(range.key).find("bytes") != std::string::npos ||
                       std::string(range.key).find("_ms") != std::string::npos ||
                       std::string(range.key) == "workers" || std::string(range.key).find("max_") == 0;
    nlohmann::json json;
    if (std::string(range.key) == "gravity") {
      json["gravity"] = {above, 0, 0};
    } else if (whole) {
      json[range.key] = static_cast<std::uint64_t>(above);
    } else {
      json[range.key] = above;
    }
    std::string error;
    auto config = apply_config_json(json, top.path(), default_config(), error);
    ASSERT_TRUE(config) << error;
    config->watch = {top / "w"};
    config->output = top / "o";
    EXPECT_FALSE(check_config(*config, error)) << json.dump();
    EXPECT_NE(error.find(std::string("\"") + range.key + "\""), std::string::npos) << error;
  }
}

TEST(DaemonConfigRanges, ATimeStepThatWouldWedgeTheDaemonIsRefused) {
  testing::TempDir top;
  DaemonConfig config = default_config();
  config.watch = {top / "w"};
  config.output = top / "o";
  config.time_step = 1e-7;
  std::string error;
  EXPECT_FALSE(check_config(config, error));
  EXPECT_NE(error.find("\"time_step\" is 1e-07, outside its valid range [0.0001, 0.1]"), std::string::npos) << error;
  config.time_step = 1e-4;
  EXPECT_TRUE(check_config(config, error)) << error;
}

TEST(DaemonConfigRanges, ReadBytesPerModelMayNotExceedTheBytesInFlight) {
  testing::TempDir top;
  DaemonConfig config = default_config();
  config.watch = {top / "w"};
  config.output = top / "o";
  config.max_read_bytes = 3000;
  config.max_read_bytes_in_flight = 2000;
  std::string error;
  EXPECT_FALSE(check_config(config, error));
  EXPECT_NE(error.find("max_read_bytes_in_flight"), std::string::npos) << error;
}

TEST(DaemonConfigFile, OnlyARegularFileOfBoundedSizeIsRead) {
  testing::TempDir top;
  std::string error;
  fs::create_directory(top / "folder.json");
  EXPECT_FALSE(load_config(top / "folder.json", default_config(), error));
  EXPECT_NE(error.find("a directory"), std::string::npos) << error;
  ASSERT_EQ(::mkfifo((top / "fifo.json").c_str(), 0644), 0);
  // Opened without blocking, so this returns although no one ever writes the FIFO.
  EXPECT_FALSE(load_config(top / "fifo.json", default_config(), error));
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  testing::write_file(top / "big.json", "{\"_comment\": \"" + std::string(kMaxConfigFileBytes, 'x') + "\"}");
  EXPECT_FALSE(load_config(top / "big.json", default_config(), error));
  EXPECT_NE(error.find("over the limit"), std::string::npos) << error;
}

}  // namespace
}  // namespace rdtf::daemon

namespace rdtf::daemon {
namespace {

// The commands' lifetime (docs/controller.md, "Command lifetime"): 0.5 s by default, read from
// the file, and kept within 0.01 .. 60 s (a controller's death is noticed, and a lifetime of 0
// would release every command before its first step).
TEST(DaemonConfig, JointCommandTimeoutIsReadAndKeptInItsRange) {
  EXPECT_EQ(default_config().joint_command_timeout_s, 0.5);
  testing::TempDir folder;
  std::string error;
  auto config = load_text(folder, R"({"joint_command_timeout_s": 2.5})", error);
  ASSERT_TRUE(config) << error;
  EXPECT_EQ(config->joint_command_timeout_s, 2.5);
  for (const double refused : {0.0, 0.005, 61.0}) {
    SCOPED_TRACE(refused);
    config->joint_command_timeout_s = refused;
    config->watch = {folder / "w"};
    config->output = folder / "o";
    EXPECT_FALSE(check_config(*config, error));
    EXPECT_NE(error.find("\"joint_command_timeout_s\""), std::string::npos) << error;
    EXPECT_NE(error.find("[0.01, 60]"), std::string::npos) << error;
  }
  config->joint_command_timeout_s = 60;
  EXPECT_TRUE(check_config(*config, error)) << error;
}

}  // namespace
}  // namespace rdtf::daemon
