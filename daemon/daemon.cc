#include "daemon.h"

#include <fcntl.h>
#include <malloc.h>
#include <poll.h>
#include <sys/stat.h>
#include <sys/file.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>

#include "../core/gltf/confined_files.h"
#include "daemon_internal.h"
#include "rdtf/atomic_file.h"
#include "rdtf/utf8.h"
#include "revision_store.h"

namespace rdtf::daemon {

std::string milliseconds(std::chrono::microseconds duration) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f ms", static_cast<double>(duration.count()) / 1000.0);
  return text;
}

std::string first_error(const Diagnostics& diag) {
  const Diagnostic* error = diag.first_error();
  return error != nullptr ? format(*error) : "unknown error";
}

std::string Daemon::since(Clock::time_point start) const {
  return milliseconds(std::chrono::duration_cast<std::chrono::microseconds>(clock_->now() - start));
}

std::string escape_for_log(std::string_view text) { return escape_for_terminal(text); }

namespace {

// One line on stderr, stamped, in one write, so that a worker's line (a result not cached) never
// interleaves with the loop's. `safe_text` must be safe for a terminal already.
void write_log_line(const std::string& safe_text) {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto millis = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y-%m-%dT%H:%M:%S", &utc);
  char full[40];
  std::snprintf(full, sizeof(full), "%s.%03lldZ", stamp, static_cast<long long>(millis));
  const std::string line = std::string(full) + " " + safe_text + "\n";
  // A write that failed once (stderr's disk full) left the stream failed, and every later line
  // was dropped though the disk had room again (s80cfg D7): each line tries afresh.
  std::cerr.clear();
  std::cerr.write(line.data(), static_cast<std::streamsize>(line.size()));
  std::cerr.flush();
}

}  // namespace

void log_line(const std::string& text) {
  // One event, one line: a file name (or any other text from outside) with a newline or a
  // terminal escape in it cannot forge a line or rewrite the terminal.
  write_log_line(escape_for_log(text));
}

void log_bus_line(const std::string& text) {
  const bool printable_ascii = std::all_of(text.begin(), text.end(), [](char c) {
    return static_cast<unsigned char>(c) >= 0x20 && static_cast<unsigned char>(c) < 0x7f;
  });
  // Its bus text is escaped already (lcm_safe::printable): escaped again, a byte 0xff showed as
  // "\\\\xff". Anything else in it is escaped as in any line.
  if (printable_ascii) {
    write_log_line(text);
  } else {
    log_line(text);
  }
}

Daemon::Daemon(DaemonConfig config, ConfigLoader reload, DaemonPorts ports)
    : config_(std::move(config)),
      reload_(std::move(reload)),
      ports_(std::move(ports)),
      clock_(ports_.clock ? ports_.clock : std::make_shared<SteadyClock>()),
      watcher_(ports_.watcher ? std::move(ports_.watcher) : std::make_unique<InotifyWatcher>()),
      runner_(std::move(ports_.runner)),
      bus_(BusInput::Handlers{[this](const rdtf::request_t& request) { on_request(request); },
                              [this](const rdtf::joint_command_t& command) {
                                // Without live simulations (--no-simulate) commands go unheard.
                                return simulation_ ? simulation_->command(command) : std::string();
                              },
                              [](const std::string& line) { log_bus_line(line); },
                              [this](const rdtf::blob_request_t& request) {
                                return blobs_.request(request, clock_->now(), *publisher_, config_.channel_prefix);
                              }}),
      blobs_([](const std::string& line) { log_bus_line(line); }),
      request_throttle_(kRequestAnswerPeriod),
      started_(clock_->now()),
      read_budget_(std::make_shared<ReadBudget>(config_.max_read_bytes_in_flight)) {
  if (!ports_.bus) ports_.bus = open_lcm_bus;
}

Daemon::~Daemon() {
  cancel_validations_ = true;
  if (runner_) runner_->stop();
  if (signal_fd_ >= 0) ::close(signal_fd_);
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

bool Daemon::start(std::string& error) {
  if (!watcher_->ok()) {
    error = std::string("inotify: ") + std::strerror(errno);
    return false;
  }
  std::unique_ptr<Bus> bus = make_bus(config_, error);
  if (!bus) return false;
  install_bus(std::move(bus));
  blobs_.set_max_message_bytes(config_.max_chunk_bytes);
  if (ports_.signals) {
    sigset_t signals;
    sigemptyset(&signals);
    for (int s : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&signals, s);
    // Blocked here (and so in the workers started below): they arrive through the signalfd only.
    pthread_sigmask(SIG_BLOCK, &signals, nullptr);
    signal_fd_ = ::signalfd(-1, &signals, SFD_NONBLOCK | SFD_CLOEXEC);
    if (signal_fd_ < 0) {
      error = std::string("signalfd: ") + std::strerror(errno);
      return false;
    }
  }
  if (!lock_output(error)) return false;
  const auto cleaning = clock_->now();
  const bool clean = take_clean_stop_mark();
  secure_revision_numbers(clean);
  if (clean) {
    log_line("the last run stopped cleanly: no leftovers to look for in " + config_.output.string());
  } else {
    remove_stale_temporaries();
    remove_unreferenced_outputs();
    log_line("looked for leftovers of an interrupted run in " + config_.output.string() + " in " + since(cleaning));
  }
  open_result_cache();
  if (!runner_) runner_ = std::make_unique<ThreadJobRunner>(config_.workers);
  start_simulation_host();
  if (config_.simulate && !simulation_) {
    error = "the live simulation: " + simulation_error_;
    return false;
  }
  started_once_ = true;
  rescan("start");
  next_republish_ = clock_->now() + config_.republish_period;
  next_status_ = clock_->now();
  std::string watched;
  for (const auto& folder : config_.watch) watched += " " + folder.string();
  for (const auto& folder : config_.created_watch_folders) {
    log_line("watched folder " + folder.string() + " did not exist: created it, empty (check --watch or the "
             "config's watch if that is not the folder meant)");
  }
  log_line("rdtfd started: watching" + watched + "; output " + config_.output.string() +
           "; LCM " + (config_.lcm_url.empty() ? std::string("default URL") : config_.lcm_url) +
           "; channels " + config_.channel_prefix + "/...");
  return true;
}

// Two daemons on one output folder share its revision numbers, clean-stop mark and result cache:
// each published revision 1 of a model with other settings, its own document under one number,
// and each then found the other's outputs "no longer the file rdtfd wrote" (helper sweep s70cache
// D2). The second is refused at its start. The lock is an flock on a file in the state folder,
// released by the kernel however the holder ends; the state folder must be a folder of the output,
// not a link to one elsewhere (where the state and the cache would be written and removed).
bool Daemon::lock_output(std::string& error) {
  const int fd = lock_output_folder(config_.output, error);
  if (fd < 0) return false;
  lock_fd_ = fd;
  return true;
}

int lock_output_folder(const std::filesystem::path& output, std::string& error) {
  const auto folder = RevisionStore::folder_for(output);
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  struct stat info {};
  if (::lstat(folder.c_str(), &info) != 0) {
    // Not there: it could not be made (a read-only or unwritable output); say why.
    error = "cannot create " + folder.string() + ": " + (ec ? ec.message() : std::string(std::strerror(errno)));
    return -1;
  }
  if (!S_ISDIR(info.st_mode)) {
    error = folder.string() + (S_ISLNK(info.st_mode) ? " is a symbolic link" : " is not a folder") +
            ": rdtfd keeps its state inside its output folder only; remove it (rdtfd creates it)";
    return -1;
  }
  const auto path = folder / "lock";
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) {
    error = "cannot open " + path.string() + ": " + std::strerror(errno);
    return -1;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int why = errno;
    ::close(fd);
    error = why == EWOULDBLOCK
                ? "another rdtfd uses the output folder " + output.string() + " (it holds " + path.string() +
                      "): two daemons on one output would publish one revision number for two documents; give "
                      "each its own output folder (--output)"
                : "cannot lock " + path.string() + ": " + std::strerror(why) +
                      " (rdtfd needs flock on its output folder's file system)";
    return -1;
  }
  return fd;
}

// A mark that the last run stopped cleanly: every conversion finished, each removing what its
// outputs no longer refer to, so there are neither temporaries nor unreferenced files to look for,
// and the start skips reading every output (seconds for 10,000 models). Taken (removed, the
// removal made durable) before anything is written, so a run killed from now on leaves none.
bool Daemon::take_clean_stop_mark() {
  const auto mark = RevisionStore::folder_for(config_.output) / "clean-stop";
  struct stat info {};
  if (::lstat(mark.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) return false;
  if (::unlink(mark.c_str()) != 0) return false;
  const int folder = ::open(mark.parent_path().c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  const bool synced = folder >= 0 && ::fsync(folder) == 0;
  if (folder >= 0) ::close(folder);
  return synced;
}

namespace {

// This boot of the machine ("" when it cannot be told).
std::string boot_id() {
  std::ifstream in("/proc/sys/kernel/random/boot_id");
  std::string id;
  std::getline(in, id);
  return id;
}

}  // namespace

void Daemon::secure_revision_numbers(bool stopped_cleanly) {
  const auto folder = RevisionStore::folder_for(config_.output);
  const auto file = folder / "boot-id";
  const std::string now = boot_id();
  std::vector<std::uint8_t> bytes;
  std::string why;
  const bool same_boot = !now.empty() && internal::read_regular_file(file, 4096, bytes, why) &&
                         std::string(bytes.begin(), bytes.end()) == now + "\n";
  if (same_boot) return;
  if (!stopped_cleanly) {
    int raised = 0;
    const auto start = clock_->now();
    if (!RevisionStore::number_from_reserves(config_.output, raised, why)) {
      // The boot is not recorded: the next start tries again.
      log_line("could not number on from the reserved revision numbers in " + folder.string() + ": " + why);
      return;
    }
    if (raised > 0) {
      log_line("the last run did not stop cleanly and the machine has restarted since: " + std::to_string(raised) +
               " models number on from the end of their reserved block of revision numbers, in case a power loss "
               "took back their last saves (" + since(start) + ")");
    }
  }
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec || !write_file_atomically(file, std::string_view(now + "\n"), why)) {
    log_line("could not record this boot in " + file.string() + " (the next start numbers as after a power loss): " +
             (ec ? ec.message() : why));
  }
}

void Daemon::leave_clean_stop_mark() {
  // A stage folder that could not be removed is a leftover the next start must look for.
  if (const auto left = StagedOutput::remove_left_behind(); !left.empty()) {
    log_line("could not remove " + std::to_string(left.size()) + " stage folders (" + left.front().string() +
             (left.size() > 1 ? ", ..." : "") + "): the stop is not marked clean, so the next start removes them");
    return;
  }
  std::string why;
  const auto folder = RevisionStore::folder_for(config_.output);
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  // Revision states are saved without an fsync between the blocks they reserve: the mark says
  // that every save is on disk, so they are synced first (one syncfs for the whole file system).
  const int fd = ec ? -1 : ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  const bool synced = fd >= 0 && ::syncfs(fd) == 0;
  if (!synced) why = std::string("syncfs: ") + std::strerror(errno);
  if (fd >= 0) ::close(fd);
  if (!synced && !ec) {
    log_line("could not mark the stop as clean (the next start looks for leftovers): " + why);
    return;
  }
  if (ec || !write_file_atomically(folder / "clean-stop", std::string_view("rdtfd stopped cleanly\n"), why)) {
    log_line("could not mark the stop as clean (the next start looks for leftovers): " + (ec ? ec.message() : why));
  }
}

void Daemon::open_result_cache() {
  cache_key_ = settings_key(config_);
  cache_.reset();
  if (config_.max_cached_results == 0) return;
  // A results folder that is a link leads out of the output: entries would be written, and the
  // bound's eviction would remove files, wherever it points (helper sweep s70cache D3).
  struct stat info {};
  if (::lstat(ResultCache::folder_for(config_.output).c_str(), &info) == 0 && !S_ISDIR(info.st_mode)) {
    log_line("result cache off: " + ResultCache::folder_for(config_.output).string() + " is " +
             (S_ISLNK(info.st_mode) ? "a symbolic link" : "not a folder") +
             "; rdtfd keeps its cache inside its output folder only (remove it: rdtfd creates it)");
    return;
  }
  cache_ = std::make_shared<ResultCache>(ResultCache::folder_for(config_.output), config_.max_cached_results);
  const std::size_t removed = cache_->open();
  log_line("result cache " + ResultCache::folder_for(config_.output).string() + ": " +
           std::to_string(cache_->entries()) + " entries" +
           (removed > 0 ? " (" + std::to_string(removed) + " least recently used removed, beyond the bound of " +
                              std::to_string(config_.max_cached_results) + ")"
                        : ""));
}

void Daemon::start_simulation_host() {
  simulation_.reset();
  if (!config_.simulate) {
    simulation_error_.clear();  // Nothing to try again.
    simulation_attempts_ = 0;
    return;
  }
  SimulationHostOptions options;
  options.lcm_url = config_.lcm_url;
  options.channel_prefix = config_.channel_prefix;
  options.simulation = simulation_options(config_);
  options.state_rate_hz = config_.state_rate_hz;
  options.real_time_factor = config_.real_time_factor;
  // At most one state a step: a higher rate is not refused (it depends on two other settings) but
  // said, since the states then come at the step rate.
  const double step_rate = options.real_time_factor / options.simulation.time_step;
  if (options.state_rate_hz > step_rate && simulation_attempts_ == 0) {  // Said once, not at each retry.
    log_line("state_rate_hz " + format_number(options.state_rate_hz) + " is above one state per step (time_step " +
             format_number(options.simulation.time_step) + " s at real_time_factor " +
             format_number(options.real_time_factor) + "): states are published at " + format_number(step_rate) +
             " Hz");
  }
  options.joint_command_lifetime =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(config_.joint_command_timeout_s));
  simulation_ = std::make_unique<SimulationHost>(options);
  if (!simulation_->ok()) {
    // Said and dropped: with no LCM the host would step models whose states go nowhere (and LCM
    // printed a line for every publish it ignored). start() refuses to run so; after a reload it is
    // tried again with a back-off, since what failed (descriptors, the network not up yet) may pass.
    simulation_error_ = simulation_->open_error();
    simulation_.reset();
    ++simulation_attempts_;
    simulation_retry_delay_ = simulation_attempts_ == 1 ? kSimulationRetryFirst
                                                        : std::min(simulation_retry_delay_ * 2, kSimulationRetryLongest);
    next_simulation_retry_ = clock_->now() + simulation_retry_delay_;
    // At start rdtfd refuses to run (start() says why); later it serves on and tries again.
    if (started_once_) {
      log_line("the live simulation cannot start: " + simulation_error_ +
               "; no joint or link states are published and no joint command is taken; trying again in " +
               std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(simulation_retry_delay_).count()) +
               " ms (attempt " + std::to_string(simulation_attempts_) + ")");
    }
    return;
  }
  if (simulation_attempts_ > 0) {
    log_line("the live simulation started after " + std::to_string(simulation_attempts_) + " failed attempts");
  }
  simulation_attempts_ = 0;
  simulation_error_.clear();
  for (const auto& [source, record] : registry_.all()) {
    const bool usable = record.live && !(record.live->validation && !record.live->validation->passed);
    if (usable) simulation_->load(record.id, record.revisions, record.live->content_hash, record.live->robot,
                                  live_stepper(*record.live), after_quickstep_failed(*record.live));
  }
}

void Daemon::retry_simulation_host(Clock::time_point now) {
  if (!config_.simulate || simulation_ || simulation_error_.empty() || now < next_simulation_retry_) return;
  start_simulation_host();
}

void Daemon::reload_config() {
  std::string error;
  std::optional<DaemonConfig> fresh;
  // Whatever goes wrong reading or checking the new config, the running one stays.
  try {
    fresh = reload_ ? reload_(error) : std::nullopt;
    if (fresh && !check_config(*fresh, error)) fresh.reset();
  } catch (const std::exception& e) {
    error = e.what();
    fresh.reset();
  }
  if (!fresh) {
    log_line("SIGHUP: config not reloaded, the running config stays: " + error);
    return;
  }
  // What the changed keys need (their reload effects, daemon/config_keys.cc).
  const ConfigChange change = compare_configs(config_, *fresh);
  const bool lcm_changed = change.has(kReconnect);
  const bool folders_changed = change.has(kFoldersChanged);
  const bool conversion_changed = change.has(kReconvert);
  const bool simulation_changed = change.has(kRestartSimulation);
  keep_restart_settings(config_, *fresh);  // E.g. the worker pool keeps its size until a restart.
  // The new bus is opened before anything changes: a URL LCM cannot open (a unicast address, a
  // port in use by nothing it may join) left the new URL in the running config, the old bus
  // serving, and the simulations restarted on a bus that did not work (s80cfg, stop 42's leftover).
  std::unique_ptr<Bus> fresh_bus;
  if (lcm_changed) {
    fresh_bus = make_bus(*fresh, error);
    if (!fresh_bus) {
      log_line("SIGHUP: config not reloaded, the running config stays: " + error);
      return;
    }
  }
  const bool output_changed = fresh->output != config_.output;
  if (output_changed) {
    // The new output is locked before the old one is let go: refused, the running config stays.
    const int fd = lock_output_folder(fresh->output, error);
    if (fd < 0) {
      log_line("SIGHUP: config not reloaded, the running config stays: " + error);
      return;
    }
    if (lock_fd_ >= 0) ::close(lock_fd_);
    lock_fd_ = fd;
  }
  for (const auto& folder : fresh->created_watch_folders) {
    log_line("SIGHUP: watched folder " + folder.string() + " did not exist: created it, empty");
  }
  config_ = std::move(*fresh);
  // Results are keyed by the settings they were computed under: new settings, a new key.
  if (output_changed) {
    open_result_cache();
  } else {
    cache_key_ = settings_key(config_);
  }
  // A shorter period takes effect now, not when the old one runs out (a day's republishing
  // period, shortened, waited out the day: s80cfg D2); a longer one from the next tick.
  const auto now = clock_->now();
  next_republish_ = std::min(next_republish_, now + config_.republish_period);
  next_status_ = std::min(next_status_, now + config_.status_period);
  // A new settle period or open-write wait moves the deadlines of the models settling.
  for (auto& [source, record] : registry_.all()) {
    unfile_timer(record);
    file_timer(record);
  }
  if (fresh_bus) install_bus(std::move(fresh_bus));
  publisher_->set_rate(config_.chunk_rate_bytes_per_s);
  blobs_.set_max_message_bytes(config_.max_chunk_bytes);
  read_budget_->set_capacity(config_.max_read_bytes_in_flight);
  if (simulation_changed) {
    simulation_attempts_ = 0;  // New settings: a failure is their first, tried again after 1 s.
    start_simulation_host();
  }
  // New conversion settings (density, limits) may change any model: convert them all again. A
  // model whose result comes out the same keeps its revision (apply), and a reload that changes
  // no conversion setting converts nothing: the rescan finds every content unchanged.
  if (conversion_changed) {
    for (auto& [source, record] : registry_.all()) record.last_hash.clear();
  }
  log_line("SIGHUP: config reloaded: " + change_text(change));
  rescan(folders_changed ? "config reloaded, folders changed" : "config reloaded");
}

void Daemon::handle_signals() {
  signalfd_siginfo info{};
  while (::read(signal_fd_, &info, sizeof(info)) == sizeof(info)) {
    if (info.ssi_signo == SIGHUP) {
      reload_config();
    } else {
      log_line(std::string("received ") + strsignal(static_cast<int>(info.ssi_signo)) + ": stopping");
      stop_ = true;
    }
  }
}

void Daemon::step(std::chrono::milliseconds max_wait) {
  auto now = clock_->now();
  // Sleep until the earliest of: a model's deadline, the publisher may send, a periodic message.
  Clock::time_point wake = now + max_wait;
  blobs_.pump(*publisher_, config_.channel_prefix);
  if (blobs_.ready(*publisher_)) wake = now;  // Files to check, or room in the send queue for chunks.
  if (!timers_.empty()) wake = std::min(wake, timers_.begin()->first);
  if (auto send = publisher_->drain(now)) wake = std::min(wake, *send);
  if (config_.republish_period.count() > 0) wake = std::min(wake, next_republish_);
  if (watches_failing_) wake = std::min(wake, next_watch_retry_);
  if (config_.simulate && !simulation_ && !simulation_error_.empty()) wake = std::min(wake, next_simulation_retry_);
  if (!pending_events_.empty()) wake = now;  // A burst still being handled: no sleep.
  wake = std::min(wake, next_status_);
  if (auto deferred = request_throttle_.next_due()) wake = std::min(wake, *deferred);
  const auto timeout = std::chrono::duration_cast<std::chrono::milliseconds>(wake - now).count();

  // A port without a descriptor (a test's fake) is asked every turn.
  pollfd fds[4] = {{watcher_->fd(), POLLIN, 0}, {lcm_->fd(), POLLIN, 0},
                   {runner_->fd(), POLLIN, 0}, {signal_fd_, POLLIN, 0}};
  const int ready = ::poll(fds, 4, static_cast<int>(std::max<long long>(timeout, 0) + (timeout > 0 ? 1 : 0)));
  auto readable = [&](const pollfd& fd) { return fd.fd < 0 || (ready > 0 && (fd.revents & POLLIN)); };
  if (signal_fd_ >= 0 && readable(fds[3])) handle_signals();
  if (readable(fds[0])) handle_file_events();
  if (readable(fds[2])) handle_outcomes(kOutcomesPerTurn);
  // Every datagram waiting (up to a bound), so that requests that came together are answered
  // together: identical blob requests then share one pass.
  if (readable(fds[1])) lcm_->receive(kDatagramsPerTurn);
  process_file_events(kFileEventsPerTurn);
  now = clock_->now();
  check_watches(now);
  fire_timers(now);
  answer_deferred_requests(now);
  periodic(now);
  blobs_.pump(*publisher_, config_.channel_prefix);
  publisher_->drain(clock_->now());
  trim_after_burst();
}

void Daemon::trim_after_burst() {
  constexpr std::size_t kTrimAfterQueuedBytes = 8u << 20;
  const std::size_t queued = publisher_->queued_bytes();
  burst_queued_bytes_ = std::max(burst_queued_bytes_, queued);
  if (queued > 0 || burst_queued_bytes_ < kTrimAfterQueuedBytes) return;
#if defined(__GLIBC__)
  const auto start = std::chrono::steady_clock::now();
  malloc_trim(0);
  log_line("memory freed after " + std::to_string(burst_queued_bytes_ >> 20) +
           " MiB of messages were sent returned to the system in " +
           milliseconds(std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start)));
#endif
  burst_queued_bytes_ = 0;
}

void Daemon::periodic(Clock::time_point now) {
  bus_.flush_drops();
  retry_simulation_host(now);
  if (config_.republish_period.count() > 0 && now >= next_republish_) {
    const auto start = clock_->now();
    const std::size_t count = publish_all();
    // One line per period, not per model: it repeats for as long as the daemon runs.
    log_line("republished " + std::to_string(count) + " models (every " +
             std::to_string(config_.republish_period.count()) + " ms), queued in " + since(start));
    next_republish_ = now + config_.republish_period;
  }
  if (now >= next_status_) {
    publish_status();
    next_status_ = now + config_.status_period;
    // Stage folders a failed write could not remove (out of descriptors) go once they can.
    const std::size_t left_before = stages_left_behind_;
    stages_left_behind_ = StagedOutput::remove_left_behind().size();
    if (stages_left_behind_ < left_before) {
      log_line("removed " + std::to_string(left_before - stages_left_behind_) +
               " stage folders a failed write had left behind" +
               (stages_left_behind_ > 0 ? "; " + std::to_string(stages_left_behind_) + " still there" : ""));
    }
  }
}

int Daemon::run() {
  while (!stop_) step(std::chrono::milliseconds(1000));
  // Let conversions in flight finish: their outputs are written atomically, so nothing is
  // half-done either way, and waiting keeps the registry consistent with the output folder. A
  // dynamics check in progress is cancelled (it writes nothing before its verdict), and its
  // revision, never judged, is dropped.
  cancel_validations_ = true;
  runner_->stop();
  bool more = true;
  while (more) {
    for (auto& outcome : runner_->take(std::numeric_limits<std::size_t>::max(), more)) {
      if (!outcome.cancelled) apply(std::move(outcome));
    }
  }
  // The real clock: run() is rdtfd's own shutdown, which sleeps while the queue drains.
  const auto flush_until = Clock::now() + std::chrono::seconds(2);
  while (publisher_->queued() > 0 && Clock::now() < flush_until) {
    if (auto next = publisher_->drain(Clock::now())) std::this_thread::sleep_until(*next);
  }
  leave_clean_stop_mark();
  log_line("rdtfd stopped");
  return 0;
}

}  // namespace rdtf::daemon
