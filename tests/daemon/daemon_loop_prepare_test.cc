// Converting while settling (`convert_while_settling`, docs/daemon.md): rdtfd's loop stepped
// in-process (daemon_loop.h). A save is converted and its outputs staged during the settle period;
// at its end they are committed and published, unless a file changed after the job read it.
#include "daemon_loop.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

class DaemonPrepared : public DaemonLoop {
 protected:
  void start_preparing() {
    start([](DaemonConfig& config) { config.convert_while_settling = true; });
  }
  // Stage folders (".stage.<pid>-<random>.tmp") in a model's output folder.
  std::size_t stages(const std::string& id) const {
    std::size_t n = 0;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(out_ / id, ec)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind(".stage.", 0) == 0) ++n;
    }
    return n;
  }
  bool exists(const fs::path& path) const { return fs::exists(path); }
  std::string live_hash(const std::string& id) const {
    const ModelRecord* record = daemon_->registry().find_id(id);
    return record && record->live ? record->live->content_hash : std::string();
  }
};

TEST_F(DaemonPrepared, ASaveIsConvertedWhileItSettlesAndPublishedWhenItHasSettled) {
  start_preparing();
  save("arm3.glb", fixture("arm3.glb"));
  ASSERT_EQ(runner_->waiting(), 1u) << "no conversion started at the save";
  runner_->run_next();
  step();
  // Converted and staged: nothing in place, nothing published before the settle period is over.
  EXPECT_TRUE(events("arm3.glb").empty());
  EXPECT_FALSE(exists(out_ / "arm3.glb" / "arm3.rdtf.gltf"));
  EXPECT_EQ(stages("arm3.glb"), 1u);
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kSettling);
  advance(49ms);
  EXPECT_EQ(runner_->waiting(), 0u);
  EXPECT_TRUE(events("arm3.glb").empty());
  advance(1ms);
  // The deadline: one job moves the staged outputs into place; no conversion again.
  ASSERT_EQ(runner_->waiting(), 1u);
  EXPECT_TRUE(runner_->next().commit != nullptr);
  convert();
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  EXPECT_TRUE(exists(out_ / "arm3.glb" / "arm3.rdtf.gltf"));
  EXPECT_EQ(stages("arm3.glb"), 0u);
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kLive);
  EXPECT_EQ(daemon_->counters().conversions, 1);
  EXPECT_EQ(runner_->started(), 2u);
}

TEST_F(DaemonPrepared, TheLiveRevisionsFilesStayUntilTheDeadline) {
  start_preparing();
  save("arm3.glb", fixture("arm3.glb"));
  convert();
  advance(50ms);
  convert();
  ASSERT_EQ(events("arm3.glb"), kRevision1);
  const fs::path live = out_ / "arm3.glb" / "arm3.rdtf.gltf";
  const std::string r1 = rdtf::testing::read_file(live);
  // A second save: a different generator string, so another document.
  std::string glb = fixture("arm3.glb");
  const auto at = glb.find("Khronos glTF Blender I/O");
  ASSERT_NE(at, std::string::npos);
  glb[at] = 'k';
  save("arm3.glb", glb);
  convert();  // Prepared and staged.
  EXPECT_EQ(rdtf::testing::read_file(live), r1) << "a prepared job replaced the live revision's file";
  EXPECT_EQ(stages("arm3.glb"), 1u);
  advance(50ms);
  convert();
  EXPECT_NE(rdtf::testing::read_file(live), r1);
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r2", "INERTIA"}));
}

TEST_F(DaemonPrepared, ASaveAfterThePreparedResultDropsItAndTheLastContentIsPublished) {
  start_preparing();
  const std::string gltf = fixture("two_cylinder.gltf");
  save("two_cylinder.bin", fixture("two_cylinder.bin"));
  save("two_cylinder.gltf", gltf);
  convert();  // Prepared: staged, held.
  EXPECT_EQ(stages("two_cylinder.gltf"), 1u);
  advance(20ms);
  save("two_cylinder.gltf", gltf + " ");
  // The held result and its stage are gone; the new content is being prepared.
  EXPECT_EQ(stages("two_cylinder.gltf"), 0u);
  ASSERT_EQ(runner_->waiting(), 1u);
  EXPECT_FALSE(runner_->next().commit);
  convert();
  advance(49ms);
  EXPECT_TRUE(events("two_cylinder.gltf").empty());
  advance(1ms);
  convert();
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
  EXPECT_EQ(daemon_->counters().conversions, 1);
  // What was published is the second save: saved again, it is unchanged content.
  const std::string published = live_hash("two_cylinder.gltf");
  save("two_cylinder.gltf", gltf + " ");
  convert();
  advance(50ms);
  convert();
  EXPECT_EQ(daemon_->counters().skipped_unchanged, 1);
  EXPECT_EQ(live_hash("two_cylinder.gltf"), published);
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
}

TEST_F(DaemonPrepared, ABrokenSaveReadBeforeTheNextSaveIsDroppedWithoutAnError) {
  start_preparing();
  save("arm3.glb", "{ not json");
  runner_->start_next();  // Reads the broken content.
  save("arm3.glb", fixture("arm3.glb"));  // Written while that job runs.
  runner_->finish();
  step();
  // The broken content's rejection is stale: nothing said of it; the good save is prepared.
  EXPECT_TRUE(events("arm3.glb").empty());
  ASSERT_EQ(runner_->waiting(), 1u);
  convert();
  advance(50ms);
  convert();
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  EXPECT_EQ(daemon_->counters().rejections, 0);
}

TEST_F(DaemonPrepared, ABrokenSaveThatSettlesIsReportedAtTheDeadline) {
  start_preparing();
  save("arm3.glb", "{ not json");
  convert();
  EXPECT_TRUE(events("arm3.glb").empty());  // Not before the deadline.
  advance(50ms);
  EXPECT_EQ(runner_->waiting(), 0u);  // Nothing to move into place: the rejection applies at once.
  EXPECT_EQ(events("arm3.glb"), std::vector<std::string>{"ERROR live r0"});
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kIdle);
  EXPECT_EQ(daemon_->counters().rejections, 1);
}

TEST_F(DaemonPrepared, AJobStillRunningAtTheDeadlineIsCommittedWhenItEnds) {
  start_preparing();
  save("arm3.glb", fixture("arm3.glb"));
  runner_->start_next();
  advance(50ms);
  EXPECT_EQ(runner_->waiting(), 0u) << "a second conversion started beside the running one";
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kConverting);
  runner_->finish();
  step();
  ASSERT_EQ(runner_->waiting(), 1u);
  EXPECT_TRUE(runner_->next().commit != nullptr);
  convert();
  EXPECT_EQ(events("arm3.glb"), kRevision1);
}

TEST_F(DaemonPrepared, AStaleJobAtTheDeadlineIsFollowedByAConversionOfWhatSettled) {
  start_preparing();
  const std::string gltf = fixture("two_cylinder.gltf");
  save("two_cylinder.bin", fixture("two_cylinder.bin"));
  save("two_cylinder.gltf", gltf);
  runner_->start_next();
  advance(10ms);
  save("two_cylinder.gltf", gltf + "  ");
  advance(50ms);  // Settled while the stale job still runs: no second job beside it.
  EXPECT_EQ(runner_->waiting(), 0u);
  runner_->finish();
  step();
  ASSERT_EQ(runner_->waiting(), 1u);  // A conversion of the settled content, at once.
  EXPECT_FALSE(runner_->next().commit);
  EXPECT_FALSE(runner_->next().prepare);
  convert();
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
  EXPECT_EQ(daemon_->counters().conversions, 1);
}

TEST_F(DaemonPrepared, AGltfAndItsBinWrittenTogetherGiveOnePreparedJob) {
  start_preparing();
  // Both events in one turn of the loop, as inotify delivers a save of both files.
  rdtf::testing::write_file(watch_ / "two_cylinder.gltf", fixture("two_cylinder.gltf"));
  rdtf::testing::write_file(watch_ / "two_cylinder.bin", fixture("two_cylinder.bin"));
  watcher_->event(Kind::kWritten, watch_ / "two_cylinder.gltf");
  watcher_->event(Kind::kWritten, watch_ / "two_cylinder.bin");
  step();
  EXPECT_EQ(runner_->waiting(), 1u);
  convert();
  advance(50ms);
  convert();
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
  EXPECT_EQ(runner_->started(), 2u);  // The prepared conversion and its commit.
}

}  // namespace
}  // namespace rdtf::daemon
