// rdtfd's dynamics gate over real LCM (one network namespace per case; see harness.h): a revision
// that fails the check never touches the live revision's files, its number is never reused,
// publish_failed publishes it and stops the simulation, and warnings of good conversions are
// logged and published with the verdict.
#include <set>
#include <sstream>

#include <rdtf/joint_state_t.hpp>

#include "daemon/harness.h"
#include "support/harness/fs_support.h"

namespace rdtf::itest {
namespace {

DaemonOptions gated() { return DaemonOptions().with("validate", true).with("validation_seconds", 0.5); }

// gate_failing_model's fault is a mass ratio of 1e6 across its one joint. A root welded to the
// world is no body (docs/dynamics.md: weld groups), so that ratio is judged only when the root
// floats, and only under QuickStep (dWorldStep, the automatic stepper's for two bodies, holds it).
DaemonOptions gated_floating() { return gated().with("floating_root", true).with("stepper", "quick_step"); }

// Revision number -> the content hashes it was published with, over every message that carries one.
std::map<std::int64_t, std::set<std::string>> numbers(const std::vector<Message>& all, const std::string& id) {
  std::map<std::int64_t, std::set<std::string>> seen;
  for (const auto& v : decoded<rdtf::validation_report_t>(all, "VALIDATION", id)) seen[v.revision].insert(v.content_hash);
  for (const auto& d : decoded<rdtf::description_t>(all, "DESCRIPTION", id)) seen[d.revision].insert(d.content_hash);
  for (const auto& t : decoded<rdtf::inertia_table_t>(all, "INERTIA", id)) seen[t.revision].insert(t.content_hash);
  return seen;
}

// The output folder as it was: the same files, each with the same bytes (names only on failure).
void expect_same_files(const std::map<std::string, std::string>& now, const std::map<std::string, std::string>& before) {
  std::vector<std::string> now_names, before_names;
  for (const auto& [name, bytes] : now) now_names.push_back(name);
  for (const auto& [name, bytes] : before) before_names.push_back(name);
  EXPECT_EQ(now_names, before_names) << "a rejected revision added or removed output files";
  for (const auto& [name, bytes] : before) {
    const auto found = now.find(name);
    if (found != now.end()) {
      EXPECT_TRUE(found->second == bytes) << "a rejected revision rewrote " << name;
    }
  }
}

bool has_error_for(const std::vector<Message>& all, const std::string& id, const std::string& hash) {
  for (const auto& e : decoded<rdtf::model_error_t>(all, "ERROR", id)) {
    if (e.content_hash == hash) return true;
  }
  return false;
}

TEST(DaemonGate, ARejectedRevisionLeavesTheLiveOutputsAndNumbersAlone) {
  Session s;
  const std::string id = "m.gltf";
  const auto good = box_model("good_base", 0.05, 2, "m.bin");
  write_model(s.watch, id, good);
  auto& daemon = s.start(gated_floating());
  ASSERT_TRUE(s.wait_revision(id, 1, content_hash(good)));
  ASSERT_TRUE(s.wait_idle());
  const auto live_files = snapshot(s.output);
  const auto live = *last_description(s.messages(), id);
  ASSERT_TRUE(fs::exists(live.output_path));
  ASSERT_TRUE(fs::exists(live.urdf_path));

  // Other geometry (another .bin, other meshes) and a mass ratio the gate refuses.
  const auto bad = gate_failing_model("bad_base", 0.07, "m.bin");
  write_model(s.watch, id, bad);
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return has_error_for(all, id, content_hash(bad)); }))
      << ::testing::PrintToString(model_events(s.messages(), id));
  ASSERT_TRUE(s.wait_idle());
  expect_same_files(snapshot(s.output), live_files);
  EXPECT_EQ(read(live.output_path), live.rdtf_json);
  EXPECT_EQ(read(live.urdf_path), live.urdf);

  const auto error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", id).back();
  EXPECT_EQ(error.live_revision, 1);
  bool mass_ratio = false;
  for (const auto& d : error.diagnostics) mass_ratio |= d.code == "JOINT_MASS_RATIO";
  EXPECT_TRUE(mass_ratio) << ::testing::PrintToString(s.messages().back().json().dump());
  EXPECT_NE(daemon.log().find("rejected " + id + " revision 2 (dynamics)"), std::string::npos) << daemon.log();

  // A subscriber that starts now gets the live revision with its own verdict, not the rejected one's.
  s.request(id, "late");
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return on_kind(all, "DESCRIPTION", id).size() == 2; }));
  ASSERT_TRUE(s.wait_idle());

  // The next good save gets a number of its own: 2 was the rejected content's.
  const auto fixed = box_model("fixed_base", 0.06, 2, "m.bin");
  write_model(s.watch, id, fixed);
  ASSERT_TRUE(s.wait_revision(id, 3, content_hash(fixed)));
  ASSERT_TRUE(s.wait_idle());
  const auto all = s.messages();
  const std::string h1 = short_hash(content_hash(good));
  const std::string h2 = short_hash(content_hash(bad));
  const std::string h3 = short_hash(content_hash(fixed));
  EXPECT_EQ(model_events(all, id),
            (std::vector<std::string>{id + " VALIDATION r1 " + h1 + " passed", id + " DESCRIPTION r1 " + h1,
                                      id + " INERTIA r1 " + h1, id + " VALIDATION r2 " + h2 + " failed",
                                      id + " ERROR live=1 " + h2, id + " VALIDATION r1 " + h1 + " passed",
                                      id + " DESCRIPTION r1 " + h1, id + " INERTIA r1 " + h1,
                                      id + " VALIDATION r3 " + h3 + " passed",
                                      id + " DESCRIPTION r3 " + h3, id + " INERTIA r3 " + h3}));
  for (const auto& [revision, hashes] : numbers(all, id)) {
    EXPECT_EQ(hashes.size(), 1u) << "revision " << revision << " stands for several contents";
  }
  const auto now_live = *last_description(all, id);
  EXPECT_EQ(read(now_live.output_path), now_live.rdtf_json);
  EXPECT_EQ(read(now_live.urdf_path), now_live.urdf);
}

// Joint states with the time each arrived.
std::vector<std::pair<Clock::time_point, rdtf::joint_state_t>> states(const std::vector<Message>& all,
                                                                      const std::string& id) {
  std::vector<std::pair<Clock::time_point, rdtf::joint_state_t>> out;
  for (const auto& m : on_kind(all, "JOINT_STATE", id)) out.emplace_back(m.received, m.as<rdtf::joint_state_t>());
  return out;
}

TEST(DaemonGate, PublishFailedPublishesTheFailedRevisionAndStopsItsSimulation) {
  Session s;
  const std::string id = "m.gltf";
  const auto good = box_model("good_base", 0.05, 2);
  write_model(s.watch, id, good);
  auto& daemon = s.start(gated_floating().with("publish_failed", true).with("simulate", true).with("state_rate_hz", 100));
  ASSERT_TRUE(s.wait_revision(id, 1, content_hash(good)));
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return states(all, id).size() >= 5; }));

  const auto bad = gate_failing_model("bad_base", 0.05);
  write_model(s.watch, id, bad);
  ASSERT_TRUE(s.wait_revision(id, 2, content_hash(bad)));
  const auto published = on_kind(s.messages(), "DESCRIPTION", id).back().received;
  const auto d = *last_description(s.messages(), id);
  EXPECT_TRUE(d.validated);
  EXPECT_FALSE(d.validation_passed);
  // Published means written: the files are the failed revision's.
  EXPECT_EQ(read(d.output_path), d.rdtf_json);
  EXPECT_EQ(read(d.urdf_path), d.urdf);
  // The stream stops with the failed revision. The simulation thread sends on its own socket, so a
  // state already on its way may arrive just after the description; 100 ms covers that, while the
  // 100 Hz stream would give about 40 states in the 400 ms watched.
  std::this_thread::sleep_for(500ms);
  int after = 0;
  for (const auto& [at, state] : states(s.messages(), id)) {
    EXPECT_NE(state.revision, 2) << "a failed revision was simulated";
    after += at > published + 100ms;
  }
  EXPECT_EQ(after, 0) << "joint states of revision 1 went on after revision 2 was published";
  EXPECT_NE(daemon.log().find("stopped the simulation of " + id + ": revision 2 failed the dynamics check"),
            std::string::npos)
      << daemon.log();

  // A good save starts it again, with its own revision.
  const auto fixed = box_model("fixed_base", 0.06, 2);
  write_model(s.watch, id, fixed);
  ASSERT_TRUE(s.wait_revision(id, 3, content_hash(fixed)));
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    for (const auto& [at, state] : states(all, id)) {
      if (state.revision == 3 && state.content_hash == content_hash(fixed)) return true;
    }
    return false;
  }));
  const auto all = s.messages();
  EXPECT_EQ(on_kind(all, "ERROR", id).size(), 0u) << "publish_failed: the failed revision is published, not an error";
  for (const auto& [revision, hashes] : numbers(all, id)) {
    EXPECT_EQ(hashes.size(), 1u) << "revision " << revision << " stands for several contents";
  }
}

TEST(DaemonGate, WarningsOfAGoodConversionAreLoggedAndPublishedWithTheVerdict) {
  Session s;
  const std::string id = "w.gltf";
  // A space is no URDF name: the URDF export renames the link (URDF_NAME_CHANGED).
  const auto model = box_model("base link", 0.05);
  write_model(s.watch, id, model);
  auto& daemon = s.start(gated());
  ASSERT_TRUE(s.wait_revision(id, 1, content_hash(model)));
  ASSERT_TRUE(s.wait_idle());
  const auto reports = decoded<rdtf::validation_report_t>(s.messages(), "VALIDATION", id);
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_TRUE(reports[0].passed);
  std::vector<rdtf::diagnostic_t> renamed;
  for (const auto& d : reports[0].diagnostics) {
    if (d.code == "URDF_NAME_CHANGED") renamed.push_back(d);
  }
  ASSERT_EQ(renamed.size(), 1u) << reports[0].num_diagnostics << " diagnostics";
  EXPECT_EQ(renamed[0].severity, rdtf::diagnostic_t::WARNING);
  EXPECT_EQ(renamed[0].pointer, "/nodes/0");
  EXPECT_FALSE(renamed[0].file.empty());
  EXPECT_NE(renamed[0].message.find("'base link'"), std::string::npos) << renamed[0].message;
  // One log line, naming the file and the place.
  const std::string line = "warning " + id + " revision 1: " + renamed[0].file + ":/nodes/0: warning URDF_NAME_CHANGED: ";
  const auto log = daemon.log();
  const auto at = log.find(line);
  ASSERT_NE(at, std::string::npos) << log;
  EXPECT_EQ(log.find(line, at + 1), std::string::npos) << "logged twice:\n" << log;

  // A subscriber that starts late asks, and gets the same report (warnings included) before the
  // description it belongs to.
  Subscriber late(s.prefix + "/.*");
  s.request(id, "late");
  ASSERT_TRUE(late.wait_for([&](const auto& all) { return !on_kind(all, "INERTIA", id).empty(); }));
  const auto answer = late.messages();
  EXPECT_EQ(model_events(answer, id),
            (std::vector<std::string>{id + " VALIDATION r1 " + short_hash(content_hash(model)) + " passed",
                                      id + " DESCRIPTION r1 " + short_hash(content_hash(model)),
                                      id + " INERTIA r1 " + short_hash(content_hash(model))}));
  const auto again = decoded<rdtf::validation_report_t>(answer, "VALIDATION", id).at(0);
  Json first = on_kind(s.messages(), "VALIDATION", id).at(0).json();
  Json second = on_kind(answer, "VALIDATION", id).at(0).json();
  first.erase("utime");  // Set when each is published.
  second.erase("utime");
  EXPECT_EQ(second, first);
  EXPECT_GE(again.utime, reports[0].utime);
}

// A robot whose QuickStep run fails and whose dWorldStep run passes (docs/dynamics.md, "When
// QuickStep fails": one island of 29 bodies, a finger overrunning its stop under QuickStep) is
// published with the exact run's verdict and QuickStep's failure as an info, and its live simulation
// steps with dWorldStep, as the check did. The model is imported before rdtfd starts; its 3 s check
// is the default's.
TEST(DaemonGate, AModelOnlyQuickStepFailsIsPublishedAndSimulatedWithDWorldStep) {
  Session s;
  const std::string id = "hand.gltf";
  const std::string import = std::string(RDTF_CLI_PATH) + " import " + RDTF_TEST_DATA_DIR +
                             "/robots/ur5_five_finger_hand.urdf -o " + (s.watch / id).string() + " 2>" +
                             (s.root / "import.log").string();
  ASSERT_EQ(run_shell(import), 0) << read(s.root / "import.log");
  auto& daemon = s.start(gated().with("validation_seconds", 3.0).with("simulate", true).with("state_rate_hz", 100));
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return !on_kind(all, "DESCRIPTION", id).empty(); }, 60s))
      << daemon.log();
  const auto reports = decoded<rdtf::validation_report_t>(s.messages(), "VALIDATION", id);
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_TRUE(reports[0].passed);
  int notes = 0;
  for (const auto& d : reports[0].diagnostics) {
    if (d.code != "SIM_QUICKSTEP_FAILED") continue;
    ++notes;
    EXPECT_EQ(d.severity, rdtf::diagnostic_t::INFO);
    EXPECT_NE(d.message.find("(29 bodies in one island, 50 iterations) the run failed"), std::string::npos) << d.message;
  }
  EXPECT_EQ(notes, 1);
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return states(all, id).size() >= 5; }, 10s)) << daemon.log();
  EXPECT_NE(daemon.log().find("simulation of " + id +
                              " revision 1 steps with dWorldStep, the stepper its dynamics check passed it with"),
            std::string::npos)
      << daemon.log();
}

// A 30-link chain of 1 kg, 10 cm rods on revolute joints limited to +-1 rad about X and Y in turn,
// three of them with their inertia x 1e-6 (point masses on their rods): QuickStep blows it up,
// dWorldStep steps it soundly (s104rev's c30_tiny3).
std::string chain_with_point_masses() {
  std::string urdf = "<?xml version=\"1.0\"?>\n<robot name=\"chain\">\n<link name=\"base\"><inertial><mass value=\"1\"/>"
                     "<inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n";
  const auto text = [](double value) {
    std::ostringstream out;
    out.precision(17);
    out << value;
    return out.str();
  };
  for (int i = 0; i < 30; ++i) {
    const double scale = (i == 5 || i == 15 || i == 25) ? 1e-6 : 1.0;
    const double across = (3 * 0.01 * 0.01 + 0.1 * 0.1) / 12 * scale, along = 0.01 * 0.01 / 2 * scale;
    const std::string name = "l" + std::to_string(i);
    urdf += "<link name=\"" + name + "\"><inertial><origin xyz=\"0 0 -0.05\"/><mass value=\"1\"/><inertia ixx=\"" +
            text(across) + "\" iyy=\"" + text(across) + "\" izz=\"" + text(along) +
            "\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial><visual><origin xyz=\"0 0 -0.05\"/><geometry><cylinder "
            "radius=\"0.01\" length=\"0.1\"/></geometry></visual></link>\n";
    urdf += "<joint name=\"j" + std::to_string(i) + "\" type=\"revolute\"><parent link=\"" +
            (i == 0 ? std::string("base") : "l" + std::to_string(i - 1)) + "\"/><child link=\"" + name +
            "\"/><origin xyz=\"0 0 " + (i == 0 ? "0" : "-0.1") + "\"/><axis xyz=\"" + (i % 2 == 0 ? "1 0 0" : "0 1 0") +
            "\"/><limit lower=\"-1\" upper=\"1\" effort=\"100\" velocity=\"10\"/></joint>\n";
  }
  return urdf + "</robot>\n";
}

// A reload that forces quick_step checks every model again, and QuickStep fails this one: its
// revision 1, judged with dWorldStep after QuickStep failed, stays live, and its simulation,
// restarted with the new settings, still steps with the stepper it was judged with. With QuickStep
// it blew up: joints limited to +-1 rad wound to 158 rad (s104rev D1). Every state now stays near
// its range: 0.5 rad, far below a blow-up and far above the 0.01 rad plus a step's travel past a
// stop that the check allows.
TEST(DaemonGate, AReloadToQuickStepKeepsSimulatingARevisionWithTheStepperItWasJudgedWith) {
  Session s;
  const std::string id = "chain.glb";
  testing::write_file(s.root / "chain.urdf", chain_with_point_masses());
  const std::string import = std::string(RDTF_CLI_PATH) + " import " + (s.root / "chain.urdf").string() + " -o " +
                             (s.watch / id).string() + " 2>" + (s.root / "import.log").string();
  ASSERT_EQ(run_shell(import), 0) << read(s.root / "import.log");
  auto& daemon = s.start(gated()
                             .with("validation_seconds", 3.0)
                             .with("validation_start_offset_rad", 0.3)
                             .with("gravity", Json::array({0, 0, -9.80665}))
                             .with("simulate", true)
                             .with("state_rate_hz", 100));
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return !on_kind(all, "DESCRIPTION", id).empty(); }, 60s))
      << daemon.log();
  ASSERT_TRUE(daemon.wait_log("simulation of " + id + " revision 1 steps with dWorldStep")) << daemon.log();

  const fs::path config = daemon.config_path();
  Json changed = Json::parse(read(config));
  changed["stepper"] = "quick_step";
  fs::remove(config);
  testing::write_file(config, changed.dump());
  daemon.signal(SIGHUP);
  ASSERT_TRUE(daemon.wait_log("SIGHUP: config reloaded")) << daemon.log();
  ASSERT_TRUE(daemon.wait_log("rejected " + id + " revision 2 (dynamics)", 60s)) << daemon.log();
  const auto reloaded = Clock::now();
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    const auto st = states(all, id);
    return !st.empty() && st.back().first > reloaded + 3s;
  }, 10s));
  std::size_t after = 0;
  for (const auto& [at, state] : states(s.messages(), id)) {
    if (at < reloaded) continue;
    ++after;
    EXPECT_EQ(state.revision, 1);
    for (int j = 0; j < state.num_joints; ++j) {
      ASSERT_LT(std::abs(state.position[j]), 1.5) << state.name[j] << " wound past its stop";
    }
  }
  EXPECT_GT(after, 100u);
}

TEST(DaemonGate, WarningsAreLoggedWithoutValidationToo) {
  Session s;
  const std::string id = "w.gltf";
  write_model(s.watch, id, box_model("base link", 0.05));
  auto& daemon = s.start();
  ASSERT_TRUE(s.wait_revision(id, 1, content_hash(box_model("base link", 0.05))));
  EXPECT_TRUE(daemon.wait_log(":/nodes/0: warning URDF_NAME_CHANGED: link 'base link' is named")) << daemon.log();
}

}  // namespace
}  // namespace rdtf::itest
