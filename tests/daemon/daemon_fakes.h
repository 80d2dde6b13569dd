// Fake ports (daemon/ports.h) for stepping rdtfd's loop in-process: a clock that moves only when
// told, a watcher that reports the events a test makes up, a job runner that runs conversions
// only when told (on the test's thread), and a bus that records what is sent and delivers made-up
// requests. The model files are real files in a temporary folder, so conversions are real.
#pragma once

#include <deque>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <rdtf/request_t.hpp>

#include "config.h"
#include "rdtf/diagnostic_codes.h"
#include "ports.h"
#include "watcher.h"

namespace rdtf::daemon::fakes {

class FakeClock final : public DaemonClock {
 public:
  Clock::time_point now() const override { return now_; }
  void advance(Clock::duration by) { now_ += by; }

 private:
  Clock::time_point now_ = Clock::time_point{} + std::chrono::hours(1000);  // Any fixed instant.
};

class FakeWatcher final : public FileWatcher {
 public:
  bool ok() const override { return true; }
  int fd() const override { return -1; }
  // Lists the real files below `root`, as the initial scan of inotify's watcher does.
  std::vector<std::filesystem::path> watch_tree(const std::filesystem::path& root, std::string& error) override {
    std::vector<std::filesystem::path> files;
    std::error_code ec;
    for (std::filesystem::recursive_directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
      if (it->is_regular_file()) files.push_back(it->path());
    }
    if (ec) error = ec.message();
    return files;
  }
  void clear() override {}
  std::vector<FileEvent> read_events(std::string&) override {
    std::vector<FileEvent> events(queued_.begin(), queued_.end());
    queued_.clear();
    return events;
  }
  std::size_t watch_count() const override { return 1; }
  const std::vector<UnwatchedFolder>& unwatched() const override { return unwatched_; }

  void event(FileEvent::Kind kind, const std::filesystem::path& path) { queued_.push_back({kind, path}); }

 private:
  std::deque<FileEvent> queued_;
  std::vector<UnwatchedFolder> unwatched_;
};

class FakeRunner final : public JobRunner {
 public:
  void submit(ConversionJob job) override { jobs_.push_back(std::move(job)); }
  std::vector<ConversionOutcome> take(std::size_t max, bool& more) override {
    std::vector<ConversionOutcome> taken;
    while (!outcomes_.empty() && taken.size() < max) {
      taken.push_back(std::move(outcomes_.front()));
      outcomes_.pop_front();
    }
    more = !outcomes_.empty();
    return taken;
  }
  int fd() const override { return -1; }
  void stop() override { jobs_.clear(); }

  std::size_t waiting() const { return jobs_.size(); }
  std::size_t started() const { return started_; }
  const ConversionJob& next() const { return jobs_.front(); }
  // Runs the oldest job now (a real conversion, reading the files as they are now) and keeps its
  // outcome, as a worker still busy, until finish(). With `disk_full`, the job fails as a full
  // output disk makes it fail: retryable, nothing written.
  void start_next(bool disk_full = false) {
    ConversionJob job = std::move(jobs_.front());
    jobs_.pop_front();
    ++started_;
    if (!disk_full) {
      running_.push_back(run_job(job));
      return;
    }
    ConversionOutcome outcome;
    outcome.model_id = job.model_id;
    outcome.source = job.source;
    outcome.cache_key = job.cache_key;  // Under the settings it ran with, as run_conversion's.
    outcome.kind = ConversionOutcome::Kind::kRejected;
    outcome.retry = true;
    outcome.prepared = job.prepare;
    outcome.diagnostics.set_file(job.source.string());
    outcome.diagnostics.error(codes::WRITE_FAILED, "", "No space left on device");
    running_.push_back(std::move(outcome));
  }
  // Hands the outcomes of the jobs started back: the daemon applies them at its next step.
  // Each one's after_handover (the cache entry) runs right after, as a worker runs it.
  void finish() {
    for (auto& outcome : running_) {
      std::function<void()> after = std::move(outcome.after_handover);
      outcome.after_handover = nullptr;
      outcomes_.push_back(std::move(outcome));
      run_after_handover(after);
    }
    running_.clear();
  }
  void run_next(bool disk_full = false) {
    start_next(disk_full);
    finish();
  }
  void run_all() {
    while (!jobs_.empty()) start_next();
    finish();
  }

 private:
  std::deque<ConversionJob> jobs_;
  std::deque<ConversionOutcome> running_;
  std::deque<ConversionOutcome> outcomes_;
  std::size_t started_ = 0;
};

struct Sent {
  std::string channel;
  std::vector<std::uint8_t> bytes;
};

// What the daemon sent, shared with the test (the daemon owns the bus and may reopen it).
struct BusRecord {
  std::vector<Sent> sent;
  BusHandlers handlers;
  std::deque<std::pair<std::string, std::vector<std::uint8_t>>> incoming;  // Channel, datagram.
  int opened = 0;
  std::string unopenable_url;  // An LCM URL the fake bus cannot open, as LCM refuses one.
};

class FakeBus final : public Bus {
 public:
  explicit FakeBus(std::shared_ptr<BusRecord> record) : record_(std::move(record)) {}
  int send(const std::string& channel, const std::uint8_t* data, unsigned int size) override {
    record_->sent.push_back({channel, std::vector<std::uint8_t>(data, data + size)});
    return 0;
  }
  int fd() const override { return -1; }
  std::size_t receive(std::size_t max) override {
    std::size_t handled = 0;
    for (; handled < max && !record_->incoming.empty(); ++handled) {
      auto [channel, bytes] = std::move(record_->incoming.front());
      record_->incoming.pop_front();
      if (channel.size() > 8 && channel.compare(channel.size() - 8, 8, "/REQUEST") == 0) {
        record_->handlers.request(channel, bytes.data(), bytes.size());
      }
    }
    return handled;
  }

 private:
  std::shared_ptr<BusRecord> record_;
};

inline BusFactory fake_bus(std::shared_ptr<BusRecord> record) {
  return [record](const DaemonConfig& config, BusHandlers handlers, std::string& error) -> std::unique_ptr<Bus> {
    if (!record->unopenable_url.empty() && config.lcm_url == record->unopenable_url) {
      error = "cannot open LCM at '" + config.lcm_url + "'";
      return nullptr;
    }
    record->handlers = std::move(handlers);
    ++record->opened;
    return std::make_unique<FakeBus>(record);
  };
}

// A request datagram as a subscriber sends it ("" for every model).
inline std::vector<std::uint8_t> encode_request(const std::string& model_id, const std::string& requester) {
  rdtf::request_t request;
  request.utime = 0;
  request.model_id = model_id;
  request.requester = requester;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(request.getEncodedSize()));
  request.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

}  // namespace rdtf::daemon::fakes
