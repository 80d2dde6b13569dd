// rdtfd's event loop: inotify events -> settle -> conversions on worker threads -> registry ->
// LCM. One thread owns all state; workers only run conversions and hand back plain values.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include <rdtf/joint_command_t.hpp>
#include <rdtf/request_t.hpp>

#include "blob_server.h"
#include "bus_input.h"
#include "config.h"
#include "publisher.h"
#include "registry.h"
#include "settle.h"
#include "simulation_host.h"
#include "watcher.h"

namespace rdtf::daemon {

// Reads the configuration again (SIGHUP): the file plus the command line's overrides.
using ConfigLoader = std::function<std::optional<DaemonConfig>(std::string& error)>;

class Daemon {
 public:
  Daemon(DaemonConfig config, ConfigLoader reload);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // Watches, connects to LCM, starts the workers and queues every model found.
  bool start(std::string& error);
  // Runs until SIGTERM/SIGINT (or request_stop); returns the process exit code.
  int run();
  // One turn of the loop, waiting at most `max_wait` for something to happen.
  void step(std::chrono::milliseconds max_wait);
  void request_stop() { stop_ = true; }

 private:
  struct Counters {
    std::int64_t conversions = 0;
    std::int64_t rejections = 0;
    std::int64_t skipped_unchanged = 0;
    std::int64_t rescans = 0;
  };

  // A conversion that failed for the environment's sake (disk full) is tried again later.
  struct Retry {
    Clock::time_point due;
    Clock::duration delay{};
    int attempts = 0;
  };

  void handle_file_events();                        // Reads what inotify has into pending_events_.
  void process_file_events(std::size_t max_events);  // Handles the oldest of them.
  void remove_stale_temporaries();
  void remove_unreferenced_outputs();
  void publish_daemon_error(const std::string& code, const std::string& file, const std::string& message);
  void on_publisher_event(const PublisherEvent& event);
  void schedule_retry(const ConversionOutcome& outcome, ModelRecord& record);
  void retry_due(Clock::time_point now);
  void check_watches(Clock::time_point now);
  void handle_signals();
  void rescan(const char* why);
  // Announces REMOVED and forgets it; `checked`: how long finding it gone took.
  void drop_model(const std::filesystem::path& source, std::chrono::microseconds checked);
  void note_change(const std::filesystem::path& path, bool still_open, bool closed);
  void dispatch_due();
  void handle_outcomes(std::size_t max_outcomes);
  void apply(ConversionOutcome outcome);
  std::size_t publish_model(const ModelRecord& record);  // 1 when it has a live revision.
  std::size_t publish_all();                             // How many models were published.
  void publish_status();
  // Raw datagrams: decoded by bus_ only after the schema check (never lcm-gen's decoder alone).
  void on_request_datagram(const lcm::ReceiveBuffer* buffer, const std::string& channel) noexcept;
  void on_command_datagram(const lcm::ReceiveBuffer* buffer, const std::string& channel) noexcept;
  void on_blob_request_datagram(const lcm::ReceiveBuffer* buffer, const std::string& channel) noexcept;
  void handler_failed() noexcept;
  void on_request(const rdtf::request_t& request);
  void answer_request(const std::string& model_id, const std::string& requester);
  void answer_deferred_requests(Clock::time_point now);
  void start_simulation_host();
  bool ignored(const std::filesystem::path& path) const;
  bool waiting_for_writer(const ModelRecord& record, Clock::time_point now) const;
  std::string unique_model_id(const std::filesystem::path& source) const;
  std::string channel(const std::string& model_id, const char* kind) const;
  // The watched folder a model lies in (the longest match when folders nest: the first listed).
  std::filesystem::path root_of(const std::filesystem::path& source) const;
  bool connect_lcm(std::string& error);
  void worker_loop();
  void reload_config();

  DaemonConfig config_;
  ConfigLoader reload_;
  InotifyWatcher watcher_;
  SettleQueue settle_;
  Registry registry_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<Publisher> publisher_;
  std::unique_ptr<SimulationHost> simulation_;  // Null when `simulate` is off.
  BusInput bus_;
  BlobServer blobs_;  // The files of every live revision, by SHA-256 (blob_server.h).
  RequestThrottle request_throttle_;
  std::uint64_t handler_failures_ = 0;  // LCM thread: exceptions caught outside BusInput.
  Counters counters_;
  // Files modified and not yet closed by their writer, since when.
  OpenWrites open_for_writing_;
  std::deque<FileEvent> pending_events_;  // Read from inotify, not yet handled.
  bool rescan_pending_ = false;           // One of them asks for a rescan.
  int signal_fd_ = -1;
  int wake_fd_ = -1;  // eventfd: a worker finished.
  std::atomic<bool> stop_{false};
  Clock::time_point started_ = Clock::now();
  Clock::time_point next_republish_;
  Clock::time_point next_status_;
  std::map<std::filesystem::path, Retry> retries_;
  bool watches_failing_ = false;         // Some folder could not be watched (inotify limit).
  Clock::time_point next_watch_retry_;

  // Shared with the workers.
  std::shared_ptr<ReadBudget> read_budget_;
  std::mutex mutex_;
  std::condition_variable work_ready_;
  std::deque<ConversionJob> jobs_;
  std::deque<ConversionOutcome> outcomes_;
  bool workers_stop_ = false;
  // Set on shutdown: a dynamics check in progress stops (SIM_CANCELLED) instead of being waited for.
  std::atomic<bool> cancel_validations_{false};
  std::vector<std::thread> workers_;
};

// One log line on stderr with a UTC timestamp.
void log_line(const std::string& text);

}  // namespace rdtf::daemon
