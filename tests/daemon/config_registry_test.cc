// The settings registry (daemon/config_keys.cc): every key reads, writes, range-checks and compares
// through its row, the reload effects are the daemon's documented ones, and docs/daemon.md's
// settings table is the one the registry generates.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <set>

#include "config.h"
#include "support/test_support.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

DaemonConfig good_config(const testing::TempDir& top) {
  DaemonConfig config = default_config();
  config.watch = {top / "w"};
  config.output = top / "o";
  return config;
}

// A valid value of `key` other than its default.
json other_value(const ConfigKey& key, const DaemonConfig& defaults) {
  const json current = key.get(defaults);
  switch (key.kind) {
    case ValueKind::kBoolean:
      return !current.get<bool>();
    case ValueKind::kString:
      return "X" + current.get<std::string>().substr(0, 8);
    case ValueKind::kFolder:
      return "/elsewhere/out";
    case ValueKind::kFolders:
      return json::array({"/elsewhere/models"});
    case ValueKind::kName:
      return key.name == "stepper" ? json("quick_step") : json("error");
    case ValueKind::kVector3:
      return json::array({0, 0, -9.80665});
    case ValueKind::kInteger:
    case ValueKind::kNumber:
      break;
  }
  const double value = current.get<double>() == *key.max ? *key.min : *key.max;
  return key.kind == ValueKind::kInteger ? json(static_cast<std::uint64_t>(value)) : json(value);
}

TEST(DaemonConfigRegistry, EveryKeyIsReadWrittenAndComparedThroughItsRow) {
  const DaemonConfig defaults = default_config();
  std::set<std::string> names;
  for (const ConfigKey& key : config_registry()) {
    SCOPED_TRACE(key.name);
    EXPECT_TRUE(names.insert(key.name).second) << "listed twice";
    EXPECT_FALSE(key.doc.empty());
    EXPECT_EQ(find_config_key(key.name), &key);
    // The default reads back as itself; another value changes exactly this key.
    std::string error;
    const auto same = apply_config_json(json{{key.name, key.get(defaults)}}, "/", defaults, error);
    ASSERT_TRUE(same) << error;
    EXPECT_TRUE(compare_configs(defaults, *same).keys.empty());
    const json value = other_value(key, defaults);
    const auto changed = apply_config_json(json{{key.name, value}}, "/", defaults, error);
    ASSERT_TRUE(changed) << value.dump() << ": " << error;
    EXPECT_EQ(key.get(*changed), value);
    const ConfigChange change = compare_configs(defaults, *changed);
    EXPECT_EQ(change.keys, std::vector<std::string>{key.name});
    EXPECT_EQ(change.effects, key.reload);
    // A value of the wrong JSON type is refused, naming the key.
    EXPECT_FALSE(apply_config_json(json{{key.name, json::object()}}, "/", defaults, error));
    EXPECT_EQ(error, "\"" + key.name + "\" has the wrong type (object)");
  }
}

TEST(DaemonConfigRegistry, BothEndsOfEveryRangeAreAccepted) {
  testing::TempDir top;
  for (const ConfigKey& key : config_registry()) {
    if (!key.min) continue;
    SCOPED_TRACE(key.name);
    for (const double end : {*key.min, *key.max}) {
      DaemonConfig config = good_config(top);
      // The per-model read budget may not exceed the one in flight: keep the other side out of the way.
      if (key.name == "max_read_bytes") config.max_read_bytes_in_flight = 4 * 1099511627776ull;
      if (key.name == "max_read_bytes_in_flight") config.max_read_bytes = 1;
      json value = key.kind == ValueKind::kInteger ? json(static_cast<std::uint64_t>(end)) : json(end);
      if (key.kind == ValueKind::kVector3) value = json::array({end, end, end});
      std::string error;
      auto applied = apply_config_json(json{{key.name, value}}, "/", config, error);
      ASSERT_TRUE(applied) << error;
      EXPECT_TRUE(check_config(*applied, error)) << value.dump() << ": " << error;
    }
  }
}

// The daemon's reload behaviour as docs/daemon.md describes it: which keys convert every model
// again, which restart the live simulations, which reopen LCM, which wait for a restart.
TEST(DaemonConfigRegistry, ReloadEffectsAreTheDocumentedOnes) {
  const auto keys_with = [](ReloadEffect effect) {
    std::set<std::string> out;
    for (const ConfigKey& key : config_registry()) {
      if ((key.reload & effect) != 0) out.insert(key.name);
    }
    return out;
  };
  EXPECT_EQ(keys_with(kReconvert),
            (std::set<std::string>{"output", "default_density", "max_file_bytes", "max_buffer_bytes",
                                   "max_accessor_count", "max_triangles", "max_read_bytes", "validate",
                                   "validation_seconds", "publish_failed", "time_step", "stepper", "max_mass_ratio",
                                   "validation_start_offset_rad", "energy_tolerance", "joint_separation_tolerance_m",
                                   "limit_tolerance_rad", "limit_tolerance_m", "bound_mass_kg", "bound_inertia_kgm2",
                                   "massless_link_severity", "validation_cpu_budget_s", "floating_root", "gravity",
                                   "urdf", "urdf_y_up"}));
  EXPECT_EQ(keys_with(kRestartSimulation),
            (std::set<std::string>{"simulate", "state_rate_hz", "real_time_factor", "floating_root", "gravity",
                                   "time_step", "stepper", "lcm_url", "channel_prefix", "bound_mass_kg",
                                   "bound_inertia_kgm2", "joint_command_timeout_s"}));
  EXPECT_EQ(keys_with(kReconnect), (std::set<std::string>{"lcm_url", "channel_prefix"}));
  EXPECT_EQ(keys_with(kFoldersChanged), (std::set<std::string>{"watch", "output"}));
  EXPECT_EQ(keys_with(kNeedsRestart), (std::set<std::string>{"workers", "max_cached_results"}));
}

TEST(DaemonConfigRegistry, AReloadKeepsTheRunningValueOfARestartKey) {
  DaemonConfig running = default_config();
  DaemonConfig fresh = running;
  fresh.workers = running.workers + 3;
  fresh.settle = running.settle * 2;
  const ConfigChange change = compare_configs(running, fresh);
  EXPECT_EQ(change.keys, (std::vector<std::string>{"settle_ms", "workers"}));
  EXPECT_TRUE(change.has(kNeedsRestart));
  EXPECT_FALSE(change.has(kReconvert));
  keep_restart_settings(running, fresh);
  EXPECT_EQ(fresh.workers, running.workers);
  EXPECT_EQ(fresh.settle, running.settle * 2);
}

TEST(DaemonConfigRegistry, CommandLineTextIsReadByTheKeysKind) {
  // A prefix or a folder named like a number stays text; numbers, booleans and lists are JSON.
  EXPECT_EQ(value_from_text(*find_config_key("channel_prefix"), {"123"}), json("123"));
  EXPECT_EQ(value_from_text(*find_config_key("output"), {"true"}), json("true"));
  EXPECT_EQ(value_from_text(*find_config_key("lcm_url"), {"udpm://239.255.76.67:7668?ttl=0"}),
            json("udpm://239.255.76.67:7668?ttl=0"));
  EXPECT_EQ(value_from_text(*find_config_key("settle_ms"), {"120"}), json(120));
  EXPECT_EQ(value_from_text(*find_config_key("settle_ms"), {"fast"}), json("fast"));  // Refused by the type check.
  EXPECT_EQ(value_from_text(*find_config_key("validate"), {"false"}), json(false));
  EXPECT_EQ(value_from_text(*find_config_key("gravity"), {"0", "0", "-9.81"}), json::array({0, 0, -9.81}));
  EXPECT_EQ(value_from_text(*find_config_key("gravity"), {"[0,0,-9.81]"}), json::array({0, 0, -9.81}));
  EXPECT_EQ(value_from_text(*find_config_key("watch"), {"a", "b"}), json::array({"a", "b"}));
  EXPECT_EQ(value_from_text(*find_config_key("watch"), {"models"}), json::array({"models"}));
  EXPECT_EQ(value_from_text(*find_config_key("watch"), {R"(["a","b"])"}), json::array({"a", "b"}));
  std::string error;
  const auto config = apply_config_json(json{{"channel_prefix", value_from_text(*find_config_key("channel_prefix"), {"123"})}},
                                        "/", default_config(), error);
  ASSERT_TRUE(config) << error;
  EXPECT_EQ(config->channel_prefix, "123");
}

// docs/daemon.md's settings table is generated: `RDTF_UPDATE_DOCS=1` rewrites it from the registry.
TEST(DaemonConfigRegistry, DocsTableIsGeneratedFromTheRegistry) {
  const fs::path doc = testing::data_dir() / ".." / ".." / "docs" / "daemon.md";
  const std::string begin = "<!-- settings table: generated from daemon/config_keys.cc -->\n";
  const std::string end = "<!-- end of settings table -->";
  std::string text = testing::read_file(doc);
  const auto from = text.find(begin);
  const auto to = text.find(end);
  ASSERT_NE(from, std::string::npos) << doc << " lacks " << begin;
  ASSERT_NE(to, std::string::npos) << doc << " lacks " << end;
  ASSERT_LT(from, to);
  const std::string table = settings_table_markdown();
  const std::string current = text.substr(from + begin.size(), to - from - begin.size());
  if (current != table && std::getenv("RDTF_UPDATE_DOCS") != nullptr) {
    text.replace(from + begin.size(), current.size(), table);
    const fs::path temporary = doc.string() + ".tmp";
    testing::write_file(temporary, text);
    fs::rename(temporary, doc);
    return;
  }
  EXPECT_EQ(current, table) << "docs/daemon.md's settings table differs from the registry; regenerate it with "
                               "RDTF_UPDATE_DOCS=1 build/tests/rdtf_tests --gtest_filter='DaemonConfigRegistry.*'";
  for (const ConfigKey& key : config_registry()) {
    EXPECT_NE(current.find("| `" + key.name + "` |"), std::string::npos) << key.name;
  }
}

}  // namespace
}  // namespace rdtf::daemon
