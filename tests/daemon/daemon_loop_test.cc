// rdtfd's loop stepped in-process (daemon/ports.h) with a fake clock, made-up file events, jobs
// run when the test says and a recording bus: how saves are scheduled (settle, open writers,
// changes during a conversion, back-off, removal, renames) and what goes on the bus, in
// milliseconds and without wall time. Models are real files; conversions are real.
#include <gtest/gtest.h>

#include <rdtf/description_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/model_removed_t.hpp>
#include <rdtf/status_t.hpp>

#include "daemon.h"
#include "daemon_fakes.h"
#include "support/test_support.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using fakes::FakeClock;
using fakes::FakeRunner;
using fakes::FakeWatcher;
using Kind = FileEvent::Kind;

std::string fixture(const std::string& name) { return rdtf::testing::read_file(rdtf::testing::data_dir() / "blender" / name); }

class DaemonLoop : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(tmp_ / "watch");
    watch_ = fs::canonical(tmp_ / "watch");
    out_ = tmp_.path() / "out";
  }

  void start(const std::function<void(DaemonConfig&)>& tweak = {}, ConfigLoader reload = {}) {
    DaemonConfig& config = config_;
    config.watch = {watch_};
    config.output = out_;
    config.validate = false;  // The dynamics gate has tests of its own; here: scheduling.
    config.simulate = false;
    config.urdf = false;
    config.republish_period = 0ms;
    config.settle = 50ms;
    config.max_open_wait = 5s;
    config.status_period = 1000ms;
    if (tweak) tweak(config);
    DaemonPorts ports;
    ports.clock = clock_;
    auto watcher = std::make_unique<FakeWatcher>();
    auto runner = std::make_unique<FakeRunner>();
    watcher_ = watcher.get();
    runner_ = runner.get();
    ports.watcher = std::move(watcher);
    ports.runner = std::move(runner);
    ports.bus = fakes::fake_bus(bus_);
    ports.signals = false;
    daemon_ = std::make_unique<Daemon>(config, std::move(reload), std::move(ports));
    std::string error;
    ASSERT_TRUE(daemon_->start(error)) << error;
    step();
  }

  void step() { daemon_->step(0ms); }
  void advance(Clock::duration by) {
    clock_->advance(by);
    step();
  }
  // Writes a file and reports it closed after writing, as inotify does for an in-place save.
  fs::path save(const std::string& name, const std::string& bytes) {
    const fs::path path = watch_ / name;
    rdtf::testing::write_file(path, bytes);
    notify(Kind::kWritten, path);
    return path;
  }
  // An event, read by the loop at once (as inotify's are, the moment they happen).
  void notify(Kind kind, const fs::path& path) {
    watcher_->event(kind, path);
    step();
  }
  // Runs every waiting conversion and lets the loop apply the outcomes.
  void convert() {
    runner_->run_all();
    step();
  }

  // What went out on one model's channels, as "KIND" or "KIND r<revision>", in order.
  std::vector<std::string> events(const std::string& id) {
    std::vector<std::string> out;
    const std::string prefix = "RDTF/" + id + "/";
    for (; seen_ < bus_->sent.size(); ++seen_) log_.push_back(bus_->sent[seen_]);
    for (const auto& sent : log_) {
      if (sent.channel.rfind(prefix, 0) != 0) continue;
      const std::string kind = sent.channel.substr(prefix.size());
      if (kind == "DESCRIPTION") {
        rdtf::description_t d;
        EXPECT_GE(d.decode(sent.bytes.data(), 0, static_cast<int>(sent.bytes.size())), 0);
        out.push_back(kind + " r" + std::to_string(d.revision));
      } else if (kind == "ERROR") {
        rdtf::model_error_t e;
        EXPECT_GE(e.decode(sent.bytes.data(), 0, static_cast<int>(sent.bytes.size())), 0);
        out.push_back(kind + " live r" + std::to_string(e.live_revision));
      } else if (kind == "REMOVED" || kind == "INERTIA") {
        out.push_back(kind);
      }
    }
    return out;
  }
  rdtf::status_t last_status() {
    rdtf::status_t status;
    for (const auto& sent : bus_->sent) {
      if (sent.channel == "RDTF/STATUS") status.decode(sent.bytes.data(), 0, static_cast<int>(sent.bytes.size()));
    }
    return status;
  }
  ModelPhase phase(const std::string& name) {
    const ModelRecord* record = const_cast<Registry&>(daemon_->registry()).find(watch_ / name);
    return record ? record->schedule.phase() : ModelPhase::kRemoved;
  }
  void clear_bus() {
    bus_->sent.clear();
    log_.clear();
    seen_ = 0;
  }

  rdtf::testing::TempDir tmp_;
  DaemonConfig config_;
  fs::path watch_;
  fs::path out_;
  std::shared_ptr<FakeClock> clock_ = std::make_shared<FakeClock>();
  std::shared_ptr<fakes::BusRecord> bus_ = std::make_shared<fakes::BusRecord>();
  FakeWatcher* watcher_ = nullptr;
  FakeRunner* runner_ = nullptr;
  std::unique_ptr<Daemon> daemon_;
  std::vector<fakes::Sent> log_;
  std::size_t seen_ = 0;
};

const std::vector<std::string> kRevision1{"DESCRIPTION r1", "INERTIA"};

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

TEST_F(DaemonLoop, DeletingAModelAnnouncesItRemovedAndForgetsIt) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  convert();
  fs::remove(watch_ / "arm3.glb");
  notify(Kind::kRemoved, watch_ / "arm3.glb");
  advance(50ms);
  convert();
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "REMOVED"}));
  EXPECT_EQ(daemon_->registry().all().count(watch_ / "arm3.glb"), 0u);
  advance(1s);
  EXPECT_EQ(last_status().num_models, 0);
}

TEST_F(DaemonLoop, DeleteAndRecreateWithinTheSettleIsOneSave) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  convert();
  fs::remove(watch_ / "arm3.glb");
  notify(Kind::kRemoved, watch_ / "arm3.glb");
  advance(20ms);
  save("arm3.glb", fixture("modelled_arm_no_extras.glb"));
  advance(50ms);
  ASSERT_EQ(runner_->waiting(), 1u);
  convert();
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r2", "INERTIA"}));
}

TEST_F(DaemonLoop, AModelRecreatedAfterItsConversionFoundItGoneIsConvertedNotRemoved) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  convert();
  fs::remove(watch_ / "arm3.glb");
  notify(Kind::kRemoved, watch_ / "arm3.glb");
  advance(50ms);
  runner_->start_next();                                          // Finds it gone...
  save("arm3.glb", fixture("modelled_arm_no_extras.glb"));  // ...and it is back before the outcome.
  runner_->finish();
  step();
  EXPECT_EQ(phase("arm3.glb"), ModelPhase::kSettling);
  advance(50ms);
  convert();
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r2", "INERTIA"}));
}

TEST_F(DaemonLoop, RenamingAModelIsARemovalAndANewModel) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  convert();
  fs::rename(watch_ / "arm3.glb", watch_ / "arm4.glb");
  notify(Kind::kRemoved, watch_ / "arm3.glb");  // IN_MOVED_FROM, IN_MOVED_TO.
  notify(Kind::kWritten, watch_ / "arm4.glb");
  advance(50ms);
  convert();
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "REMOVED"}));
  EXPECT_EQ(events("arm4.glb"), kRevision1);
  advance(1s);
  EXPECT_EQ(last_status().model_ids, std::vector<std::string>{"arm4.glb"});
}

TEST_F(DaemonLoop, ModelsWhoseNamesSanitiseAlikeGetDistinctChannels) {
  rdtf::testing::write_file(watch_ / "a b.glb", fixture("arm3.glb"));
  rdtf::testing::write_file(watch_ / "a_b.glb", fixture("modelled_arm.glb"));
  start();
  advance(50ms);
  convert();
  EXPECT_EQ(events("a_b.glb"), kRevision1);
  EXPECT_EQ(events("a_b.glb_2"), kRevision1);
  advance(1s);
  EXPECT_EQ(last_status().num_models, 2);
}

TEST_F(DaemonLoop, ModelsSettleIndependently) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  advance(30ms);
  save("modelled_arm.glb", fixture("modelled_arm.glb"));
  advance(20ms);
  ASSERT_EQ(runner_->waiting(), 1u);
  EXPECT_EQ(runner_->next().model_id, "arm3.glb");
  save("arm3.glb", fixture("modelled_arm_no_extras.glb"));  // A's events do not move b's deadline.
  advance(30ms);
  ASSERT_EQ(runner_->waiting(), 2u);
}

TEST_F(DaemonLoop, RequestsAreAnsweredForOneModelOrAllAndRepeatsWithinASecondOnce) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  save("modelled_arm.glb", fixture("modelled_arm.glb"));
  advance(50ms);
  convert();
  clear_bus();
  bus_->incoming.emplace_back("RDTF/REQUEST", fakes::encode_request("arm3.glb", "a"));
  bus_->incoming.emplace_back("RDTF/REQUEST", fakes::encode_request("no-such-model", "b"));
  step();
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  EXPECT_TRUE(events("modelled_arm.glb").empty());
  // Again within the second: answered once, when the second is over.
  bus_->incoming.emplace_back("RDTF/REQUEST", fakes::encode_request("arm3.glb", "a"));
  bus_->incoming.emplace_back("RDTF/REQUEST", fakes::encode_request("arm3.glb", "c"));
  step();
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  advance(1s);
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r1", "INERTIA"}));
  bus_->incoming.emplace_back("RDTF/REQUEST", fakes::encode_request("", "all"));
  step();
  EXPECT_EQ(events("modelled_arm.glb"), kRevision1);
}

TEST_F(DaemonLoop, PeriodicRepublicationSendsEveryLiveModel) {
  start([](DaemonConfig& config) { config.republish_period = 5000ms; });
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  convert();
  advance(4900ms);
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  advance(50ms);
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r1", "INERTIA"}));
}

TEST_F(DaemonLoop, AQueueOverflowRescansAndFindsWhatItsEventsWouldHaveTold) {
  start();
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  convert();
  // Events lost: a new model and a change of the known one, seen only by the rescan.
  rdtf::testing::write_file(watch_ / "modelled_arm.glb", fixture("modelled_arm.glb"));
  rdtf::testing::write_file(watch_ / "arm3.glb", fixture("modelled_arm_no_extras.glb"));
  notify(Kind::kRescan, {});
  advance(50ms);
  ASSERT_EQ(runner_->waiting(), 2u);
  convert();
  EXPECT_EQ(events("modelled_arm.glb"), kRevision1);
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r2", "INERTIA"}));
  EXPECT_EQ(daemon_->counters().rescans, 2);  // At start, and this one.
}

TEST_F(DaemonLoop, TemporariesAndTheOutputFolderNeverTriggerConversions) {
  start([&](DaemonConfig& config) { config.output = watch_ / "out"; });
  for (const char* name : {".arm3.glb.swp", "arm3.glb~", "arm3.glb.tmp", "out/arm3.glb/arm3.rdtf.gltf"}) {
    fs::create_directories((watch_ / name).parent_path());
    save(name, fixture("arm3.glb"));
  }
  advance(1s);
  EXPECT_EQ(runner_->started() + runner_->waiting(), 0u);
  EXPECT_TRUE(daemon_->registry().all().empty());
}

TEST_F(DaemonLoop, AReloadWithANewSettlePeriodAppliesItToModelsSettling) {
  start({}, [this](std::string&) -> std::optional<DaemonConfig> {
    DaemonConfig fresh = config_;
    fresh.settle = 200ms;
    return fresh;
  });
  save("arm3.glb", fixture("arm3.glb"));
  step();
  daemon_->reload_config();  // SIGHUP; its rescan counts as an event of every model.
  advance(199ms);
  EXPECT_EQ(runner_->waiting(), 0u);
  advance(1ms);
  EXPECT_EQ(runner_->waiting(), 1u);
}

}  // namespace
}  // namespace rdtf::daemon
