// rdtfd's loop stepped in-process (daemon_loop.h): models removed, recreated and renamed,
// rescans, requests and republication, and reloads, as seen on the bus.
#include <algorithm>
#include <set>

#include "daemon_loop.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Kind = FileEvent::Kind;

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

// From the 100th file whose name sanitises alike, "_N" is longer than the three characters kept
// for it: the id is shortened for it, so that every channel stays within LCM's 63 characters
// (RDTF/<id>/DESCRIPTION_CHUNK was 64 at "_100": LCM refused it, and the send queue stopped
// behind it; s100java D6).
TEST_F(DaemonLoop, AHundredAndMoreNamesThatSanitiseAlikeKeepChannelsLcmSends) {
  // 11 x 11 names of 40 characters, each sanitising to "nnn_nnn_nnn...".
  const std::string others = "_ #+!@$%^&=";
  for (const char a : others) {
    for (const char b : others) {
      std::string name(40, 'n');
      name[3] = a;
      name[7] = b;
      rdtf::testing::write_file(watch_ / (name + ".glb"), "");
    }
  }
  start();
  std::set<std::string> ids;
  for (const auto& [source, record] : daemon_->registry().all()) {
    ids.insert(record.id);
    EXPECT_LE(std::string("RDTF/" + record.id + "/DESCRIPTION_CHUNK").size(), 63u) << record.id;
  }
  EXPECT_EQ(ids.size(), daemon_->registry().all().size());
  EXPECT_EQ(ids.size(), 121u);
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
  // The first publication of both models spends the publisher's burst; a second lets it refill,
  // so what follows is answered in the step that reads the request, not paced behind it.
  advance(1s);
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
  advance(1s);  // arm3's answer just spent the burst: the rest goes out paced.
  EXPECT_EQ(events("modelled_arm.glb"), kRevision1);
}

// A model every save of which was refused has no description to send: a REQUEST for it (or for
// all) is answered with the ERROR of its last save, all a subscriber that came late can learn of
// it; it was answered with nothing. Once a revision is live, requests get that instead.
TEST_F(DaemonLoop, ARequestForAModelNeverLiveIsAnsweredWithItsLastError) {
  start();
  save("broken.glb", "{ not json");
  advance(50ms);
  convert();
  ASSERT_EQ(events("broken.glb"), (std::vector<std::string>{"ERROR live r0"}));
  advance(1s);
  clear_bus();
  bus_->incoming.emplace_back("RDTF/REQUEST", fakes::encode_request("broken.glb", "late"));
  step();
  EXPECT_EQ(events("broken.glb"), (std::vector<std::string>{"ERROR live r0"}));
  advance(1s);
  bus_->incoming.emplace_back("RDTF/REQUEST", fakes::encode_request("", "all"));
  step();
  EXPECT_EQ(events("broken.glb"), (std::vector<std::string>{"ERROR live r0", "ERROR live r0"}));
  save("broken.glb", fixture("arm3.glb"));
  advance(50ms);
  convert();
  advance(1s);
  clear_bus();
  bus_->incoming.emplace_back("RDTF/REQUEST", fakes::encode_request("broken.glb", "late"));
  step();
  EXPECT_EQ(events("broken.glb"), kRevision1);
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

// A reload that changes a conversion setting while a model converts under the old one: the result
// is not applied, and the model converts again under the new settings. It was applied and marked
// its content converted, so the reload's own rescan (which found the model busy) was the last
// word and the model kept the old density for good (s80cfg D1).
TEST_F(DaemonLoop, AResultConvertedUnderSettingsAReloadChangedIsConvertedAgain) {
  start({}, [this](std::string&) -> std::optional<DaemonConfig> {
    DaemonConfig fresh = config_;
    fresh.convert.default_density = 2000;
    return fresh;
  });
  save("arm3.glb", fixture("arm3.glb"));
  advance(50ms);
  ASSERT_EQ(runner_->waiting(), 1u);  // Converting under density 1000.
  daemon_->reload_config();
  convert();  // The job ends after the reload.
  EXPECT_TRUE(events("arm3.glb").empty());
  advance(50ms);
  ASSERT_EQ(runner_->waiting(), 1u);
  convert();
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  const ModelRecord* record = const_cast<Registry&>(daemon_->registry()).find(watch_ / "arm3.glb");
  ASSERT_TRUE(record != nullptr && record->live.has_value());
  // arm3's parts without an rdtf_density of their own take the default: 2000 now, 1000 never.
  int at_default = 0;
  for (const Link& link : record->live->robot.links) {
    for (const LinkMesh& mesh : link.meshes) {
      EXPECT_NE(mesh.density, 1000.0) << link.name;
      at_default += mesh.density == 2000.0;
    }
  }
  EXPECT_GT(at_default, 0);
}

// A reload that shortens the heartbeat takes effect at once: it waited out the old period (a
// minute here; a day's republishing period, a day: s80cfg D2).
TEST_F(DaemonLoop, AShorterStatusPeriodTakesEffectAtOnce) {
  start([](DaemonConfig& config) { config.status_period = 60s; },
        [this](std::string&) -> std::optional<DaemonConfig> {
          DaemonConfig fresh = config_;
          fresh.status_period = 100ms;
          return fresh;
        });
  const auto statuses = [&] {
    return std::count_if(bus_->sent.begin(), bus_->sent.end(), [](const auto& sent) { return sent.channel == "RDTF/STATUS"; });
  };
  const auto at_start = statuses();
  advance(1s);
  EXPECT_EQ(statuses(), at_start);
  daemon_->reload_config();
  advance(100ms);
  EXPECT_GT(statuses(), at_start);
}

// A reload to an LCM URL that cannot be opened changes nothing: the new URL and prefix were
// committed before the bus was opened, so rdtfd went on sending on its old bus under the new
// prefix, and restarted its simulations on the URL that did not open (stop 42's leftover).
TEST_F(DaemonLoop, AReloadToAnUnopenableBusKeepsTheRunningConfig) {
  std::string next_url = "udpm://239.255.76.1:7601";
  start([](DaemonConfig& config) { config.status_period = 100ms; },
        [this, &next_url](std::string&) -> std::optional<DaemonConfig> {
          DaemonConfig fresh = config_;
          fresh.lcm_url = next_url;
          fresh.channel_prefix = "NEW";
          return fresh;
        });
  bus_->unopenable_url = next_url;
  const auto on = [&](const std::string& channel) {
    return std::count_if(bus_->sent.begin(), bus_->sent.end(), [&](const auto& sent) { return sent.channel == channel; });
  };
  daemon_->reload_config();
  clear_bus();
  advance(200ms);
  EXPECT_GT(on("RDTF/STATUS"), 0);
  EXPECT_EQ(on("NEW/STATUS"), 0);
  EXPECT_EQ(bus_->opened, 1);
  // The same reload once the URL opens: the new bus, under the new prefix.
  next_url = "udpm://239.255.76.2:7602";
  daemon_->reload_config();
  clear_bus();
  advance(200ms);
  EXPECT_EQ(bus_->opened, 2);
  EXPECT_GT(on("NEW/STATUS"), 0);
  EXPECT_EQ(on("RDTF/STATUS"), 0);
}

// A reload that restarts the live simulation while its LCM cannot open (the robot's network not up
// yet, no descriptor free; here LCM's file provider, whose folder is not there) left rdtfd without
// live states until the next reload or restart (stop 48's leftover). Now it is tried again after
// 1 s, then 2 s, and runs once it opens. (The file provider keeps the test off any network; the
// live simulation only publishes, and with no model nothing.)
TEST_F(DaemonLoop, ALiveSimulationThatCannotOpenAfterAReloadIsTriedAgain) {
  const std::filesystem::path folder = tmp_.path() / "bus";
  std::filesystem::create_directories(folder);
  double rate = 100;
  start(
      [&](DaemonConfig& config) {
        config.simulate = true;
        config.lcm_url = "file://" + (folder / "states.lcm").string() + "?mode=w";
      },
      [this, &rate](std::string&) -> std::optional<DaemonConfig> {
        DaemonConfig fresh = config_;
        fresh.state_rate_hz = rate;  // A setting that restarts the live simulation.
        return fresh;
      });
  ASSERT_TRUE(daemon_->simulating());
  std::filesystem::remove_all(folder);
  rate = 50;
  daemon_->reload_config();
  EXPECT_FALSE(daemon_->simulating());
  advance(999ms);
  EXPECT_FALSE(daemon_->simulating());
  advance(1ms);  // The first attempt: the folder is still not there.
  EXPECT_FALSE(daemon_->simulating());
  std::filesystem::create_directories(folder);
  advance(1999ms);
  EXPECT_FALSE(daemon_->simulating());
  advance(1ms);
  EXPECT_TRUE(daemon_->simulating());
}

}  // namespace
}  // namespace rdtf::daemon
