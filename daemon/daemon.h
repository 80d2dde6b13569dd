// rdtfd's event loop: file events -> each model's state machine (model_schedule.h) -> conversions on
// the job runner -> registry -> bus. One thread owns all state; workers only run conversions and
// hand back plain values. The clock, the watcher, the job runner and the bus are ports (ports.h):
// real ones in rdtfd, fakes when a test steps the loop.
#pragma once

#include <atomic>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <utility>

#include <rdtf/model_error_t.hpp>
#include <rdtf/request_t.hpp>

#include "blob_server.h"
#include "bus_input.h"
#include "config.h"
#include "ports.h"
#include "publisher.h"
#include "registry.h"
#include "result_cache.h"
#include "settle.h"
#include "simulation_host.h"
#include "verdict_memo.h"
#include "watcher.h"

namespace rdtf::daemon {

// Reads the configuration again (SIGHUP): the file plus the command line's overrides.
using ConfigLoader = std::function<std::optional<DaemonConfig>(std::string& error)>;

struct DaemonCounters {
  std::int64_t conversions = 0;
  std::int64_t rejections = 0;
  std::int64_t skipped_unchanged = 0;
  std::int64_t rescans = 0;
  std::int64_t from_cache = 0;     // Results taken from the result cache (nothing converted).
  std::int64_t cache_refused = 0;  // Cache entries refused (torn, altered) or whose outputs had changed.
};

// Creates <output>/.rdtfd-state (refusing one that is a link) and takes the exclusive flock on its
// `lock` file that keeps a second rdtfd off this output: the open descriptor, or -1 with `error`.
int lock_output_folder(const std::filesystem::path& output, std::string& error);

class Daemon {
 public:
  Daemon(DaemonConfig config, ConfigLoader reload, DaemonPorts ports = {});
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // Watches, opens the bus, starts the workers and queues every model found.
  bool start(std::string& error);
  // Runs until SIGTERM/SIGINT (or request_stop); returns the process exit code.
  int run();
  // One turn of the loop, waiting at most `max_wait` for something to happen (ports without a
  // file descriptor are asked every turn).
  void step(std::chrono::milliseconds max_wait);
  void request_stop() { stop_ = true; }
  void reload_config();  // What SIGHUP does.

  // For tests that step the loop: the models and what the daemon counted.
  const Registry& registry() const { return registry_; }
  const DaemonCounters& counters() const { return counters_; }
  bool simulating() const { return simulation_ != nullptr; }  // The live simulation runs.

 private:
  // File events and the watched tree (daemon_files.cc).
  void handle_file_events();                         // Reads what the watcher has into pending_events_.
  void process_file_events(std::size_t max_events);  // Handles the oldest of them.
  void remove_stale_temporaries();
  void remove_unreferenced_outputs();
  void check_watches(Clock::time_point now);
  void rescan(const char* why);
  void note_change(const std::filesystem::path& path, FileChange change);
  bool ignored(const std::filesystem::path& path) const;
  std::string alike_id(const std::filesystem::path& source, int n) const;
  std::string choose_model_id(const std::filesystem::path& source) const;
  // Whether `source` is a model file in a watched folder, not yet known: the file an earlier run
  // gave an id that another file now asks for.
  bool held_by_a_file_here(const std::filesystem::path& source) const;
  // The watched folder a model lies in (the longest match when folders nest: the first listed).
  std::filesystem::path root_of(const std::filesystem::path& source) const;

  // Scheduling: state machines, timers, jobs and their outcomes (daemon_jobs.cc).
  SettlePolicy settle_policy() const { return {config_.settle, config_.max_open_wait}; }
  // Applies an event to a model's state machine, keeping the timer index in step.
  template <typename Event>
  ModelActions transition(ModelRecord& record, Event&& event);
  void file_timer(ModelRecord& record);
  void unfile_timer(ModelRecord& record);
  void fire_timers(Clock::time_point now);
  ConversionJob make_job(const ModelRecord& record) const;
  bool is_small(const ModelRecord& record) const;
  void start_job(ModelRecord& record);
  // Whether the record's revision numbers are known: its state file read (again, if it could not
  // be read for want of descriptors when the model was found). If not, `*why` says so.
  bool state_known(ModelRecord& record, std::string* why);
  // Converting while settling: what a file event's or a prepared job's transition asks for, and
  // a prepared job started when the model may have one.
  void on_settling(ModelRecord& record, const ModelActions& actions);
  void use_prepared(ModelRecord& record, ConversionOutcome outcome);
  void apply_prepared(ConversionOutcome outcome);
  void start_prepared_jobs(Clock::time_point now);
  std::vector<std::filesystem::path> to_prepare_;  // Models that may prepare once this turn's events are in.
  bool waiting_for_writer(const ModelRecord& record, Clock::time_point now) const;
  void handle_outcomes(std::size_t max_outcomes);
  void apply(ConversionOutcome outcome);
  void apply_converted(ConversionOutcome& outcome, ModelRecord& record);
  // Announces REMOVED and forgets it; `checked`: how long finding it gone took.
  void drop_model(const std::filesystem::path& source, std::chrono::microseconds checked);

  // The bus (daemon_publish.cc).
  // A bus on `config`'s URL and prefix (nullptr and `error` when LCM cannot open it), and the
  // publisher that sends on it; opened before a reload commits, so a URL LCM refuses changes nothing.
  std::unique_ptr<Bus> make_bus(const DaemonConfig& config, std::string& error);
  void install_bus(std::unique_ptr<Bus> bus);
  void publish_daemon_error(const std::string& code, const std::string& file, const std::string& message);
  // A model's ERROR, kept as its refusal while no revision of it is live (ModelRecord::refusal).
  void publish_error(ModelRecord& record, rdtf::model_error_t error);
  void republish_refusal(const ModelRecord& record);
  void on_publisher_event(const PublisherEvent& event);
  // 1 when it has a live revision and published it. One whose texts cannot be read is logged, or
  // said in `*unpublished` when given.
  std::size_t publish_model(const ModelRecord& record, std::string* unpublished = nullptr);
  std::size_t publish_all();                             // How many models were published.
  void publish_status();
  void on_request(const rdtf::request_t& request);
  void answer_request(const std::string& model_id, const std::string& requester);
  void answer_deferred_requests(Clock::time_point now);
  std::string channel(const std::string& model_id, const char* kind) const;

  // The loop (daemon.cc).
  void handle_signals();
  // Starts the live simulation when `simulate` is on. One whose LCM does not open is dropped and
  // tried again from periodic(), with a back-off (kSimulationRetryFirst doubling to ...Longest).
  void start_simulation_host();
  void retry_simulation_host(Clock::time_point now);
  static constexpr Clock::duration kSimulationRetryFirst = std::chrono::seconds(1);
  static constexpr Clock::duration kSimulationRetryLongest = std::chrono::seconds(30);
  void periodic(Clock::time_point now);
  // Once the send queue is empty after holding at least kTrimAfterQueuedBytes, the memory freed
  // meanwhile goes back to the system (malloc_trim). A restart over thousands of cached models
  // queues tens of MB of encoded messages within seconds, and glibc kept most of it once sent.
  void trim_after_burst();
  std::size_t burst_queued_bytes_ = 0;  // The most the send queue held since the last trim.
  std::string since(Clock::time_point start) const;

  DaemonConfig config_;
  ConfigLoader reload_;
  DaemonPorts ports_;
  std::shared_ptr<DaemonClock> clock_;
  std::unique_ptr<FileWatcher> watcher_;
  std::unique_ptr<JobRunner> runner_;
  Registry registry_;
  // Every model's deadline (ModelSchedule::deadline), earliest first.
  std::set<std::pair<Clock::time_point, std::filesystem::path>> timers_;
  std::unique_ptr<Bus> lcm_;
  std::unique_ptr<Publisher> publisher_;
  std::unique_ptr<SimulationHost> simulation_;  // Null when `simulate` is off, or its LCM did not open.
  std::size_t stages_left_behind_ = 0;  // Stage folders a failed write could not remove, at the last look.
  std::string simulation_error_;                 // Why the last host did not start; empty when it did.
  Clock::time_point next_simulation_retry_;      // When simulation_error_ is set: the next attempt.
  Clock::duration simulation_retry_delay_{};
  int simulation_attempts_ = 0;                  // Failed attempts since it last ran.
  bool started_once_ = false;                    // start() succeeded: failures are retried, not fatal.
  BusInput bus_;
  BlobServer blobs_;  // The files of every live revision, by SHA-256 (blob_server.h).
  RequestThrottle request_throttle_;
  DaemonCounters counters_;
  // Files modified and not yet closed by their writer, since when.
  OpenWrites open_for_writing_;
  std::deque<FileEvent> pending_events_;  // Read from the watcher, not yet handled.
  bool rescan_pending_ = false;           // One of them asks for a rescan.
  bool rescanning_ = false;               // note_change() calls from a rescan announce no save.
  int signal_fd_ = -1;
  int lock_fd_ = -1;  // <output>/.rdtfd-state/lock, held while this daemon runs (lock_output)
  std::atomic<bool> stop_{false};
  Clock::time_point started_;
  Clock::time_point next_republish_;
  Clock::time_point next_status_;
  bool watches_failing_ = false;  // Some folder could not be watched (inotify limit).
  Clock::time_point next_watch_retry_;
  int watch_retries_ = 0;  // Retries since every folder was last watched.
  std::shared_ptr<ReadBudget> read_budget_;  // Shared with the workers.
  std::shared_ptr<ResultCache> cache_;       // Shared with the workers; null when off.
  std::string cache_key_;                    // settings_key(config_).
  void open_result_cache();
  bool lock_output(std::string& error);  // One daemon per output folder.
  bool take_clean_stop_mark();   // The last run left the mark (now removed): nothing to clean.
  void leave_clean_stop_mark();  // At the end of a clean stop.
  // Revision states are saved without an fsync between the blocks of numbers they reserve. Unless
  // the last run stopped cleanly (its stop synced them) or the machine has not restarted since it
  // ran (the kernel still has every save), a power loss may have taken saves back: then every
  // state numbers on from its reserve (RevisionStore::number_from_reserves). Then records this
  // boot's id for the next start.
  void secure_revision_numbers(bool stopped_cleanly);
  // Set on shutdown: a dynamics check in progress stops (SIM_CANCELLED) instead of being waited for.
  std::atomic<bool> cancel_validations_{false};
};

template <typename Event>
inline ModelActions Daemon::transition(ModelRecord& record, Event&& event) {
  unfile_timer(record);
  const ModelActions actions = event(record.schedule);
  file_timer(record);
  return actions;
}

// One log line on stderr with a UTC timestamp; the text escaped for a terminal.
void log_line(const std::string& text);
// The same for a line BusInput or the blob server made, whose bus text lcm_safe::printable
// escaped already: printable ASCII is written as it is (anything else is escaped as above).
void log_bus_line(const std::string& text);

}  // namespace rdtf::daemon
