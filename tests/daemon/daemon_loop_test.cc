// rdtfd's loop stepped in-process (daemon_loop.h): how saves are scheduled (the settle, bursts,
// open writers, changes during a conversion, skips, the back-off of failed writes) and what goes
// on the bus, in milliseconds and without wall time.
#include "daemon_loop.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Kind = FileEvent::Kind;

TEST_F(DaemonLoop, InitialScanConvertsEachModelOnceAfterTheSettle) {
  rdtf::testing::write_file(watch_ / "arm3.glb", fixture("arm3.glb"));
  rdtf::testing::write_file(watch_ / "two_cylinder.gltf", fixture("two_cylinder.gltf"));
  rdtf::testing::write_file(watch_ / "two_cylinder.bin", fixture("two_cylinder.bin"));
  start();
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kSettling);
  advance(49ms);
  EXPECT_EQ(runner_->waiting(), 0u);
  advance(1ms);
  EXPECT_EQ(runner_->waiting(), 2u);
  EXPECT_EQ(last_status().pending, 2);
  convert();
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
  EXPECT_EQ(phase("two_cylinder.gltf"), ModelPhase::kLive);
  advance(1s);  // The next heartbeat.
  EXPECT_EQ(last_status().pending, 0);
  EXPECT_EQ(last_status().conversions, 2);
  EXPECT_EQ(last_status().num_models, 2);
}

TEST_F(DaemonLoop, ABurstOfSavesGivesOneConversionOfTheLastContent) {
  start();
  const std::string gltf = fixture("two_cylinder.gltf");
  save("two_cylinder.bin", fixture("two_cylinder.bin"));
  // 100 saves 10 ms apart: never quiet for the settle period.
  for (int i = 0; i < 100; ++i) {
    save("two_cylinder.gltf", gltf + std::string(static_cast<std::size_t>(i), ' '));
    advance(10ms);
    ASSERT_EQ(runner_->waiting(), 0u) << "converted during the burst, at save " << i;
  }
  advance(40ms);
  ASSERT_EQ(runner_->waiting(), 1u);
  convert();
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
  EXPECT_EQ(daemon_->counters().conversions, 1);
  // The content converted is the last one saved (99 spaces appended): saved again, it is skipped.
  save("two_cylinder.gltf", gltf + std::string(99, ' '));
  advance(50ms);
  convert();
  EXPECT_EQ(daemon_->counters().skipped_unchanged, 1);
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
}

TEST_F(DaemonLoop, TwoBurstsWithAPauseGiveOneConversionPerPauseEachOfTheLastSaveBeforeIt) {
  start();
  const std::string gltf = fixture("two_cylinder.gltf");
  auto version = [&](int i) { return gltf + std::string(static_cast<std::size_t>(i), ' '); };
  save("two_cylinder.bin", fixture("two_cylinder.bin"));
  save("two_cylinder.gltf", version(0));
  advance(50ms);
  convert();  // Revision 1.
  // Saves 1..100 every 10 ms, a pause of a second after the 50th.
  for (int i = 1; i <= 100; ++i) {
    save("two_cylinder.gltf", version(i));
    advance(i == 50 ? 1s : 10ms);
    convert();
  }
  advance(50ms);
  convert();
  EXPECT_EQ(events("two_cylinder.gltf"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r2",
                                                                    "INERTIA", "DESCRIPTION r3", "INERTIA"}));
  EXPECT_EQ(runner_->started(), 3u);
  // Revision 2 was save 50 and revision 3 save 100: saved again, each is unchanged content.
  const ModelRecord* record = daemon_->registry().find_id("two_cylinder.gltf");
  ASSERT_NE(record, nullptr);
  const std::string last = record->last_hash;
  save("two_cylinder.gltf", version(100));
  advance(50ms);
  convert();
  EXPECT_EQ(daemon_->counters().skipped_unchanged, 1);
  EXPECT_EQ(record->last_hash, last);
  EXPECT_EQ(daemon_->counters().rejections, 0);
}

TEST_F(DaemonLoop, AFileStillOpenForWritingHoldsItsModelUntilClosed) {
  start();
  const fs::path model = watch_ / "arm3.glb";
  rdtf::testing::write_file(model, fixture("arm3.glb").substr(0, 100));
  watcher_->event(Kind::kModified, model);  // Written, not closed: a save in progress.
  step();
  advance(2s);
  EXPECT_EQ(runner_->waiting(), 0u);
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kSettling);
  rdtf::testing::write_file(model, fixture("arm3.glb"));
  watcher_->event(Kind::kWritten, model);  // Closed.
  step();
  advance(49ms);
  EXPECT_EQ(runner_->waiting(), 0u);
  advance(1ms);
  EXPECT_EQ(runner_->waiting(), 1u);
  convert();
  EXPECT_EQ(events("arm3.glb"), kRevision1);  // One conversion, of the whole file.
}

TEST_F(DaemonLoop, AWriterThatNeverClosesHoldsItsModelForMaxOpenWaitOnly) {
  start([](DaemonConfig& config) { config.max_open_wait = 1000ms; });
  const fs::path model = save("arm3.glb", fixture("arm3.glb"));
  watcher_->event(Kind::kModified, model);  // An mmap writer: modified, never closed.
  step();
  advance(999ms);
  EXPECT_EQ(runner_->waiting(), 0u);
  // At max_open_wait the writer still counts (open for at most that long): one more settle.
  advance(1ms);
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kWaitingForWriter);
  advance(49ms);
  EXPECT_EQ(runner_->waiting(), 0u);
  advance(1ms);
  EXPECT_EQ(runner_->waiting(), 1u);
}

TEST_F(DaemonLoop, TheFirstExportOfAModelWaitsForItsBinStillBeingWritten) {
  start();
  // Blender writes the .gltf, then the .bin in place: the model names a file not yet known.
  save("two_cylinder.gltf", fixture("two_cylinder.gltf"));
  const fs::path bin = watch_ / "two_cylinder.bin";
  rdtf::testing::write_file(bin, fixture("two_cylinder.bin").substr(0, 64));
  notify(Kind::kModified, bin);
  advance(50ms);
  // Settled, but a file in its folder is open: it waits for the writer, a settle at a time.
  EXPECT_EQ(runner_->waiting(), 0u);
  EXPECT_EQ(phase("two_cylinder.gltf"), ModelPhase::kSettling);
  advance(1s);
  EXPECT_EQ(runner_->waiting(), 0u);
  rdtf::testing::write_file(bin, fixture("two_cylinder.bin"));
  notify(Kind::kWritten, bin);
  advance(50ms);
  ASSERT_EQ(runner_->waiting(), 1u);
  convert();
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
}

TEST_F(DaemonLoop, ASettledModelWithAWriterOpenOnItsBinWaitsForTheWriter) {
  rdtf::testing::write_file(watch_ / "two_cylinder.gltf", fixture("two_cylinder.gltf"));
  rdtf::testing::write_file(watch_ / "two_cylinder.bin", fixture("two_cylinder.bin"));
  start();
  advance(50ms);
  convert();
  save("two_cylinder.gltf", fixture("two_cylinder.gltf") + " ");
  watcher_->event(Kind::kModified, watch_ / "two_cylinder.bin");  // Its .bin is being rewritten.
  step();
  // The .bin's write counts as an event of its model, still open: it holds it up to max_open_wait.
  advance(5s - 1ms);
  EXPECT_EQ(runner_->waiting(), 0u);
  notify(Kind::kWritten, watch_ / "two_cylinder.bin");
  advance(50ms);
  EXPECT_EQ(runner_->waiting(), 1u);
}

TEST_F(DaemonLoop, AChangeDuringAConversionConvertsOnceMoreAfterIt) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  ASSERT_EQ(runner_->waiting(), 1u);
  runner_->start_next();  // A worker reads the first content...
  save("arm3.glb", fixture("modelled_arm_no_extras.glb"));  // ...and it is saved again.
  advance(50ms);
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kConvertAgain);
  EXPECT_EQ(runner_->waiting(), 0u);  // One job per model at a time.
  runner_->finish();                  // The first content becomes revision 1...
  step();
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kSettling);
  advance(50ms);  // ...and the second is converted a settle after.
  ASSERT_EQ(runner_->waiting(), 1u);
  convert();
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r2", "INERTIA"}));
}

TEST_F(DaemonLoop, ABrokenSaveSupersededDuringItsConversionPublishesNoError) {
  start();
  save("arm3.glb", "not a model");
  advance(50ms);
  runner_->start_next();  // Reads the broken content.
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);  // The good save settles while the broken one converts.
  runner_->finish();
  step();
  EXPECT_TRUE(events("arm3.glb").empty());
  advance(50ms);
  convert();
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  EXPECT_EQ(daemon_->counters().rejections, 1);
}

TEST_F(DaemonLoop, ABrokenSaveIsPublishedAndTheGoodRevisionStaysLiveAndAnswered) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  convert();
  save("arm3.glb", "{ not json");
  advance(50ms);
  convert();
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "ERROR live r1"}));
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kLive);
  bus_->incoming.emplace_back("RDTF/REQUEST", fakes::encode_request("arm3.glb", "test"));
  step();
  EXPECT_EQ(events("arm3.glb"),
            (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "ERROR live r1", "DESCRIPTION r1", "INERTIA"}));
}

TEST_F(DaemonLoop, SavingTheSameContentAgainIsSkipped) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  convert();
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  ASSERT_EQ(runner_->waiting(), 1u);
  convert();
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  EXPECT_EQ(daemon_->counters().skipped_unchanged, 1);
}

TEST_F(DaemonLoop, ABinSavedIsAnEventOfItsModel) {
  rdtf::testing::write_file(watch_ / "two_cylinder.gltf", fixture("two_cylinder.gltf"));
  rdtf::testing::write_file(watch_ / "two_cylinder.bin", fixture("two_cylinder.bin"));
  start();
  advance(50ms);
  convert();
  save("two_cylinder.bin", fixture("two_cylinder.bin"));  // The same bytes: converted, skipped.
  EXPECT_EQ(phase("two_cylinder.gltf"), ModelPhase::kSettling);
  advance(50ms);
  ASSERT_EQ(runner_->waiting(), 1u);
  convert();
  EXPECT_EQ(daemon_->counters().skipped_unchanged, 1);
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
}

// A .gltf cut short names no .bin, so its rejection left the model with no known files; the save
// that repaired it wrote the .bin just after the .gltf (Blender), and that event reached no model:
// the repair was converted with the old .bin, found unchanged, and the new .bin never published.
TEST_F(DaemonLoop, ABinSavedRightAfterTheRepairOfABrokenGltfIsAnEventOfItsModel) {
  rdtf::testing::write_file(watch_ / "two_cylinder.gltf", fixture("two_cylinder.gltf"));
  rdtf::testing::write_file(watch_ / "two_cylinder.bin", fixture("two_cylinder.bin"));
  start();
  advance(50ms);
  convert();
  save("two_cylinder.gltf", fixture("two_cylinder.gltf").substr(0, 100));  // Cut short.
  advance(50ms);
  convert();
  ASSERT_EQ(daemon_->counters().rejections, 1);
  // The .bin alone (a conversion prepared from the repaired .gltf while it settled has read the
  // old one: only this event tells the model that it is stale).
  std::string bin = fixture("two_cylinder.bin");
  bin[bin.size() / 2] = static_cast<char>(bin[bin.size() / 2] ^ 1);
  save("two_cylinder.bin", bin);
  EXPECT_EQ(phase("two_cylinder.gltf"), ModelPhase::kSettling);
  save("two_cylinder.gltf", fixture("two_cylinder.gltf"));
  advance(50ms);
  convert();
  EXPECT_EQ(events("two_cylinder.gltf"),
            (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "ERROR live r1", "DESCRIPTION r2", "INERTIA"}));
}

TEST_F(DaemonLoop, AFullDiskIsReportedOnceAndRetriedWithABackOffUntilItWorks) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  runner_->run_next(/*disk_full=*/true);
  step();
  EXPECT_EQ(events("arm3.glb"), std::vector<std::string>{"ERROR live r0"});
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kRetryAfter);
  // 200 ms, then 400 ms, then 800 ms, each followed by the settle; one ERROR for the outage.
  for (const auto delay : {200ms, 400ms}) {
    advance(delay - 1ms);
    EXPECT_EQ(phase("arm3.glb"), ModelPhase::kRetryAfter);
    advance(1ms);
    EXPECT_EQ(phase("arm3.glb"), ModelPhase::kSettling);
    advance(49ms);
    EXPECT_EQ(runner_->waiting(), 0u);
    advance(1ms);
    ASSERT_EQ(runner_->waiting(), 1u);
    runner_->run_next(true);
    step();
  }
  EXPECT_EQ(events("arm3.glb"), std::vector<std::string>{"ERROR live r0"});
  advance(799ms);
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kRetryAfter);
  advance(1ms);
  advance(50ms);
  ASSERT_EQ(runner_->waiting(), 1u);
  convert();  // Space came back.
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"ERROR live r0", "DESCRIPTION r1", "INERTIA"}));
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kLive);
}

// A model whose revision state could not be opened for want of descriptors (EMFILE, not ENOENT)
// when it was found was taken for one with a refused state and numbered from the clock for good
// (s106fd D5). Now the state is read again when its conversion starts; still unreadable then, the
// job reads and writes nothing and is retried like a full disk's, and the model goes on from its
// state's numbers (7 here: revision 8). Read after the job had written its outputs, a state
// absent would have taken them for an earlier run's and numbered from the clock all the same.
// Both ways of starting a conversion: at the deadline, and while settling (rdtfd's default),
// where no prepared job starts until the state is read.
class DaemonStateUnread : public DaemonLoop, public ::testing::WithParamInterface<bool> {};

TEST_P(DaemonStateUnread, ARevisionStateNotReadForWantOfDescriptorsIsReadBeforeNumbering) {
  const bool while_settling = GetParam();
  ModelRecord earlier;
  earlier.id = "arm3.glb";
  earlier.source = watch_ / "arm3.glb";
  earlier.numbered = 7;
  ASSERT_EQ(save_revisions(out_, earlier, std::nullopt), "");
  // That run stopped cleanly: the start numbers on from 7, not from the end of its reserve.
  rdtf::testing::write_file(RevisionStore::folder_for(out_) / "clean-stop", "");
  start([&](DaemonConfig& config) { config.convert_while_settling = while_settling; });
  // The same steps once with descriptors free: under the sanitizers, UBSan's vptr check needs a
  // pipe at the first call through each vtable (docs/notes/ubsan-descriptors.md), so every call
  // the starved steps make is made here first.
  save("warm.glb", fixture("arm3.glb"));
  advance(50ms);
  convert();
  convert();  // While settling: the prepared job, then the commit.
  ASSERT_EQ(events("warm.glb"), kRevision1);
  rdtf::testing::write_file(watch_ / "arm3.glb", fixture("arm3.glb"));
  {
    const rdtf::testing::DescriptorHeadroom none(0);
    ASSERT_TRUE(none.ok());
    notify(Kind::kWritten, watch_ / "arm3.glb");  // Registered: its state file looked for.
  }
  const ModelRecord* record = const_cast<Registry&>(daemon_->registry()).find(watch_ / "arm3.glb");
  ASSERT_NE(record, nullptr);
  EXPECT_EQ(record->id, "arm3.glb");
  EXPECT_TRUE(record->state_unread);
  EXPECT_EQ(runner_->waiting(), 0u);  // Nothing prepared while its numbers are unknown.
  {
    const rdtf::testing::DescriptorHeadroom none(0);
    ASSERT_TRUE(none.ok());
    advance(50ms);  // Settled: the job starts, its state still unreadable.
  }
  ASSERT_EQ(runner_->waiting(), 1u);
  convert();
  EXPECT_EQ(events("arm3.glb"), std::vector<std::string>{"ERROR live r0"});
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kRetryAfter);
  EXPECT_FALSE(std::filesystem::exists(out_ / "arm3.glb"));  // Nothing written.
  advance(200ms);
  advance(50ms);
  convert();
  convert();
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"ERROR live r0", "DESCRIPTION r8", "INERTIA"}));
  EXPECT_FALSE(const_cast<Registry&>(daemon_->registry()).find(watch_ / "arm3.glb")->state_unread);
}

INSTANTIATE_TEST_SUITE_P(BothWays, DaemonStateUnread, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& param_info) {
                           return param_info.param ? "WhileSettling" : "AtTheDeadline";
                         });

}  // namespace
}  // namespace rdtf::daemon
