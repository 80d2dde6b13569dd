// DELTA and revision numbers that last across restarts, with a real rdtfd over real LCM (one
// network namespace per case; see harness.h): a save that changes one joint's limit gives a DELTA
// naming that joint with only `limits`; an unchanged model keeps its number after a restart, a
// changed one gets the next and is diffed against the earlier run's live revision; numbers of
// rejected contents are not handed out again; a corrupt or hostile state file is refused.
#include <functional>
#include <set>

#include <rdtf/delta_t.hpp>

#include "daemon/harness.h"

namespace rdtf::itest {
namespace {

// base -> joint_1 -> link_1 -> joint_2 -> link_2, joint_2 limited to [-1, `upper`].
GeneratedModel chain(double upper) {
  GeneratedModel model = box_model("base", 0.05, 3);
  Json document = Json::parse(model.gltf);
  document["nodes"][4]["extras"]["rdtf_lower"] = -1.0;
  document["nodes"][4]["extras"]["rdtf_upper"] = upper;
  model.gltf = document.dump(1);
  return model;
}

std::vector<rdtf::delta_t> deltas(const std::vector<Message>& all, const std::string& id) {
  return decoded<rdtf::delta_t>(all, "DELTA", id);
}

std::optional<rdtf::delta_t> delta_of(const std::vector<Message>& all, const std::string& id, std::int64_t revision) {
  for (const auto& d : deltas(all, id)) {
    if (d.revision == revision) return d;
  }
  return std::nullopt;
}

bool has_delta(const std::vector<Message>& all, const std::string& id, std::int64_t revision) {
  return delta_of(all, id, revision).has_value();
}

// The DELTA of a limit edit of joint_2: that joint, only `limits`, nothing else.
void expect_only_joint_2_limits(const rdtf::delta_t& d) {
  EXPECT_EQ(d.part, 0);
  EXPECT_EQ(d.num_parts, 1);
  EXPECT_EQ(d.total_changes, 1);
  ASSERT_EQ(d.changes.size(), 1u);
  const auto& c = d.changes[0];
  EXPECT_EQ(c.element, "joint");
  EXPECT_EQ(c.change, "changed");
  EXPECT_EQ(c.name, "joint_2");
  EXPECT_EQ(c.urdf_name, "joint_2");
  EXPECT_EQ(c.aspects, std::vector<std::string>{"limits"});
}

// The first DESCRIPTION of `id` at or after message `from` (a restart's), waited for.
std::optional<rdtf::description_t> description_since(Session& s, std::size_t from, const std::string& id) {
  std::optional<rdtf::description_t> found;
  s.wait_for([&](const auto& all) {
    for (std::size_t i = from; i < all.size(); ++i) {
      if (all[i].kind() == "DESCRIPTION" && all[i].model_id() == id) {
        found = all[i].template as<rdtf::description_t>();
        return true;
      }
    }
    return false;
  }, 10s);
  return found;
}

// Whether the result cache holds an entry of this content (rdtfd writes it once the revision is
// handed to its loop, beside the publication: docs/daemon.md, "Result cache").
bool cached(const fs::path& output, const std::string& content_hash) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(output / ".rdtfd-state" / "results", ec)) {
    if (entry.path().extension() == ".json" && read(entry.path()).find(content_hash) != std::string::npos) return true;
  }
  return false;
}

fs::path state_file_of(const fs::path& output) {
  std::vector<fs::path> files;
  // The revision states ("m-<hex>.json"); the folder also holds the result cache and the clean-stop mark.
  for (const auto& entry : fs::directory_iterator(output / ".rdtfd-state")) {
    if (entry.path().filename().string().rfind("m-", 0) == 0) files.push_back(entry.path());
  }
  if (files.size() != 1) throw std::runtime_error("expected one state file, found " + std::to_string(files.size()));
  return files[0];
}

TEST(Revisions, ALimitEditGivesADeltaNamingThatJointWithOnlyLimits) {
  Session s;
  const std::string id = "arm.gltf";
  const auto v1 = chain(1.0);
  const auto v2 = chain(1.5);
  write_model(s.watch, id, v1);
  s.start();
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return has_delta(all, id, 1); }));
  // The first revision: no previous one, everything added.
  const auto first = *delta_of(s.messages(), id, 1);
  EXPECT_EQ(first.previous_revision, 0);
  EXPECT_EQ(first.previous_content_hash, "");
  EXPECT_EQ(first.content_hash, content_hash(v1));
  EXPECT_EQ(first.total_changes, 5);  // 3 links, 2 joints
  for (const auto& c : first.changes) EXPECT_EQ(c.change, "added") << c.name;

  write_in_place(s.watch / id, v2.gltf);
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return has_delta(all, id, 2); }));
  const auto all = s.messages();
  const auto second = *delta_of(all, id, 2);
  EXPECT_EQ(second.previous_revision, 1);
  EXPECT_EQ(second.previous_content_hash, content_hash(v1));
  EXPECT_EQ(second.content_hash, content_hash(v2));
  expect_only_joint_2_limits(second);
  // After the revision's description and inertia, once (other kinds, such as the files a revision
  // lists, may come between: only these three are looked at).
  std::vector<std::string> kinds;
  for (const auto& m : all) {
    const std::string k = m.kind();
    if (m.model_id() == id && (k == "DESCRIPTION" || k == "INERTIA" || k == "DELTA")) kinds.push_back(k);
  }
  EXPECT_EQ(kinds, (std::vector<std::string>{"DESCRIPTION", "INERTIA", "DELTA", "DESCRIPTION", "INERTIA", "DELTA"}));
  // rdtf-echo's JSON (clients/echo/message_json.cc) of the same message.
  const auto delta_messages = on_kind(all, "DELTA", id);
  const Json json = delta_messages.back().json();
  ASSERT_TRUE(json.is_object());
  EXPECT_EQ(json["type"], "rdtf.delta_t");
  EXPECT_EQ(json["previous_revision"], 1);
  EXPECT_EQ(json["revision"], 2);
  EXPECT_EQ(json["changes"], Json::parse(R"([{"element":"joint","change":"changed","name":"joint_2",
                                             "urdf_name":"joint_2","aspects":["limits"]}])"));
}

TEST(Revisions, SurviveARestartUnchangedKeepTheirNumberChangedGetTheNext) {
  Session s;
  const auto a = box_model("a_base", 0.05);
  const auto b1 = chain(1.0);
  const auto b2 = chain(1.5);
  const auto b3 = chain(2.0);
  write_model(s.watch, "a.gltf", a);
  write_model(s.watch, "b.gltf", b1);
  auto& daemon = s.start();
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_revision("b.gltf", 1, content_hash(b1)));
  write_in_place(s.watch / "b.gltf", b2.gltf);
  ASSERT_TRUE(s.wait_revision("b.gltf", 2, content_hash(b2)));
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return has_delta(all, "b.gltf", 2); }));
  ASSERT_TRUE(wait_until([&] { return cached(s.output, content_hash(a)) && cached(s.output, content_hash(b2)); }, 10s))
      << daemon.log();

  // Killed, not stopped: the state was saved before the numbers were published.
  daemon.signal(SIGKILL);
  ASSERT_EQ(daemon.wait_exit(5s), 128 + SIGKILL);
  std::size_t from = s.subscriber.size();
  daemon.restart();
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    std::set<std::string> seen;
    for (std::size_t i = from; i < all.size(); ++i) {
      if (all[i].kind() == "INERTIA") seen.insert(all[i].model_id());
    }
    return seen.size() == 2;
  }, 10s)) << daemon.log();
  ASSERT_TRUE(s.wait_idle());
  auto all = s.messages();
  const std::vector<Message> after(all.begin() + static_cast<std::ptrdiff_t>(from), all.end());
  EXPECT_EQ(model_events(after, "a.gltf"), revision_events("a.gltf", 1, content_hash(a)));
  EXPECT_EQ(model_events(after, "b.gltf"), revision_events("b.gltf", 2, content_hash(b2)));
  EXPECT_TRUE(on_kind(after, "DELTA").empty()) << "nothing changed, yet a DELTA";
  EXPECT_TRUE(daemon.wait_log("converted b.gltf revision 2 (3 links, 2 joints) in ")) << daemon.log();
  EXPECT_NE(daemon.log().find("(the result the earlier run served: its number kept)"), std::string::npos);

  // Changed while rdtfd was down: the next number, diffed against the earlier run's revision 2.
  ASSERT_EQ(daemon.stop(), std::optional<int>(0));
  write_in_place(s.watch / "b.gltf", b3.gltf);
  from = s.subscriber.size();
  daemon.restart();
  const auto b_after = description_since(s, from, "b.gltf");
  ASSERT_TRUE(b_after) << daemon.log();
  EXPECT_EQ(b_after->revision, 3);
  EXPECT_EQ(b_after->content_hash, content_hash(b3));
  const auto a_after = description_since(s, from, "a.gltf");
  ASSERT_TRUE(a_after) << daemon.log();
  EXPECT_EQ(a_after->revision, 1);
  EXPECT_EQ(a_after->content_hash, content_hash(a));
  ASSERT_TRUE(s.wait_for([&](const auto& m) { return has_delta(m, "b.gltf", 3); }));
  ASSERT_TRUE(s.wait_idle());
  all = s.messages();
  const auto d = *delta_of(all, "b.gltf", 3);
  EXPECT_EQ(d.previous_revision, 2);
  EXPECT_EQ(d.previous_content_hash, content_hash(b2));
  expect_only_joint_2_limits(d);
  // No other revision of either model since the restart.
  for (std::size_t i = from; i < all.size(); ++i) {
    if (all[i].kind() != "DESCRIPTION") continue;
    const auto desc = all[i].as<rdtf::description_t>();
    EXPECT_EQ(desc.revision, desc.model_id == "a.gltf" ? 1 : 3) << desc.model_id;
  }
}

// Revision states are synced once per block of numbers they reserve (docs/daemon.md, "Revision
// state"). A power loss can take back the saves since: here the state file is put back as the
// durable save of revision 1 left it, and the machine has booted again. The next number is above
// the block that save reserved, never 2 again.
TEST(Revisions, AfterAPowerLossNumbersGoOnAboveTheReservedBlock) {
  Session s;
  const std::string id = "b.gltf";
  const auto b1 = chain(1.0);
  const auto b2 = chain(1.5);
  const auto b3 = chain(2.0);
  write_model(s.watch, id, b1);
  auto& daemon = s.start();
  ASSERT_TRUE(s.wait_revision(id, 1, content_hash(b1)));
  const fs::path state = state_file_of(s.output);
  const std::string durable = read(state);
  write_in_place(s.watch / id, b2.gltf);
  ASSERT_TRUE(s.wait_revision(id, 2, content_hash(b2)));
  daemon.signal(SIGKILL);
  ASSERT_EQ(daemon.wait_exit(5s), 128 + SIGKILL);
  testing::write_file(state, durable);
  testing::write_file(s.output / ".rdtfd-state" / "boot-id", "an earlier boot\n");

  write_in_place(s.watch / id, b3.gltf);
  const std::size_t from = s.subscriber.size();
  daemon.restart();
  const auto after = description_since(s, from, id);
  ASSERT_TRUE(after) << daemon.log();
  EXPECT_EQ(after->revision, 101) << daemon.log();
  EXPECT_EQ(after->content_hash, content_hash(b3));

  // The same after a clean stop: the start trusts the file, which says 101.
  ASSERT_EQ(daemon.stop(), std::optional<int>(0));
  const auto b4 = chain(2.5);
  write_in_place(s.watch / id, b4.gltf);
  const std::size_t again = s.subscriber.size();
  daemon.restart();
  const auto next = description_since(s, again, id);
  ASSERT_TRUE(next) << daemon.log();
  EXPECT_EQ(next->revision, 102) << daemon.log();
}

TEST(Revisions, NumbersOfRejectedContentsAreNotHandedOutAgainAfterARestart) {
  Session s;
  const std::string id = "m.gltf";
  const auto good = chain(1.0);
  const auto bad = gate_failing_model("bad_base", 0.05);
  const auto fixed = chain(1.5);
  write_model(s.watch, id, good);
  // The bad model's mass ratio is judged under QuickStep (docs/dynamics.md, JOINT_MASS_RATIO).
  const auto gated = DaemonOptions()
                         .with("validate", true)
                         .with("validation_seconds", 0.5)
                         .with("floating_root", true)
                         .with("stepper", "quick_step");
  auto& daemon = s.start(gated);
  ASSERT_TRUE(s.wait_revision(id, 1, content_hash(good), 20s)) << daemon.log();
  write_in_place(s.watch / id, bad.gltf);
  auto rejected = [&](std::int64_t revision) {
    return s.wait_for([&](const auto& all) {
      for (const auto& v : decoded<rdtf::validation_report_t>(all, "VALIDATION", id)) {
        if (v.revision == revision && !v.passed && v.content_hash == content_hash(bad)) return true;
      }
      return false;
    }, 20s);
  };
  ASSERT_TRUE(rejected(2)) << daemon.log();
  ASSERT_TRUE(daemon.wait_log("rejected m.gltf revision 2 (dynamics)"));
  ASSERT_EQ(daemon.stop(), std::optional<int>(0));

  // The rejected content is still the file: judged again under a new number, not 2 again and not 1.
  const std::size_t from = s.subscriber.size();
  daemon.restart();
  ASSERT_TRUE(rejected(3)) << daemon.log();
  const auto seen = s.messages();
  for (std::size_t i = from; i < seen.size(); ++i) {
    const auto& m = seen[i];
    if (m.kind() == "VALIDATION") {
      EXPECT_EQ(m.as<rdtf::validation_report_t>().revision, 3);
    }
  }
  // A good save: the next number, diffed against revision 1, the last one served.
  write_in_place(s.watch / id, fixed.gltf);
  ASSERT_TRUE(s.wait_revision(id, 4, content_hash(fixed), 20s)) << daemon.log();
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return has_delta(all, id, 4); }));
  const auto d = *delta_of(s.messages(), id, 4);
  EXPECT_EQ(d.previous_revision, 1);
  EXPECT_EQ(d.previous_content_hash, content_hash(good));
  expect_only_joint_2_limits(d);
  std::set<std::int64_t> described;
  for (const auto& desc : decoded<rdtf::description_t>(s.messages(), "DESCRIPTION", id)) described.insert(desc.revision);
  EXPECT_EQ(described, (std::set<std::int64_t>{1, 4}));
}

// A state file torn, hostile or not a file: refused with the reason in the log, and the model
// numbered above anything an earlier run can have handed out (microseconds since the epoch).
void expect_refused_state(const std::function<void(const fs::path&)>& spoil,
                          const std::function<std::string(const fs::path& state)>& logged) {
  Session s;
  const std::string id = "arm.gltf";
  const auto v1 = chain(1.0);
  write_model(s.watch, id, v1);
  auto& daemon = s.start();
  ASSERT_TRUE(s.wait_revision(id, 1, content_hash(v1)));
  ASSERT_EQ(daemon.stop(), std::optional<int>(0));
  const fs::path state = state_file_of(s.output);
  spoil(state);

  const auto before = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::system_clock::now().time_since_epoch()).count();
  std::size_t from = s.subscriber.size();
  daemon.restart();
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    for (std::size_t i = from; i < all.size(); ++i) {
      if (all[i].kind() == "DELTA") return true;
    }
    return false;
  }, 10s)) << daemon.log();
  EXPECT_TRUE(daemon.wait_log(logged(state))) << daemon.log();
  const auto d = *last_description(s.messages(), id);
  EXPECT_GT(d.revision, before) << "a number an earlier run may have handed out";
  EXPECT_LT(d.revision, std::int64_t{1} << 53);
  // Nothing known of the earlier revision: everything is new to this DELTA.
  const auto delta = deltas(s.messages(), id).back();
  EXPECT_EQ(delta.revision, d.revision);
  EXPECT_EQ(delta.previous_revision, 0);
  EXPECT_EQ(delta.total_changes, 5);

  // The new state is whole again: the next restart keeps that number.
  ASSERT_EQ(daemon.stop(), std::optional<int>(0));
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(state)));
  from = s.subscriber.size();
  daemon.restart();
  const auto again = description_since(s, from, id);
  ASSERT_TRUE(again) << daemon.log();
  EXPECT_EQ(again->revision, d.revision);
  EXPECT_EQ(again->content_hash, content_hash(v1));
}

std::function<std::string(const fs::path&)> refused_because(const std::string& reason) {
  return [reason](const fs::path& state) { return "revision state of arm.gltf ignored: " + state.string() + ": " + reason; };
}

// The state folder deleted, the outputs kept: the earlier run's numbers are not handed out again
// to other contents (they started at 1 again).
TEST(Revisions, AStateFolderDeletedBesideTheOutputsNumbersFromTheClock) {
  expect_refused_state([](const fs::path& state) { fs::remove_all(state.parent_path()); }, [](const fs::path& state) {
    return "revision state of arm.gltf missing while " + (state.parent_path().parent_path() / "arm.gltf").string() +
           " holds an earlier run's outputs";
  });
}

TEST(Revisions, ATornStateFileIsRefused) {
  expect_refused_state([](const fs::path& state) {
    const std::string text = read(state);
    write_in_place(state, text.substr(0, text.size() / 2));
  }, refused_because("not valid JSON (at byte "));
}

TEST(Revisions, AHostileStateFileIsRefused) {
  expect_refused_state([](const fs::path& state) {
    Json j = Json::parse(read(state));
    j["numbered"] = 9007199254740993ull;  // 2^53 + 1: a number that would not stay exact
    write_in_place(state, j.dump());
  }, refused_because("/: 'numbered' "));
}

TEST(Revisions, AStateFileThatIsASymlinkIsRefused) {
  expect_refused_state([](const fs::path& state) {
    const fs::path elsewhere = state.parent_path().parent_path().parent_path() / "elsewhere.json";
    fs::rename(state, elsewhere);
    fs::create_symlink(elsewhere, state);
  }, refused_because("cannot open: Too many levels of symbolic links"));
}

TEST(Revisions, AStateFileOfAnotherModelIsRefused) {
  expect_refused_state([](const fs::path& state) {
    Json j = Json::parse(read(state));
    j["model_id"] = "other.gltf";
    j["live"] = nullptr;
    write_in_place(state, j.dump());
  }, refused_because("is the state of model 'other.gltf', not of 'arm.gltf'"));
}

}  // namespace
}  // namespace rdtf::itest
