// The life of rdtfd: stopping on SIGTERM/SIGINT, reloading its config on SIGHUP, surviving bad
// models, and its default settings (dynamics validation on). See harness.h for how these run.
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <regex>
#include <set>

#include <rdtf/joint_state_t.hpp>

#include "daemon/harness.h"

namespace rdtf::itest {
namespace {

// Every output is whole: each *.rdtf.gltf parses, and no temporary file is left.
void expect_outputs_whole(const fs::path& output) {
  for (const auto& entry : fs::recursive_directory_iterator(output)) {
    if (!entry.is_regular_file()) continue;
    const std::string name = entry.path().filename().string();
    EXPECT_FALSE(name.size() > 4 && name.substr(name.size() - 4) == ".tmp") << "left behind: " << entry.path();
    EXPECT_NE(name.front(), '.') << "left behind: " << entry.path();
    if (name.size() > 10 && name.substr(name.size() - 10) == ".rdtf.gltf") {
      Json document;
      EXPECT_NO_THROW(document = Json::parse(read(entry.path()))) << entry.path();
      EXPECT_TRUE(document.contains("extras")) << entry.path();
    }
  }
}

TEST(DaemonLife, SigtermExitsZero) {
  Session s;
  const auto a = box_model("a_base", 0.05);
  write_model(s.watch, "a.gltf", a);
  auto& daemon = s.start();
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_idle());
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait_exit(3s), std::optional<int>(0)) << daemon.log();
  EXPECT_NE(daemon.log().find("received Terminated: stopping"), std::string::npos) << daemon.log();
  EXPECT_NE(daemon.log().find("rdtfd stopped"), std::string::npos) << daemon.log();
  expect_outputs_whole(s.output);
}

// systemd's readiness protocol: with $NOTIFY_SOCKET, rdtfd sends READY=1 once it reads its
// signals (the unit is Type=notify), and a SIGHUP from then on reloads. Before it was ready, a
// SIGHUP in its first milliseconds killed it, and systemd counted that as a clean exit (s80cfg D6).
TEST(DaemonLife, TellsSystemdItIsReadyAndASighupRightThenReloads) {
  Session s;
  const fs::path socket_path = s.output.parent_path() / "notify.sock";
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  ASSERT_LT(socket_path.string().size(), sizeof(address.sun_path));
  std::memcpy(address.sun_path, socket_path.c_str(), socket_path.string().size());
  ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0) << std::strerror(errno);
  auto& daemon = s.start(DaemonOptions().with_env("NOTIFY_SOCKET=" + socket_path.string()));
  pollfd ready{fd, POLLIN, 0};
  ASSERT_EQ(::poll(&ready, 1, 10000), 1) << "no READY=1 in 10 s:\n" << daemon.log();
  char text[64] = {};
  ASSERT_GT(::recv(fd, text, sizeof(text) - 1, 0), 0);
  EXPECT_STREQ(text, "READY=1");
  ::close(fd);
  daemon.signal(SIGHUP);  // At once, as `systemctl reload` right after `start`.
  ASSERT_TRUE(daemon.wait_log("config reloaded")) << daemon.log();
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait_exit(3s), std::optional<int>(0)) << daemon.log();
}

TEST(DaemonLife, SigintExitsZero) {
  Session s;
  auto& daemon = s.start();
  daemon.signal(SIGINT);
  EXPECT_EQ(daemon.wait_exit(3s), std::optional<int>(0)) << daemon.log();
  EXPECT_NE(daemon.log().find("rdtfd stopped"), std::string::npos) << daemon.log();
}

TEST(DaemonLife, SigtermDuringConversionsExitsZeroAndLeavesNothingHalfDone) {
  Session s;
  for (int i = 0; i < 12; ++i) {
    write_model(s.watch, "m" + std::to_string(i) + ".gltf", many_parts_model("m_base", 1500, 0.01));
  }
  auto& daemon = s.start(DaemonOptions().with_settle(10));
  // Stop as soon as the first model is out: the others are queued or converting.
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "DESCRIPTION").empty(); }, 10s));
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait_exit(5s), std::optional<int>(0)) << daemon.log();
  EXPECT_NE(daemon.log().find("rdtfd stopped"), std::string::npos) << daemon.log();
  expect_outputs_whole(s.output);
  // Every model announced was written whole before the exit.
  for (const auto& d : decoded<rdtf::description_t>(s.messages(), "DESCRIPTION")) {
    ASSERT_TRUE(fs::exists(d.output_path)) << d.output_path;
    EXPECT_EQ(static_cast<std::int64_t>(fs::file_size(d.output_path)), d.rdtf_json_size) << d.output_path;
  }
}

TEST(DaemonLife, SighupReloadsTheConfigAndRepublishesWithNewMasses) {
  Session s;
  const auto a = box_model("a_base", 0.05);
  write_model(s.watch, "a.gltf", a);
  copy_fixture(s.watch, "arm3");
  auto& daemon = s.start(DaemonOptions().with("default_density", 1000));
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_revision("arm3.gltf", 1, fixture_hash("arm3")));
  ASSERT_TRUE(s.wait_idle());
  const auto before_a = *last_inertia(s.messages(), "a.gltf");
  const auto before_arm = *last_inertia(s.messages(), "arm3.gltf");
  expect_inertia_matches(before_a, inspect(s.watch / "a.gltf"));
  expect_inertia_matches(before_arm, inspect(s.watch / "arm3.gltf"));
  EXPECT_NEAR(before_a.total_mass, a.link_mass, 1e-6);

  daemon.write_config({{"default_density", 2500}});
  daemon.signal(SIGHUP);
  // Same files, new settings: a new revision of each, with the content hash unchanged.
  ASSERT_TRUE(s.wait_revision("a.gltf", 2, content_hash(a)));
  ASSERT_TRUE(s.wait_revision("arm3.gltf", 2, fixture_hash("arm3")));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->rescans, 2);
  EXPECT_EQ(idle->conversions, 4);
  EXPECT_NE(daemon.log().find("config reloaded"), std::string::npos) << daemon.log();
  const auto all = s.messages();
  EXPECT_EQ(model_events(all, "a.gltf"),
            concat({revision_events("a.gltf", 1, content_hash(a)), revision_events("a.gltf", 2, content_hash(a))}));
  EXPECT_EQ(model_events(all, "arm3.gltf"), concat({revision_events("arm3.gltf", 1, fixture_hash("arm3")),
                                                    revision_events("arm3.gltf", 2, fixture_hash("arm3"))}));
  const auto after_a = *last_inertia(all, "a.gltf");
  const auto after_arm = *last_inertia(all, "arm3.gltf");
  expect_inertia_matches(after_a, inspect(s.watch / "a.gltf", "--density 2500"));
  expect_inertia_matches(after_arm, inspect(s.watch / "arm3.gltf", "--density 2500"));
  EXPECT_NEAR(after_a.total_mass, 2.5 * before_a.total_mass, 1e-9 * after_a.total_mass);
  ASSERT_EQ(after_arm.links.size(), before_arm.links.size());
  for (std::size_t i = 0; i < after_arm.links.size(); ++i) {
    if (before_arm.links[i].authored) continue;  // Masses given in the file do not scale.
    EXPECT_NEAR(after_arm.links[i].mass, 2.5 * before_arm.links[i].mass, 1e-9 * after_arm.links[i].mass)
        << after_arm.links[i].name;
  }
  // The description's document carries the new masses too.
  EXPECT_NE(last_description(all, "arm3.gltf")->rdtf_json, on_kind(all, "DESCRIPTION", "arm3.gltf")[0].as<rdtf::description_t>().rdtf_json);
}

// Log lines matching `pattern` (the whole line after the timestamp).
std::vector<std::string> log_lines(const std::string& log, const std::string& pattern) {
  static const std::regex kStamp(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z (.*))");
  const std::regex wanted(pattern);
  std::vector<std::string> out;
  std::istringstream in(log);
  for (std::string line; std::getline(in, line);) {
    std::smatch match;
    if (std::regex_match(line, match, kStamp) && std::regex_match(match[1].str(), wanted)) out.push_back(match[1].str());
  }
  return out;
}

TEST(DaemonLife, LogsOneLinePerEventWithTimings) {
  Session s;
  const auto a = box_model("a_base", 0.05);
  const auto b = box_model("b_base", 0.05);
  write_model(s.watch, "a.gltf", a);
  const auto b_path = write_model(s.watch, "b.gltf", b);
  auto& daemon = s.start(DaemonOptions().with_republish(300));
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_revision("b.gltf", 1, content_hash(b)));
  const std::string ms = R"([0-9]+\.[0-9] ms)";
  const std::string stages = "; stages: read " + ms + ", convert " + ms + ", check " + ms + ", write " + ms +
                             ", cache " + ms + ", picked up " + ms + ", state saved " + ms + ", sent " + ms;
  for (const char* id : {"a", "b"}) {
    // The line is written after the description is sent (its last stage is the sending), so a
    // subscriber can hold the revision a moment before the log has the line: wait for it.
    // Converted while the model settled (the default, convert_while_settling) or after it.
    const std::string line =
        std::string("converted ") + id + R"(\.gltf revision 1 \(1 links, 0 joints\) in )" + ms + "( while settling)?" + stages;
    EXPECT_TRUE(wait_until([&] { return !log_lines(daemon.log(), line).empty(); }, 5s)) << daemon.log();
    EXPECT_EQ(log_lines(daemon.log(), line).size(), 1u) << daemon.log();
  }
  // Periodic republication: one line per period for both models, never one per model.
  const std::string periodic = R"(republished 2 models \(every 300 ms\), queued in )" + ms;
  ASSERT_TRUE(wait_until([&] { return log_lines(daemon.log(), periodic).size() >= 3; }, 5s)) << daemon.log();
  // The description of each model came again with every period that was logged.
  const auto periods = log_lines(daemon.log(), periodic).size();
  EXPECT_GE(on_kind(s.messages(), "DESCRIPTION", "a.gltf").size(), periods);
  EXPECT_TRUE(log_lines(daemon.log(), R"(republished (a|b)\.gltf.*)").empty()) << daemon.log();

  s.request("a.gltf", "log test");
  EXPECT_TRUE(wait_until([&] {
    return log_lines(daemon.log(), R"(republished a\.gltf on request of 'log test', queued in )" + ms).size() == 1;
  }, 5s)) << daemon.log();
  s.request("", "log test");
  EXPECT_TRUE(wait_until([&] {
    return log_lines(daemon.log(), R"(republished every model on request of 'log test' \(2 models\), queued in )" + ms).size() == 1;
  }, 5s)) << daemon.log();

  fs::remove(b_path);
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "REMOVED", "b.gltf").empty(); }));
  EXPECT_TRUE(wait_until([&] {
    return log_lines(daemon.log(), R"(removed b\.gltf in )" + ms + R"( \(revision 1 was live\))").size() == 1;
  }, 5s)) << daemon.log();
  // Now one model is left, and the periodic line says so.
  EXPECT_TRUE(wait_until([&] {
    return !log_lines(daemon.log(), R"(republished 1 models \(every 300 ms\), queued in )" + ms).empty();
  }, 5s)) << daemon.log();
}

// Joint states of `id` with revision `revision`.
std::vector<rdtf::joint_state_t> states_of(const std::vector<Message>& all, const std::string& id, std::int64_t revision) {
  std::vector<rdtf::joint_state_t> out;
  for (const auto& st : decoded<rdtf::joint_state_t>(all, "JOINT_STATE", id)) {
    if (st.revision == revision) out.push_back(st);
  }
  return out;
}

// model_events without the live simulation's stream.
std::vector<std::string> events_but_states(const std::vector<Message>& all, const std::string& id) {
  std::vector<std::string> out;
  for (auto& e : model_events(all, id)) {
    if (e != id + " JOINT_STATE" && e != id + " LINK_STATE") out.push_back(e);
  }
  return out;
}

TEST(DaemonLife, SighupThatChangesNoConversionSettingKeepsRevisionsAndSimulations) {
  Session s;
  const auto a = box_model("a_base", 0.05, 2);
  write_model(s.watch, "a.gltf", a);
  auto& daemon = s.start(DaemonOptions().with("simulate", true).with("state_rate_hz", 100));
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return states_of(all, "a.gltf", 1).size() >= 10; }));
  ASSERT_TRUE(s.wait_idle());

  auto reload = [&](const Json& config, int reloads) {
    daemon.write_config(config);
    daemon.signal(SIGHUP);
    return wait_until([&] { return log_lines(daemon.log(), "rescan \\(config reloaded\\).*").size() ==
                                   static_cast<std::size_t>(reloads); }, 5s);
  };
  // Nothing changed, then only settings no conversion depends on.
  ASSERT_TRUE(reload({{"simulate", true}, {"state_rate_hz", 100}}, 1)) << daemon.log();
  ASSERT_TRUE(s.wait_idle());
  const double before = states_of(s.messages(), "a.gltf", 1).back().sim_time;
  ASSERT_TRUE(reload({{"simulate", true}, {"state_rate_hz", 100}, {"max_open_wait_ms", 4000},
                      {"chunk_rate_bytes_per_s", 16000000}}, 2)) << daemon.log();
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 1);
  EXPECT_EQ(idle->rescans, 3);
  // The simulation ran on: simulated time did not start again from zero.
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return states_of(all, "a.gltf", 1).back().sim_time > before + 0.2; }));
  double previous = 0;
  for (const auto& st : states_of(s.messages(), "a.gltf", 1)) {
    EXPECT_GE(st.sim_time, previous) << "the simulation was started again";
    previous = st.sim_time;
  }
  EXPECT_EQ(events_but_states(s.messages(), "a.gltf"), revision_events("a.gltf", 1, content_hash(a)));

  // A setting the result depends on: a new revision.
  ASSERT_TRUE(reload({{"simulate", true}, {"state_rate_hz", 100}, {"default_density", 2000}}, 3)) << daemon.log();
  ASSERT_TRUE(s.wait_revision("a.gltf", 2, content_hash(a)));
  ASSERT_TRUE(s.wait_idle());
  EXPECT_EQ(events_but_states(s.messages(), "a.gltf"),
            concat({revision_events("a.gltf", 1, content_hash(a)), revision_events("a.gltf", 2, content_hash(a))}));
}

TEST(DaemonLife, SighupWithABadConfigKeepsTheRunningOne) {
  Session s;
  const auto a = box_model("a_base", 0.05);
  write_model(s.watch, "a.gltf", a);
  auto& daemon = s.start(DaemonOptions().with("default_density", 1000));
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_idle());
  daemon.write_config({{"default_density", "heavy"}});
  daemon.signal(SIGHUP);
  ASSERT_TRUE(daemon.wait_log("SIGHUP: config not reloaded")) << daemon.log();
  EXPECT_NE(daemon.log().find("default_density"), std::string::npos) << daemon.log();
  auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->rescans, 1);
  EXPECT_EQ(model_events(s.messages()), revision_events("a.gltf", 1, content_hash(a)));
  // Still serving, still watching.
  const auto a2 = box_model("a2_base", 0.06);
  write_by_rename(s.watch / "a.gltf", a2.gltf, "a.gltf.tmp");
  ASSERT_TRUE(s.wait_revision("a.gltf", 2, content_hash(a2)));
  EXPECT_NEAR(last_inertia(s.messages(), "a.gltf")->total_mass, a2.link_mass, 1e-6);  // Density 1000.
}

TEST(DaemonLife, SighupWithOtherWatchFoldersSwitchesToThem) {
  // Folders set in the config file only (the command line would override them).
  Session s;
  const fs::path first = s.root / "first";
  const fs::path second = s.root / "second";
  fs::create_directories(first);
  fs::create_directories(second);
  const auto a = box_model("a_base", 0.05);
  const auto b = box_model("b_base", 0.06);
  write_model(first, "a.gltf", a);
  write_model(second, "b.gltf", b);
  auto& daemon = s.start(DaemonOptions().with_folders_in_config().with("watch", {first.string()}).with("output", s.output.string()));
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_idle());

  daemon.write_config({{"watch", {second.string()}}, {"output", s.output.string()}});
  daemon.signal(SIGHUP);
  ASSERT_TRUE(s.wait_revision("b.gltf", 1, content_hash(b)));
  ASSERT_TRUE(daemon.wait_log("config reloaded, folders changed")) << daemon.log();
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  // a.gltf is no longer watched: it is gone from the daemon's view (REMOVED), not converted again.
  EXPECT_EQ(idle->model_ids, std::vector<std::string>{"b.gltf"});
  EXPECT_EQ(model_events(s.messages(), "a.gltf"),
            concat({revision_events("a.gltf", 1, content_hash(a)), {"a.gltf REMOVED last=1"}}));
  EXPECT_EQ(model_events(s.messages(), "b.gltf"), revision_events("b.gltf", 1, content_hash(b)));
  // And changes in the old folder are ignored.
  write_by_rename(first / "a.gltf", box_model("a2_base", 0.07).gltf, "a.gltf.tmp");
  const auto later = s.wait_idle();
  ASSERT_TRUE(later);
  EXPECT_EQ(later->conversions, idle->conversions);
}

TEST(DaemonLife, BadModelsNeverStopTheDaemon) {
  Session s;
  auto& daemon = s.start();
  ASSERT_TRUE(s.wait_idle());
  Json escape = Json::parse(box_model("x", 0.05, 1, "x.bin").gltf);
  escape["buffers"][0]["uri"] = "../../../../../../etc/passwd";
  Json dot = escape;
  dot["buffers"][0]["uri"] = ".";
  Json huge = Json::parse(box_model("x", 0.05).gltf);
  huge["accessors"][0]["count"] = 1ull << 40;
  std::string garbage(4096, '\0');
  for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<char>((i * 2654435761u) >> 13);
  const std::map<std::string, std::string> bad = {
      {"empty.gltf", ""},
      {"not_json.gltf", "{{{ not json"},
      {"garbage.glb", "glTF" + garbage},
      {"escape.gltf", escape.dump()},
      {"dot_uri.gltf", dot.dump()},
      {"huge_count.gltf", huge.dump()},
      {"deep.gltf", std::string(100000, '[') + std::string(100000, ']')},
      {"no_scene.gltf", R"({"asset": {"version": "2.0"}})"},
      {"broken.gltf", broken_model()},
  };
  for (const auto& [name, bytes] : bad) write_by_rename(s.watch / name, bytes, name + ".tmp");
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return on_kind(all, "ERROR").size() >= bad.size(); }, 10s))
      << ::testing::PrintToString(model_events(s.messages())) << daemon.log();
  ASSERT_TRUE(daemon.running()) << daemon.log();
  for (const auto& [name, bytes] : bad) {
    SCOPED_TRACE(name);
    const auto errors = decoded<rdtf::model_error_t>(s.messages(), "ERROR", name);
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_EQ(errors[0].live_revision, 0);
    EXPECT_EQ(errors[0].content_hash, content_hash(bytes));
    ASSERT_FALSE(errors[0].diagnostics.empty());
    EXPECT_EQ(errors[0].diagnostics[0].severity, rdtf::diagnostic_t::ERROR);
    EXPECT_EQ(fs::path(errors[0].diagnostics[0].file), fs::canonical(s.watch / name));
  }
  // Still working: a good model after all that.
  const auto good = box_model("good_base", 0.05);
  write_model(s.watch, "good.gltf", good);
  ASSERT_TRUE(s.wait_revision("good.gltf", 1, content_hash(good)));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->rejections, static_cast<std::int64_t>(bad.size()));
  EXPECT_EQ(idle->conversions, 1);
  EXPECT_EQ(idle->model_ids, std::vector<std::string>{"good.gltf"});
  EXPECT_EQ(model_events(s.messages()).size(), bad.size() + 2);
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait_exit(3s), std::optional<int>(0));
}

TEST(DaemonLife, ASlowModelDoesNotDelayOthers) {
  Session s;
  s.start();
  ASSERT_TRUE(s.wait_idle());
  const auto heavy = many_parts_model("heavy_base", 20000, 0.001);
  const auto small = box_model("small_base", 0.05);
  write_model(s.watch, "heavy.gltf", heavy);
  write_model(s.watch, "small.gltf", small);
  const auto saved = Clock::now();
  ASSERT_TRUE(s.wait_revision("small.gltf", 1, content_hash(small)));
  // A wait, not a speed bound: it returns when the revision arrives. The 20,000-part model
  // takes ~2 s in a release build, but over 20 s in a Debug ASan build on a loaded 2-core machine.
  ASSERT_TRUE(s.wait_revision("heavy.gltf", 1, content_hash(heavy), 180s)) << s.daemon->log();
  ASSERT_TRUE(s.wait_idle());
  // The heavy model really is slow: its conversion time from the log.
  const std::string log = s.daemon->log();
  const std::regex line("converted heavy\\.gltf revision 1 \\([^)]*\\) in ([0-9.]+) ms");
  std::smatch match;
  ASSERT_TRUE(std::regex_search(log, match, line)) << log;
  const double heavy_ms = std::stod(match[1]);
  ASSERT_GT(heavy_ms, 150.0) << "the heavy model converted too fast to show anything";
  RecordProperty("heavy_conversion_ms", std::to_string(heavy_ms));
  // The small one, saved at the same time, came out long before.
  const auto all = s.messages();
  const auto small_at = on_kind(all, "DESCRIPTION", "small.gltf").at(0).received;
  const auto heavy_at = on_kind(all, "DESCRIPTION", "heavy.gltf").at(0).received;
  EXPECT_LT(small_at, heavy_at);
  const double small_ms = std::chrono::duration<double, std::milli>(small_at - saved).count();
  EXPECT_LT(small_ms, heavy_ms)
      << "small model published only after the heavy one's conversion time";
  EXPECT_EQ(model_events(all, "small.gltf"), revision_events("small.gltf", 1, content_hash(small)));
}

TEST(DaemonLife, DefaultsValidateEveryRevisionBeforePublishingIt) {
  // The shipped defaults: dynamics validation on, two workers, so models converting at the same
  // time are validated at the same time. Each revision: VALIDATION (passed), then DESCRIPTION
  // (validated) and INERTIA; and the daemon keeps running.
  Session s;
  copy_fixture(s.watch, "arm3");
  copy_fixture(s.watch, "two_cylinder");
  copy_fixture(s.watch, "transforms");
  std::map<std::string, std::string> expected = {{"arm3.gltf", fixture_hash("arm3")},
                                                 {"two_cylinder.gltf", fixture_hash("two_cylinder")},
                                                 {"transforms.gltf", fixture_hash("transforms")}};
  for (int i = 0; i < 10; ++i) {  // Enough models that validations overlap many times.
    const auto chain = box_model("chain_base", 0.05 + 0.005 * i, 3);
    write_model(s.watch, "chain" + std::to_string(i) + ".gltf", chain);
    expected["chain" + std::to_string(i) + ".gltf"] = content_hash(chain);
  }
  auto& daemon = s.start(DaemonOptions().with("validate", true).with("workers", 2));
  auto all_there = [&] {
    const auto all = s.messages();
    for (const auto& [id, hash] : expected) {
      if (!has_revision(all, id, 1, hash)) return false;
    }
    return true;
  };
  wait_until([&] { return all_there() || !daemon.running(); }, 10s);
  ASSERT_TRUE(daemon.running()) << "rdtfd died:\n" << daemon.log();
  ASSERT_TRUE(all_there()) << ::testing::PrintToString(model_events(s.messages()));
  ASSERT_TRUE(s.wait_idle());
  const auto all = s.messages();
  for (const auto& [id, hash] : expected) {
    EXPECT_EQ(model_events(all, id),
              concat({{id + " VALIDATION r1 " + short_hash(hash) + " passed"}, revision_events(id, 1, hash)}));
    const auto d = last_description(all, id);
    EXPECT_TRUE(d->validated) << id;
    EXPECT_TRUE(d->validation_passed) << id;
  }
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait_exit(3s), std::optional<int>(0)) << daemon.log();
}

// The gate's settings reach it, from the config file and from --set on the command line (which
// wins): the run lasts validation_seconds in steps of time_step.
TEST(DaemonLife, ValidationSettingsFromTheConfigAndSetReachTheGate) {
  Session s;
  const auto a = box_model("a_base", 0.05, 2);
  write_model(s.watch, "a.gltf", a);
  s.start(DaemonOptions()
              .with("validate", true)
              .with("validation_seconds", 0.5)
              .with("time_step", 0.001)
              .with_args({"--set", "time_step=0.002", "--set", "stepper=quick_step"}));
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "VALIDATION", "a.gltf").empty(); }));
  const auto report = on_kind(s.messages(), "VALIDATION", "a.gltf").front().as<rdtf::validation_report_t>();
  EXPECT_TRUE(report.passed);
  EXPECT_EQ(report.steps, 250);
  EXPECT_NEAR(report.simulated_time, 0.5, 1e-9 * 0.5);
}

TEST(DaemonLife, UnknownSetKeyIsRefusedAtStart) {
  Session s;
  DaemonOptions options = DaemonOptions().with_args({"--set", "max_mass_ration=20"});
  options.watch = {s.watch};
  options.output = s.output;
  DaemonProcess daemon(std::move(options));
  EXPECT_EQ(daemon.wait_exit(5s), std::optional<int>(2)) << daemon.log();
  EXPECT_NE(daemon.log().find("rdtfd: --set: unknown key \"max_mass_ration\""), std::string::npos) << daemon.log();
}

}  // namespace
}  // namespace rdtf::itest
