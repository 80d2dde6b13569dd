// The revision state's text: what state_to_json writes, state_from_json reads back exactly, and
// anything else it refuses with a reason.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>

#include <nlohmann/json.hpp>

#include "rdtf/atomic_file.h"
#include "revision_store.h"

namespace rdtf::daemon {
namespace {

ModelState sample() {
  ModelState state;
  state.model_id = "sub/arm.gltf";
  state.source = "/models/sub/arm.gltf";
  state.numbered = 7;
  StoredRevision live;
  live.revision = 5;
  live.content_hash = "abc";
  live.result_digest = "def";
  LinkFacts link;
  link.name = "base";
  link.urdf_name = "base";
  link.mass = 0.1 + 0.2;  // Not a short decimal: must come back bit for bit.
  link.volume = 1e-300;
  link.center_of_mass[1] = -0.0;
  link.inertia[5] = 1.0 / 3.0;
  link.geometry = "0123";
  live.facts.links.push_back(link);
  JointFacts joint;
  joint.name = "j";
  joint.urdf_name = "j";
  joint.type = "revolute";
  joint.parent = "base";
  joint.child = "tip";
  joint.origin[0] = std::nextafter(1.0, 2.0);
  joint.has_limits = true;
  joint.has_range = true;
  joint.limits[1] = 3.141592653589793;
  live.facts.joints.push_back(joint);
  state.live = live;
  return state;
}

TEST(RevisionStore, StateComesBackExactly) {
  const ModelState state = sample();
  std::string why;
  const auto back = state_from_json(state_to_json(state), why);
  ASSERT_TRUE(back) << why;
  EXPECT_EQ(back->model_id, state.model_id);
  EXPECT_EQ(back->source, state.source);
  EXPECT_EQ(back->numbered, 7);
  EXPECT_EQ(back->reserved, 7);  // Never below `numbered`, even when the state says less.
  ASSERT_TRUE(back->live);
  EXPECT_EQ(back->live->revision, 5);
  EXPECT_EQ(back->live->content_hash, "abc");
  EXPECT_EQ(back->live->result_digest, "def");
  // Exactly the same facts: diffing them finds nothing.
  EXPECT_TRUE(diff_robots(state.live->facts, back->live->facts).empty());
  EXPECT_EQ(back->live->facts.links[0].mass, 0.1 + 0.2);
  EXPECT_EQ(back->live->facts.joints[0].origin[0], std::nextafter(1.0, 2.0));
  EXPECT_TRUE(back->live->facts.joints[0].has_range);
}

// A source path that is not UTF-8 comes back byte for byte (it came back with U+FFFD, never matched
// the file again, and every restart numbered the model anew with a DELTA of everything "added");
// the file stays valid JSON, a UTF-8 path stays readable text.
TEST(RevisionStore, ASourceThatIsNotUtf8ComesBackByteForByte) {
  ModelState state = sample();
  state.source = "/models/a\xff\xfe.gltf";
  const std::string text = state_to_json(state);
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j["source"], nlohmann::json({{"hex", "2f6d6f64656c732f61fffe2e676c7466"}}));
  std::string why;
  const auto back = state_from_json(text, why);
  ASSERT_TRUE(back) << why;
  EXPECT_EQ(back->source, state.source);
  EXPECT_EQ(nlohmann::json::parse(state_to_json(sample()))["source"], "/models/sub/arm.gltf");
  // A hex that is not whole bytes is refused with its reason.
  std::string bad = text;
  bad.replace(bad.find("fffe"), 4, "fff");
  EXPECT_FALSE(state_from_json(bad, why));
  EXPECT_NE(why.find("'source'"), std::string::npos) << why;
}

// Whether a joint's limits have a range is kept (it was lost, and after a restart every DELTA
// then said the limits of every joint with a range had changed); a file written before the flag
// existed reads as "a range wherever there were limits", which was true then.
TEST(RevisionStore, AJointsRangeComesBackAndOldFilesHadOne) {
  ModelState state = sample();
  state.live->facts.joints[0].has_range = false;  // Effort and speed limits alone.
  std::string why;
  auto back = state_from_json(state_to_json(state), why);
  ASSERT_TRUE(back) << why;
  EXPECT_FALSE(back->live->facts.joints[0].has_range);
  EXPECT_TRUE(diff_robots(state.live->facts, back->live->facts).empty());

  Json old = Json::parse(state_to_json(sample()));
  bool erased = false;
  for (Json& joint : old["live"]["joints"]) erased = joint.erase("has_range") > 0 || erased;
  ASSERT_TRUE(erased) << old.dump();
  back = state_from_json(old.dump(), why);
  ASSERT_TRUE(back) << why;
  EXPECT_TRUE(back->live->facts.joints[0].has_range);
}

TEST(RevisionStore, AnythingElseIsRefusedWithItsReason) {
  const std::string good = state_to_json(sample());
  auto refused = [](const std::string& text) {
    std::string why;
    EXPECT_FALSE(state_from_json(text, why)) << text;
    return why;
  };
  auto edited = [&](const std::function<void(nlohmann::json&)>& edit) {
    auto j = nlohmann::json::parse(good);
    edit(j);
    return refused(j.dump());
  };
  EXPECT_EQ(refused(good.substr(0, good.size() / 2)).rfind("not valid JSON (at byte ", 0), 0u);
  EXPECT_EQ(refused("[]"), "not a JSON object");
  EXPECT_EQ(edited([](auto& j) { j["format"] = "rdtfd-revisions 2"; }), "/format is not 'rdtfd-revisions 1'");
  EXPECT_EQ(edited([](auto& j) { j.erase("numbered"); }), "/: no 'numbered'");
  EXPECT_EQ(edited([](auto& j) { j["numbered"] = -1; }), "/: 'numbered' -1 is out of range");
  EXPECT_EQ(edited([](auto& j) { j["numbered"] = 1.5; }), "/: 'numbered' has the wrong type");
  EXPECT_EQ(edited([](auto& j) { j["numbered"] = 9007199254740993ull; }),
            "/: 'numbered' 9007199254740993 is out of range");
  EXPECT_EQ(edited([](auto& j) { j["numbered"] = 4; }), "/live/revision 5 is above /numbered 4");
  EXPECT_EQ(edited([](auto& j) { j["reserved"] = 6; }), "/reserved 6 is below /numbered 7");
  EXPECT_EQ(edited([](auto& j) { j["reserved"] = -1; }), "/: 'reserved' -1 is out of range");
  EXPECT_EQ(edited([](auto& j) { j["reserved"] = "many"; }), "/: 'reserved' has the wrong type");
  EXPECT_EQ(edited([](auto& j) { j["live"]["revision"] = 0; }), "/live: 'revision' 0 is out of range");
  EXPECT_EQ(edited([](auto& j) { j["live"]["links"][0]["inertia"] = {1, 2}; }),
            "/live/links/0: 'inertia' needs 6 numbers");
  EXPECT_EQ(edited([](auto& j) { j["live"]["links"][0]["mass"] = "heavy"; }),
            "/live/links/0: 'mass' has the wrong type");
  EXPECT_EQ(edited([](auto& j) { j["live"]["joints"][0]["axis"][2] = nullptr; }),
            "/live/joints/0/axis is not a number");
  EXPECT_EQ(edited([](auto& j) { j["live"]["joints"][0].erase("child"); }), "/live/joints/0: no 'child'");
}

TEST(RevisionStore, TheReserveComesBackAndAFileWithoutOneReadsAsNumbered) {
  ModelState state = sample();
  state.reserved = 106;
  std::string why;
  const auto back = state_from_json(state_to_json(state), why);
  ASSERT_TRUE(back) << why;
  EXPECT_EQ(back->reserved, 106);
  // The files of versions before the reserve: no number above `numbered` was handed out.
  auto j = nlohmann::json::parse(state_to_json(state));
  j.erase("reserved");
  const auto earlier = state_from_json(j.dump(), why);
  ASSERT_TRUE(earlier) << why;
  EXPECT_EQ(earlier->numbered, 7);
  EXPECT_EQ(earlier->reserved, 7);
}

TEST(RevisionStore, TheFloorIsTheClockInMicroseconds) {
  const auto now = std::chrono::duration_cast<std::chrono::microseconds>(
                       std::chrono::system_clock::now().time_since_epoch()).count();
  const auto floor = revision_floor_now();
  EXPECT_GE(floor, now);
  EXPECT_LT(floor, std::int64_t{1} << 53);
}

TEST(RevisionStore, FileNamesAreNoContentAddressedNames) {
  const auto file = RevisionStore::file_for("/out", "sub/robot.0123456789abcdef.gltf");
  EXPECT_EQ(file.parent_path(), "/out/.rdtfd-state");
  EXPECT_FALSE(is_content_addressed_name(file.filename().string())) << file;
  EXPECT_NE(file, RevisionStore::file_for("/out", "sub/robot.glb"));
}

}  // namespace
}  // namespace rdtf::daemon
