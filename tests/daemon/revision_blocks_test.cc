// Revision numbers reserved in blocks (daemon/registry.h, docs/daemon.md "Revision state"): a
// durable save reserves the next kReservedRevisions numbers, the saves between are not synced,
// and a start after a possible power loss numbers above the reserve, never from a `numbered` the
// power loss may have taken back.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "registry.h"
#include "support/test_support.h"

namespace rdtf::daemon {
namespace {

ModelRecord record_of(const std::string& id) {
  ModelRecord record;
  record.id = id;
  record.source = "/models/" + id;
  return record;
}

nlohmann::json state_file(const std::filesystem::path& output, const std::string& id) {
  return nlohmann::json::parse(testing::read_file(RevisionStore::file_for(output, id)));
}

// Numbers one by one, as apply_converted does: the next number, then the state saved.
void hand_out(const std::filesystem::path& output, ModelRecord& record, std::int64_t up_to) {
  while (record.numbered < up_to) {
    ++record.numbered;
    ASSERT_EQ(save_revisions(output, record, std::nullopt), "");
  }
}

TEST(RevisionBlocks, ADurableSaveReservesTheNextHundredNumbers) {
  testing::TempDir output;
  ModelRecord record = record_of("m.gltf");
  hand_out(output.path(), record, 1);
  EXPECT_EQ(record.reserved, 100);
  EXPECT_EQ(state_file(output.path(), "m.gltf")["reserved"], 100);
  // Numbers within the reserve: the file follows `numbered`, the reserve stays.
  hand_out(output.path(), record, 100);
  EXPECT_EQ(record.reserved, 100);
  EXPECT_EQ(state_file(output.path(), "m.gltf")["numbered"], 100);
  EXPECT_EQ(state_file(output.path(), "m.gltf")["reserved"], 100);
  // The first number above it reserves the next block.
  hand_out(output.path(), record, 101);
  EXPECT_EQ(record.reserved, 200);
  EXPECT_EQ(state_file(output.path(), "m.gltf")["reserved"], 200);
}

TEST(RevisionBlocks, AStartGoesOnFromNumberedWithinTheReserve) {
  testing::TempDir output;
  ModelRecord first = record_of("m.gltf");
  hand_out(output.path(), first, 7);
  ModelRecord again = record_of("m.gltf");
  EXPECT_EQ(restore_revisions(output.path(), again), "");
  EXPECT_EQ(again.numbered, 7);
  EXPECT_EQ(again.reserved, 100);
  hand_out(output.path(), again, 8);
  EXPECT_EQ(state_file(output.path(), "m.gltf")["numbered"], 8);
  EXPECT_EQ(again.reserved, 100);  // Still within the block: no durable save was needed.
}

// A state file not read for want of descriptors is neither refused nor absent: the model is not
// numbered from the clock for good (s106fd D5: a failure that passes), and the next read, with
// descriptors free, goes on from the file's numbers.
TEST(RevisionBlocks, AStateNotReadForWantOfDescriptorsIsReadAgain) {
  testing::TempDir output;
  ModelRecord first = record_of("m.gltf");
  hand_out(output.path(), first, 7);
  ModelRecord again = record_of("m.gltf");
  std::string line;
  {
    const testing::DescriptorHeadroom none(0);
    ASSERT_TRUE(none.ok());
    line = restore_revisions(output.path(), again);
  }
  EXPECT_TRUE(again.state_unread);
  EXPECT_EQ(again.numbered, 0);
  EXPECT_NE(line.find("revision state of m.gltf cannot be read now: "), std::string::npos) << line;
  EXPECT_NE(line.find("Too many open files"), std::string::npos) << line;
  EXPECT_EQ(restore_revisions(output.path(), again), "");
  EXPECT_FALSE(again.state_unread);
  EXPECT_EQ(again.numbered, 7);
  EXPECT_EQ(again.reserved, 100);
}

// After a power loss a file may be older than the numbers the bus saw (7 was saved, 8 to 50 handed
// out and their saves lost): every file numbers on from its reserve, and says so, before any model
// is restored, so that no start after it can go back below that.
TEST(RevisionBlocks, AfterAPossiblePowerLossEveryStateNumbersOnFromItsReserve) {
  testing::TempDir output;
  for (const std::string id : {"m.gltf", "sub/n.gltf", "o.glb"}) {
    ModelRecord record = record_of(id);
    hand_out(output.path(), record, id == "o.glb" ? 100 : 7);
  }
  // A file that is refused stays as it is (a start refuses it again and numbers from the clock).
  testing::write_file(RevisionStore::file_for(output.path(), "torn.gltf"), "{\"format\": ");
  int raised = -1;
  std::string why;
  ASSERT_TRUE(RevisionStore::number_from_reserves(output.path(), raised, why)) << why;
  EXPECT_EQ(raised, 2);  // o.glb had handed out its whole block already.
  EXPECT_EQ(testing::read_file(RevisionStore::file_for(output.path(), "torn.gltf")), "{\"format\": ");
  for (const std::string id : {"m.gltf", "sub/n.gltf", "o.glb"}) {
    ModelRecord record = record_of(id);
    EXPECT_EQ(restore_revisions(output.path(), record), "");
    EXPECT_EQ(record.numbered, 100) << id;
    // Its next number is above every number the lost run can have handed out, and reserves anew.
    hand_out(output.path(), record, 101);
    EXPECT_EQ(record.reserved, 200) << id;
  }
  // No state folder yet: nothing to do.
  testing::TempDir empty;
  EXPECT_TRUE(RevisionStore::number_from_reserves(empty.path(), raised, why)) << why;
  EXPECT_EQ(raised, 0);
}

TEST(RevisionBlocks, TheLiveRevisionSurvivesNumberingFromTheReserve) {
  testing::TempDir output;
  ModelRecord first = record_of("m.gltf");
  ++first.numbered;
  StoredRevision live;
  live.revision = 1;
  live.content_hash = "abc";
  live.result_digest = "def";
  ASSERT_EQ(save_revisions(output.path(), first, live), "");
  int raised = 0;
  std::string why;
  ASSERT_TRUE(RevisionStore::number_from_reserves(output.path(), raised, why)) << why;
  ModelRecord again = record_of("m.gltf");
  restore_revisions(output.path(), again);
  ASSERT_TRUE(again.restored);
  EXPECT_EQ(again.restored->revision, 1);
  EXPECT_EQ(again.restored->content_hash, "abc");
  EXPECT_EQ(again.numbered, 100);
}

}  // namespace
}  // namespace rdtf::daemon
