// The daemon's ports to the world: the clock, the file watcher, the job runner and the bus, each
// behind a small interface (as watchman's and LevelDB's Env), so that its loop can be stepped in
// a test with a fake clock, made-up file events, jobs run when the test says, and a bus that
// records what is sent. The real ones: the steady clock, inotify, worker threads and LCM.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "conversion.h"
#include "settle.h"
#include "watcher.h"

namespace lcm {
class LCM;
class ReceiveBuffer;
}  // namespace lcm

namespace rdtf::daemon {

struct DaemonConfig;

class DaemonClock {
 public:
  virtual ~DaemonClock() = default;
  virtual Clock::time_point now() const = 0;
};

class SteadyClock final : public DaemonClock {
 public:
  Clock::time_point now() const override { return Clock::now(); }
};

// Runs conversions off the loop's thread and hands back their outcomes.
class JobRunner {
 public:
  virtual ~JobRunner() = default;
  virtual void submit(ConversionJob job) = 0;
  // Up to `max` finished outcomes, oldest first; `more`: others are left.
  virtual std::vector<ConversionOutcome> take(std::size_t max, bool& more) = 0;
  // Readable when outcomes wait; -1 when there is nothing to poll (take() is called every turn).
  virtual int fd() const = 0;
  // Drops the jobs not started, waits for the ones running; their outcomes can still be taken.
  virtual void stop() = 0;
};

// `workers` threads running run_conversion, and one express thread that takes only express jobs
// (ConversionJob::express: small models, commits), so that two large files dropped in the folder
// cannot stall every other model's save for as long as they convert; an eventfd wakes the loop
// when one finishes.
class ThreadJobRunner final : public JobRunner {
 public:
  explicit ThreadJobRunner(int workers, bool express_worker = true);
  ~ThreadJobRunner() override;
  void submit(ConversionJob job) override;
  std::vector<ConversionOutcome> take(std::size_t max, bool& more) override;
  int fd() const override { return wake_fd_; }
  void stop() override;

 private:
  void worker_loop(bool express_only);
  // The next job a worker may take (jobs_.end() if none); with mutex_ held.
  std::deque<ConversionJob>::iterator next_job(bool express_only);
  void wake();

  int wake_fd_ = -1;
  std::mutex mutex_;
  std::condition_variable work_ready_;
  std::deque<ConversionJob> jobs_;
  std::deque<ConversionOutcome> outcomes_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

// A conversion that threw: a rejection with its reason (no exception crosses a thread).
ConversionOutcome run_job(const ConversionJob& job);
// An outcome's after_handover, if any; what it throws is logged, not passed on.
void run_after_handover(const std::function<void()>& after) noexcept;

// Raw datagrams of the channels the daemon listens to (decoded by BusInput after its schema check).
struct BusHandlers {
  using Datagram = std::function<void(const std::string& channel, const void* data, std::size_t size)>;
  Datagram request;       // <prefix>/REQUEST
  Datagram command;       // <prefix>/<model>/JOINT_COMMAND
  Datagram blob_request;  // <prefix>/BLOB_REQUEST
};

class Bus {
 public:
  virtual ~Bus() = default;
  // One datagram out: 0 on success, as lcm::LCM::publish (the Publisher paces and retries).
  virtual int send(const std::string& channel, const std::uint8_t* data, unsigned int size) = 0;
  // Readable when datagrams wait; -1 when there is nothing to poll (receive() is called every turn).
  virtual int fd() const = 0;
  // Hands up to `max` waiting datagrams to the handlers; how many.
  virtual std::size_t receive(std::size_t max) = 0;
};

// Opens the bus of a configuration (lcm_url, channel_prefix); null with `error` when it cannot.
using BusFactory =
    std::function<std::unique_ptr<Bus>(const DaemonConfig& config, BusHandlers handlers, std::string& error)>;
std::unique_ptr<Bus> open_lcm_bus(const DaemonConfig& config, BusHandlers handlers, std::string& error);

// What the daemon runs on. Every null port is the real one; tests pass fakes.
struct DaemonPorts {
  std::shared_ptr<DaemonClock> clock;
  std::unique_ptr<FileWatcher> watcher;
  std::unique_ptr<JobRunner> runner;  // Null: ThreadJobRunner with the config's `workers`.
  BusFactory bus;
  bool signals = true;  // SIGTERM, SIGINT and SIGHUP through a signalfd (a test process keeps its own).
};

}  // namespace rdtf::daemon
