// The fixture of the in-process loop tests (daemon_loop*_test.cc): rdtfd's loop stepped with a
// fake clock, made-up file events, jobs run when the test says and a recording bus
// (daemon_fakes.h). Models are real files in a temporary folder; conversions are real.
#pragma once

#include <gtest/gtest.h>

#include <rdtf/description_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/model_removed_t.hpp>
#include <rdtf/status_t.hpp>

#include "daemon.h"
#include "daemon_fakes.h"
#include "support/test_support.h"

namespace rdtf::daemon {

inline std::string fixture(const std::string& name) { return rdtf::testing::read_file(rdtf::testing::data_dir() / "blender" / name); }

class DaemonLoop : public ::testing::Test {
 public:
  using Kind = FileEvent::Kind;

 protected:
  void SetUp() override {
    std::filesystem::create_directories(tmp_ / "watch");
    watch_ = std::filesystem::canonical(tmp_ / "watch");
    out_ = tmp_.path() / "out";
  }

  void start(const std::function<void(DaemonConfig&)>& tweak = {}, ConfigLoader reload = {}) {
    DaemonConfig& config = config_;
    config.watch = {watch_};
    config.output = out_;
    config.validate = false;  // The dynamics gate has tests of its own; here: scheduling.
    config.simulate = false;
    config.urdf = false;
    config.republish_period = std::chrono::milliseconds(0);
    config.settle = std::chrono::milliseconds(50);
    config.max_open_wait = std::chrono::seconds(5);
    // Jobs start at the deadline, as the scheduling tests count them; DaemonPrepared turns it on.
    config.convert_while_settling = false;
    config.status_period = std::chrono::milliseconds(1000);
    if (tweak) tweak(config);
    DaemonPorts ports;
    ports.clock = clock_;
    auto watcher = std::make_unique<fakes::FakeWatcher>();
    auto runner = std::make_unique<fakes::FakeRunner>();
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

  void step() { daemon_->step(std::chrono::milliseconds(0)); }
  void advance(Clock::duration by) {
    clock_->advance(by);
    step();
  }
  // Writes a file and reports it closed after writing, as inotify does for an in-place save.
  std::filesystem::path save(const std::string& name, const std::string& bytes) {
    const std::filesystem::path path = watch_ / name;
    rdtf::testing::write_file(path, bytes);
    notify(Kind::kWritten, path);
    return path;
  }
  // An event, read by the loop at once (as inotify's are, the moment they happen).
  void notify(Kind kind, const std::filesystem::path& path) {
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
  std::filesystem::path watch_;
  std::filesystem::path out_;
  std::shared_ptr<fakes::FakeClock> clock_ = std::make_shared<fakes::FakeClock>();
  std::shared_ptr<fakes::BusRecord> bus_ = std::make_shared<fakes::BusRecord>();
  fakes::FakeWatcher* watcher_ = nullptr;
  fakes::FakeRunner* runner_ = nullptr;
  std::unique_ptr<Daemon> daemon_;
  std::vector<fakes::Sent> log_;
  std::size_t seen_ = 0;
};

inline const std::vector<std::string> kRevision1{"DESCRIPTION r1", "INERTIA"};

}  // namespace rdtf::daemon
