#include "daemon.h"

#include <poll.h>
#include <sys/eventfd.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <regex>
#include <set>
#include <tuple>

#include <rdtf/status_t.hpp>

#include "delta_messages.h"
#include "messages.h"
#include "rdtf/atomic_file.h"
#include "rdtf/gltf.h"
#include "rdtf/urdf.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::daemon {
namespace {

// LCM channel names are at most 63 characters: "<prefix>/<id>/DESCRIPTION_CHUNK" must fit.
constexpr std::size_t kMaxChannelLength = 63;
constexpr std::size_t kLongestKind = sizeof("/DESCRIPTION_CHUNK") - 1;

// How often folders that could not be watched are tried again; the back-off of failed writes.
constexpr std::chrono::milliseconds kWatchRetryPeriod{1000};
constexpr std::chrono::milliseconds kFirstRetryDelay{200};
constexpr std::chrono::milliseconds kLongestRetryDelay{3000};

// The publisher's burst, in receive-buffer bytes: 60% of Linux's default 212,992-byte socket
// buffer, so that a subscriber that wakes late still holds a whole burst, with room left for
// the joint and link states that the simulation sends alongside.
constexpr std::size_t kBurstReceiveBufferBytes = 128 * 1024;

// Requests for the same model (or for all) are answered at most once per this period
// (RequestThrottle): a flood of requests costs one publication per model and period.
constexpr std::chrono::milliseconds kRequestAnswerPeriod{1000};

// Work one turn of the loop does at most, so that a burst of files (tens of thousands) never
// holds back requests, commands and heartbeats: this many file events are handled and finished
// conversions applied per turn (reading the events is cheap; handling them is not).
constexpr std::size_t kOutcomesPerTurn = 64;
// LCM datagrams handled per turn (each is cheap: a request is answered by queueing messages).
constexpr std::size_t kDatagramsPerTurn = 256;
// File events handled per turn (a new folder of 20,000 files is listed at once: 20,000 events).
constexpr std::size_t kFileEventsPerTurn = 2048;

std::string milliseconds(std::chrono::microseconds duration) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f ms", static_cast<double>(duration.count()) / 1000.0);
  return text;
}

std::optional<std::string> read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

bool is_gltf_output(const std::string& name) {
  return name.size() > 10 && name.compare(name.size() - 10, 10, ".rdtf.gltf") == 0;
}

// The files a primary output (a .rdtf.gltf or a robot.urdf) refers to, canonical; none for any
// other file; nothing when they cannot be known (unreadable file or folder).
std::optional<std::set<std::filesystem::path>> files_referenced_by(const std::filesystem::path& path) {
  const std::string name = path.filename().string();
  if (!is_gltf_output(name) && name != "robot.urdf") return std::set<std::filesystem::path>{};
  std::error_code ec;
  const auto folder = std::filesystem::canonical(path.parent_path(), ec);
  const auto text = read_text(path);
  if (ec || !text) return std::nullopt;
  std::set<std::filesystem::path> files;
  if (is_gltf_output(name)) {
    for (auto& file : referenced_files(std::vector<std::uint8_t>(text->begin(), text->end()), folder)) {
      files.insert(file.lexically_normal());
    }
  } else {
    // write_urdf puts every mesh in <folder>/meshes, whatever prefix its filename has.
    for (const auto& filename : urdf_mesh_filenames(*text)) {
      files.insert(folder / "meshes" / std::filesystem::path(filename).filename());
    }
  }
  return files;
}

std::string first_error(const Diagnostics& diag) {
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError) return format(d);
  }
  return "unknown error";
}

// A conversion again of the content served (after a reload) whose result is the served one.
bool same_result(const ConvertedModel& live, const ConvertedModel& candidate) {
  return live.content_hash == candidate.content_hash && live.written == candidate.written &&
         live.output_path == candidate.output_path && live.rdtf_json == candidate.rdtf_json &&
         live.urdf_path == candidate.urdf_path && live.urdf == candidate.urdf && live.files == candidate.files &&
         live.validation.has_value() == candidate.validation.has_value() &&
         (!live.validation || live.validation->passed == candidate.validation->passed);
}

// Whether `path` is a regular file reached from `root` through real folders only (no symlink on
// the way, none at the end): where read_beneath would find a model.
bool regular_file_below(const std::filesystem::path& root, const std::filesystem::path& path) {
  const auto relative = path.lexically_relative(root);
  if (relative.empty() || *relative.begin() == "..") return false;
  std::filesystem::path at = root;
  std::error_code ec;
  for (auto it = relative.begin(); it != relative.end(); ++it) {
    at /= *it;
    const auto status = std::filesystem::symlink_status(at, ec);
    const bool last = std::next(it) == relative.end();
    if (ec || !(last ? std::filesystem::is_regular_file(status) : std::filesystem::is_directory(status))) return false;
  }
  return true;
}

std::string since(Clock::time_point start) {
  return milliseconds(std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start));
}

}  // namespace

std::string escape_for_log(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else if (byte < 0x20 || byte == 0x7f) {
      char escaped[8];
      std::snprintf(escaped, sizeof(escaped), "\\x%02x", byte);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out;
}

void log_line(const std::string& text) {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto millis = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y-%m-%dT%H:%M:%S", &utc);
  char full[40];
  std::snprintf(full, sizeof(full), "%s.%03lldZ", stamp, static_cast<long long>(millis));
  // One event, one line: a file name (or any other text from outside) with a newline or a
  // terminal escape in it cannot forge a line or rewrite the terminal.
  std::cerr << full << " " << escape_for_log(text) << std::endl;
}

Daemon::Daemon(DaemonConfig config, ConfigLoader reload)
    : config_(std::move(config)),
      reload_(std::move(reload)),
      settle_(config_.settle, config_.max_open_wait),
      bus_(BusInput::Handlers{[this](const rdtf::request_t& request) { on_request(request); },
                              [this](const rdtf::joint_command_t& command) {
                                // Without live simulations (--no-simulate) commands go unheard.
                                return simulation_ ? simulation_->command(command) : std::string();
                              },
                              [](const std::string& line) { log_line(line); },
                              [this](const rdtf::blob_request_t& request) {
                                return blobs_.request(request, Clock::now(), *publisher_, config_.channel_prefix);
                              }}),
      blobs_([](const std::string& line) { log_line(line); }),
      request_throttle_(kRequestAnswerPeriod),
      read_budget_(std::make_shared<ReadBudget>(config_.max_read_bytes_in_flight)) {}

Daemon::~Daemon() {
  cancel_validations_ = true;
  {
    std::lock_guard lock(mutex_);
    workers_stop_ = true;
  }
  work_ready_.notify_all();
  for (auto& worker : workers_) worker.join();
  if (signal_fd_ >= 0) ::close(signal_fd_);
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

bool Daemon::connect_lcm(std::string& error) {
  auto lcm = std::make_unique<lcm::LCM>(config_.lcm_url);
  if (!lcm->good()) {
    error = "cannot open LCM at '" + (config_.lcm_url.empty() ? std::string("default URL") : config_.lcm_url) + "'";
    return false;
  }
  lcm->subscribe(config_.channel_prefix + "/REQUEST", &Daemon::on_request_datagram, this);
  lcm->subscribe(config_.channel_prefix + "/.*/JOINT_COMMAND", &Daemon::on_command_datagram, this);
  lcm->subscribe(config_.channel_prefix + "/BLOB_REQUEST", &Daemon::on_blob_request_datagram, this);
  publisher_ = std::make_unique<Publisher>(*lcm, config_.chunk_rate_bytes_per_s, kBurstReceiveBufferBytes);
  publisher_->on_event([this](const PublisherEvent& event) { on_publisher_event(event); });
  blobs_.publisher_replaced();
  lcm_ = std::move(lcm);
  return true;
}

bool Daemon::start(std::string& error) {
  if (!watcher_.ok()) {
    error = std::string("inotify: ") + std::strerror(errno);
    return false;
  }
  if (!connect_lcm(error)) return false;
  blobs_.set_max_message_bytes(config_.max_chunk_bytes);
  sigset_t signals;
  sigemptyset(&signals);
  for (int s : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&signals, s);
  // Blocked here (and so in the workers started below): they arrive through the signalfd only.
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal_fd_ = ::signalfd(-1, &signals, SFD_NONBLOCK | SFD_CLOEXEC);
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (signal_fd_ < 0 || wake_fd_ < 0) {
    error = std::string("signalfd/eventfd: ") + std::strerror(errno);
    return false;
  }
  remove_stale_temporaries();
  remove_unreferenced_outputs();
  for (int i = 0; i < config_.workers; ++i) workers_.emplace_back([this] { worker_loop(); });
  start_simulation_host();
  rescan("start");
  next_republish_ = Clock::now() + config_.republish_period;
  next_status_ = Clock::now();
  std::string watched;
  for (const auto& folder : config_.watch) watched += " " + folder.string();
  log_line("rdtfd started: watching" + watched + "; output " + config_.output.string() +
           "; LCM " + (config_.lcm_url.empty() ? std::string("default URL") : config_.lcm_url) +
           "; channels " + config_.channel_prefix + "/...");
  return true;
}

// Temporary files of write_file_atomically (".<name>.<pid>-<random>.tmp") whose writer is gone:
// left by a daemon killed mid-write. Files of a live process (another rdtfd) are left alone.
void Daemon::remove_stale_temporaries() {
  std::error_code ec;
  int removed = 0;
  std::vector<std::filesystem::path> stale;
  for (std::filesystem::recursive_directory_iterator it(config_.output, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code type_error;
    const auto status = it->symlink_status(type_error);
    const bool folder = std::filesystem::is_directory(status);
    if (!folder && !std::filesystem::is_regular_file(status)) continue;
    const auto pid = temporary_writer_pid(it->path().filename().string());
    if (!pid) continue;
    // Stage folders (StagedOutput) are temporaries too, with all they hold.
    if (folder) it.disable_recursion_pending();
    const bool writer_alive = *pid > 0 && *pid != ::getpid() && (::kill(static_cast<pid_t>(*pid), 0) == 0 || errno == EPERM);
    if (!writer_alive) stale.push_back(it->path());
  }
  for (const auto& path : stale) {
    std::error_code remove_error;
    if (std::filesystem::remove_all(path, remove_error) > 0) ++removed;
  }
  if (removed > 0) {
    log_line("removed " + std::to_string(removed) + " temporary files left in " + config_.output.string() +
             " by an earlier run");
  }
}

// Content-addressed files (docs/daemon.md, "Outputs") that no primary output refers to: written by
// a conversion killed before it renamed its primary file into place. Every model is converted
// again after a start, so what the primary files on disk refer to is all a reader can need.
void Daemon::remove_unreferenced_outputs() {
  std::set<std::filesystem::path> referenced;
  std::vector<std::filesystem::path> addressed;
  std::error_code ec;
  for (std::filesystem::recursive_directory_iterator it(config_.output, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code path_error;
    // Regular files only, never through a symlink: a link is no output of ours to follow or remove.
    if (!std::filesystem::is_regular_file(it->symlink_status(path_error))) continue;
    if (is_content_addressed_name(it->path().filename().string())) {
      const auto folder = std::filesystem::canonical(it->path().parent_path(), path_error);
      if (!path_error) addressed.push_back(folder / it->path().filename());
      continue;
    }
    const auto files = files_referenced_by(it->path());
    if (!files) return;  // Leftovers harm no one; removing a file an output needs would.
    referenced.insert(files->begin(), files->end());
  }
  int removed = 0;
  for (const auto& path : addressed) {
    std::error_code remove_error;
    if (referenced.count(path) == 0 && std::filesystem::remove(path, remove_error)) ++removed;
  }
  if (removed > 0) {
    log_line("removed " + std::to_string(removed) + " files no output refers to from " + config_.output.string() +
             " (written by an earlier run killed before it finished those outputs)");
  }
}

// An error that belongs to no one model (a folder that cannot be watched, LCM sends that failed):
// a model_error_t with an empty model_id on <prefix>/ERROR.
void Daemon::publish_daemon_error(const std::string& code, const std::string& file, const std::string& message) {
  Diagnostics diag(file);
  diag.error(code, "", message);
  rdtf::model_error_t error;
  error.utime = now_utime();
  error.source_path = file;
  error.live_revision = 0;
  error.diagnostics = to_messages(diag);
  publisher_->publish(config_.channel_prefix + "/ERROR", error);
}

void Daemon::on_publisher_event(const PublisherEvent& event) {
  log_line(event.text);
  // While sends fail nothing can be told over LCM; once they work, the outage is reported.
  if (event.kind == PublisherEvent::Kind::kSendRecovered) publish_daemon_error(codes::LCM_SEND_FAILED, "", event.text);
}

void Daemon::schedule_retry(const ConversionOutcome& outcome, ModelRecord& record) {
  Retry& retry = retries_[record.source];
  retry.delay = retry.attempts == 0 ? Clock::duration(kFirstRetryDelay)
                                    : std::min<Clock::duration>(retry.delay * 2, kLongestRetryDelay);
  retry.due = Clock::now() + retry.delay;
  ++retry.attempts;
  log_line("could not write the outputs of " + record.id + ": " + first_error(outcome.diagnostics) +
           "; trying again in " + std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(retry.delay).count()) +
           " ms (attempt " + std::to_string(retry.attempts) + ")");
  // One ERROR per outage, not one per attempt.
  if (retry.attempts == 1) {
    publisher_->publish(channel(record.id, "ERROR"), make_model_error(record, outcome.content_hash, outcome.diagnostics, config_.max_chunk_bytes));
  }
}

void Daemon::retry_due(Clock::time_point now) {
  for (auto it = retries_.begin(); it != retries_.end(); ++it) {
    if (it->second.due > now) continue;
    it->second.due = Clock::time_point::max();  // Until the outcome of this attempt.
    settle_.touch(it->first.string(), now);
  }
}

// Folders that could not be watched are reported once. A folder inotify refused (max_user_watches
// reached) is tried again every second; a watched folder that is missing (deleted) is looked for
// every second, which costs one stat, and watched again when it is back. When every folder is
// watched again, a rescan has caught what changed meanwhile.
void Daemon::check_watches(Clock::time_point now) {
  const auto& unwatched = watcher_.unwatched();
  if (unwatched.empty()) {
    if (watches_failing_) log_line("every folder is watched again");
    watches_failing_ = false;
    return;
  }
  if (!watches_failing_) {
    watches_failing_ = true;
    next_watch_retry_ = now + kWatchRetryPeriod;
    for (const auto& [folder, missing] : unwatched) {
      if (missing) {
        log_line("watched folder " + folder.string() + " is missing; looking for it every second");
        publish_daemon_error(codes::WATCH_FAILED, folder.string(),
                             "cannot watch " + folder.string() +
                                 ": it is missing (deleted or moved away); its models were removed, and "
                                 "it is looked for every second and watched again when it is back");
      } else {
        publish_daemon_error(codes::WATCH_FAILED, folder.string(),
                             "cannot watch " + folder.string() +
                                 ": inotify watches exhausted (raise /proc/sys/fs/inotify/max_user_watches); "
                                 "its models were converted once, and the folder is tried again every second");
      }
    }
    return;
  }
  if (now >= next_watch_retry_) {
    next_watch_retry_ = now + kWatchRetryPeriod;
    const bool worth_a_rescan = std::any_of(unwatched.begin(), unwatched.end(), [](const auto& entry) {
      std::error_code ec;
      return !entry.missing || std::filesystem::is_directory(std::filesystem::symlink_status(entry.folder, ec));
    });
    if (worth_a_rescan) rescan("retrying folders that could not be watched");
  }
}

bool Daemon::ignored(const std::filesystem::path& path) const {
  const std::string name = path.filename().string();
  // Temporary files of editors and of our own atomic writes.
  if (name.empty() || name.front() == '.' || name.back() == '~' ||
      (name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0)) {
    return true;
  }
  const auto relative = path.lexically_relative(config_.output);
  return !relative.empty() && *relative.begin() != "..";
}

std::filesystem::path Daemon::root_of(const std::filesystem::path& source) const {
  for (const auto& root : config_.watch) {
    const auto relative = source.lexically_relative(root);
    if (!relative.empty() && *relative.begin() != "..") return root;
  }
  return source.parent_path();
}

std::string Daemon::channel(const std::string& model_id, const char* kind) const {
  return config_.channel_prefix + "/" + model_id + "/" + kind;
}

void Daemon::note_change(const std::filesystem::path& path, bool still_open, bool closed) {
  if (ignored(path)) return;
  const auto now = Clock::now();
  auto touch = [&](const std::filesystem::path& model) {
    if (closed) {
      settle_.closed(model.string(), now);
    } else {
      settle_.touch(model.string(), now, still_open);
    }
  };
  if (is_model_file(path)) {
    if (registry_.find(path) == nullptr) {
      ModelRecord& record = registry_.ensure(path, unique_model_id(path));
      const std::string refused = restore_revisions(config_.output, record);
      if (!refused.empty()) log_line(refused);
    }
    touch(path);
    return;
  }
  const auto dependents = registry_.dependents(path);
  for (const auto& model : dependents) touch(model);
  if (!dependents.empty()) return;
  // A file no known model refers to yet: it may be the .bin of a model never converted (Blender
  // writes the .gltf first). Such models in the same folder wait for it too.
  for (const auto& [source, record] : registry_.all()) {
    if (record.revisions == 0 && record.dependencies.empty() && source.parent_path() == path.parent_path()) {
      touch(source);
    }
  }
}

std::string Daemon::unique_model_id(const std::filesystem::path& source) const {
  const std::size_t max_id = kMaxChannelLength - config_.channel_prefix.size() - 1 - kLongestKind;
  // Three characters kept free for a "_N" that tells apart ids that sanitise alike.
  const std::string base = model_id_for(source, config_.watch, max_id - 3);
  std::string id = base;
  // Two names that sanitise alike ("a b.gltf", "a_b.gltf") must not share channels.
  for (int n = 2; registry_.find_id(id) != nullptr; ++n) {
    id = base + "_" + std::to_string(n);
  }
  return id;
}

bool Daemon::waiting_for_writer(const ModelRecord& record, Clock::time_point now) const {
  // The model file, a file it refers to, or (never converted yet: its .bin unknown) any file in its folder.
  std::vector<std::filesystem::path> files = record.dependencies;
  files.push_back(record.source);
  const auto folder = record.source.parent_path();
  return open_for_writing_.holds(files, record.dependencies.empty() ? &folder : nullptr, now, config_.max_open_wait);
}

void Daemon::drop_model(const std::filesystem::path& source, std::chrono::microseconds checked) {
  const auto start = Clock::now();
  ModelRecord* record = registry_.find(source);
  if (record == nullptr) return;
  if (record->live) publisher_->publish(channel(record->id, "REMOVED"), make_model_removed(*record));
  if (simulation_) simulation_->remove(record->id);
  blobs_.remove_model(record->id);
  log_line("removed " + record->id + " in " +
           milliseconds(checked + std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start)) +
           (record->live ? " (revision " + std::to_string(record->revisions) + " was live)" : ""));
  settle_.forget(source.string());
  retries_.erase(source);
  registry_.erase(source);
}

void Daemon::rescan(const char* why) {
  ++counters_.rescans;
  open_for_writing_.clear();  // Close events may have been lost with the queue.
  pending_events_.clear();    // What they told, the rescan finds.
  rescan_pending_ = false;
  // Models outside every watched folder (after a reload changed them) are gone from our view.
  std::vector<std::filesystem::path> outside;
  for (const auto& [source, record] : registry_.all()) {
    // An init-capture: clang 14 cannot capture a structured binding (P1091 came in clang 16).
    const bool watched = std::any_of(config_.watch.begin(), config_.watch.end(), [&model = source](const auto& root) {
      const auto relative = model.lexically_relative(root);
      return !relative.empty() && *relative.begin() != "..";
    });
    if (!watched) outside.push_back(source);
  }
  for (const auto& source : outside) drop_model(source, {});
  watcher_.clear();
  std::vector<std::filesystem::path> files;
  for (const auto& root : config_.watch) {
    std::string error;
    auto found = watcher_.watch_tree(root, error);
    if (!error.empty()) log_line("watch error: " + error);
    files.insert(files.end(), found.begin(), found.end());
  }
  // Known models that are no longer there get converted too: the conversion finds them gone.
  for (const auto& [source, record] : registry_.all()) settle_.touch(source.string(), Clock::now());
  for (const auto& file : files) note_change(file, false, true);
  log_line(std::string("rescan (") + why + "): " + std::to_string(files.size()) + " files, " +
           std::to_string(watcher_.watch_count()) + " folders watched");
}

void Daemon::handle_file_events() {
  std::string error;
  auto events = watcher_.read_events(error);
  if (!error.empty()) log_line("watch error: " + error);
  for (auto& event : events) {
    if (event.kind == FileEvent::Kind::kRescan) rescan_pending_ = true;
    pending_events_.push_back(std::move(event));
  }
}

void Daemon::process_file_events(std::size_t max_events) {
  // Events were lost, or a watched folder moved or went: the rescan finds what every event
  // still waiting would tell, so they need no handling of their own.
  if (rescan_pending_) {
    rescan("inotify queue overflow or a watched folder moved or went");
    return;
  }
  for (std::size_t handled = 0; handled < max_events && !pending_events_.empty(); ++handled) {
    const FileEvent event = std::move(pending_events_.front());
    pending_events_.pop_front();
    switch (event.kind) {
      case FileEvent::Kind::kRescan:
        rescan("inotify queue overflow or a watched folder moved or went");
        return;
      case FileEvent::Kind::kModified:
        if (!ignored(event.path)) open_for_writing_.opened(event.path, Clock::now());
        note_change(event.path, true, false);
        break;
      case FileEvent::Kind::kWritten:
      case FileEvent::Kind::kRemoved:
        open_for_writing_.closed(event.path);
        note_change(event.path, false, true);
        break;
    }
  }
}

void Daemon::dispatch_due() {
  const auto now = Clock::now();
  for (const std::string& source : settle_.take_due(now)) {
    ModelRecord* record = registry_.find(source);
    if (record == nullptr) continue;
    if (waiting_for_writer(*record, now)) {
      settle_.touch(source, now);  // Look again a settle period later.
      continue;
    }
    if (record->in_flight) {
      record->again = true;
      continue;
    }
    record->in_flight = true;
    ConversionJob job;
    job.model_id = record->id;
    job.root = root_of(record->source);
    job.source = record->source;
    if (record->live) {
      job.live_rdtf_json = record->live->rdtf_json;
      job.live_urdf = record->live->urdf;
    }
    job.max_read_bytes = config_.max_read_bytes;
    job.budget = read_budget_;
    job.output_dir = config_.output / record->id;
    job.options = config_.convert;
    job.previous_hash = record->last_hash;
    job.write_failed = config_.publish_failed;
    if (config_.validate) {
      job.validation = validation_options(config_);
      job.validation->cancel = &cancel_validations_;
    }
    if (config_.urdf) {
      UrdfOptions urdf;
      urdf.y_up = config_.urdf_y_up;
      job.urdf = urdf;
    }
    {
      std::lock_guard lock(mutex_);
      jobs_.push_back(std::move(job));
    }
    work_ready_.notify_one();
  }
}

void Daemon::worker_loop() {
  for (;;) {
    ConversionJob job;
    {
      std::unique_lock lock(mutex_);
      work_ready_.wait(lock, [this] { return workers_stop_ || !jobs_.empty(); });
      if (jobs_.empty()) return;  // Stopping, and nothing left to finish.
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    ConversionOutcome outcome;
    try {
      outcome = run_conversion(job);
    } catch (const std::exception& error) {
      // No exception crosses a thread: an internal failure becomes a rejection with its reason.
      outcome.model_id = job.model_id;
      outcome.source = job.source;
      outcome.kind = ConversionOutcome::Kind::kRejected;
      outcome.diagnostics.set_file(job.source.string());
      outcome.diagnostics.error(codes::INTERNAL_ERROR, "", error.what());
    }
    {
      std::lock_guard lock(mutex_);
      outcomes_.push_back(std::move(outcome));
    }
    const std::uint64_t one = 1;
    [[maybe_unused]] auto written = ::write(wake_fd_, &one, sizeof(one));
  }
}

void Daemon::handle_outcomes(std::size_t max_outcomes) {
  std::uint64_t value = 0;
  [[maybe_unused]] auto read = ::read(wake_fd_, &value, sizeof(value));
  std::deque<ConversionOutcome> outcomes;
  bool more = false;
  {
    std::lock_guard lock(mutex_);
    while (!outcomes_.empty() && outcomes.size() < max_outcomes) {
      outcomes.push_back(std::move(outcomes_.front()));
      outcomes_.pop_front();
    }
    more = !outcomes_.empty();
  }
  for (auto& outcome : outcomes) apply(std::move(outcome));
  // The rest in the next turns of the loop, between requests and heartbeats.
  if (more) {
    const std::uint64_t one = 1;
    [[maybe_unused]] auto written = ::write(wake_fd_, &one, sizeof(one));
  }
}

void Daemon::apply(ConversionOutcome outcome) {
  ModelRecord* record = registry_.find(outcome.source);
  if (record == nullptr) return;
  record->in_flight = false;
  const std::string id = record->id;
  switch (outcome.kind) {
    case ConversionOutcome::Kind::kConverted: {
      const ConvertedModel& candidate = *outcome.converted;
      const bool failed = candidate.validation && !candidate.validation->passed;
      retries_.erase(record->source);
      record->last_hash = outcome.content_hash;
      record->dependencies = outcome.dependencies;
      if (record->live && same_result(*record->live, candidate)) {
        // A reload changed settings this model's result does not depend on.
        ++counters_.skipped_unchanged;
        log_line("unchanged " + id + " in " + milliseconds(outcome.duration) + ": still revision " +
                 std::to_string(record->revisions));
        break;
      }
      // The first conversion after a restart that gives the result the earlier run served keeps
      // its number; any other content that gets a VALIDATION gets a number of its own, accepted or
      // not, saved before anything publishes it (docs/lcm.md, "Revision numbers").
      const std::string candidate_result = result_digest(candidate);
      const bool kept = !record->live && record->restored &&
                        record->restored->content_hash == candidate.content_hash &&
                        record->restored->result_digest == candidate_result;
      const std::optional<StoredRevision> previous = stored_live(*record);
      const std::int64_t number = kept ? record->restored->revision : ++record->numbered;
      if (!kept) {
        // The live revision after this one: this one, unless the check rejects it unpublished.
        const std::optional<StoredRevision> live =
            failed && !config_.publish_failed
                ? previous
                : StoredRevision{number, candidate.content_hash, candidate_result, candidate.facts};
        const std::string why = save_revisions(config_.output, *record, live);
        if (!why.empty()) {
          log_line("could not save the revision state of " + id + " (revision " + std::to_string(number) +
                   " may be numbered again after a restart): " + why);
        }
      }
      // Warnings of a conversion that succeeded: one log line each, and on LCM with the verdict
      // (with the infos, which every Blender export has and which would only crowd the log).
      for (const Diagnostic& d : outcome.diagnostics.all()) {
        if (d.severity == Severity::kWarning) log_line("warning " + id + " revision " + std::to_string(number) + ": " + format(d));
      }
      // The verdict with the conversion's warnings: published before every description of the
      // revision, so a subscriber that starts late gets the report too.
      std::optional<ValidationSummary> report = candidate.validation;
      if (report) report->diagnostics.append(outcome.diagnostics);
      if (failed && !config_.publish_failed) {
        publisher_->publish(channel(id, "VALIDATION"),
                            make_validation_report(id, number, outcome.content_hash, *report, config_.max_chunk_bytes));
        ++counters_.rejections;
        log_line("rejected " + id + " revision " + std::to_string(number) + " (dynamics) in " +
                 milliseconds(outcome.duration) + ": " + candidate.validation->summary_line +
                 (record->live ? "; still serving revision " + std::to_string(record->revisions) : ""));
        publisher_->publish(channel(id, "ERROR"),
                            make_model_error(*record, outcome.content_hash, candidate.validation->diagnostics, config_.max_chunk_bytes));
        break;
      }
      ++counters_.conversions;
      std::vector<ElementChange> changes;
      if (!kept) changes = diff_robots(previous ? previous->facts : RobotFacts{}, candidate.facts);
      record->revisions = number;
      record->restored.reset();
      record->live_result = candidate_result;
      record->live = std::move(outcome.converted);
      record->live->validation = std::move(report);
      // From now on the previous revision's files are no longer served (docs/lcm.md, "Files and blobs").
      blobs_.set_model(id, config_.output / id, record->live->files);
      log_line("converted " + id + " revision " + std::to_string(record->revisions) + " (" +
               std::to_string(record->live->robot.links.size()) + " links, " +
               std::to_string(record->live->robot.joints.size()) + " joints" +
               (record->live->validation ? std::string(", dynamics ") + (failed ? "FAILED" : "passed") : "") +
               ") in " + milliseconds(outcome.duration) + (kept ? " (the result the earlier run served: its number kept)" : ""));
      if (simulation_) {
        if (failed) {
          // A revision that failed the check would blow up in ODE, and the previous one is no
          // longer what is published: no simulation runs until a revision passes.
          simulation_->remove(id);
          log_line("stopped the simulation of " + id + ": revision " + std::to_string(number) +
                   " failed the dynamics check");
        } else {
          simulation_->load(id, record->revisions, record->live->content_hash, record->live->robot);
        }
      }
      publish_model(*record);
      if (!kept) {
        // Once, after the revision's description: what changed since the revision it replaces.
        const DeltaHeader header{id, previous ? previous->revision : 0, previous ? previous->content_hash : "",
                                 number, record->live->content_hash};
        for (const auto& part : make_deltas(header, changes, now_utime(), config_.max_chunk_bytes)) {
          publisher_->publish(channel(id, "DELTA"), part);
        }
      }
      break;
    }
    case ConversionOutcome::Kind::kUnchanged:
      retries_.erase(record->source);
      ++counters_.skipped_unchanged;
      record->dependencies = outcome.dependencies;
      break;
    case ConversionOutcome::Kind::kRejected:
      ++counters_.rejections;
      if (outcome.retry) {
        schedule_retry(outcome, *record);  // last_hash kept: the same content is converted again.
        break;
      }
      retries_.erase(record->source);
      record->last_hash = outcome.content_hash;
      record->dependencies = outcome.dependencies;
      log_line("rejected " + id + " in " + milliseconds(outcome.duration) + ": " +
               first_error(outcome.diagnostics) +
               (record->live ? "; still serving revision " + std::to_string(record->revisions) : ""));
      // A newer save already waits: the rejected content is superseded, so say nothing of it.
      if (!record->again) {
        publisher_->publish(channel(id, "ERROR"),
                            make_model_error(*record, outcome.content_hash, outcome.diagnostics, config_.max_chunk_bytes));
      }
      break;
    case ConversionOutcome::Kind::kVanished: {
      retries_.erase(outcome.source);
      if (regular_file_below(root_of(outcome.source), outcome.source)) {
        // Recreated while its conversion found it gone: convert the new file.
        settle_.touch(outcome.source.string(), Clock::now());
        return;
      }
      drop_model(outcome.source, outcome.duration);
      return;
    }
  }
  if (record->again) {
    record->again = false;
    settle_.touch(record->source.string(), Clock::now());
  }
}

std::size_t Daemon::publish_model(const ModelRecord& record) {
  if (!record.live) return 0;
  // The report comes first: a description is only ever published with its verdict.
  if (record.live->validation) {
    publisher_->publish(channel(record.id, "VALIDATION"),
                        make_validation_report(record.id, record.revisions, record.live->content_hash,
                                               *record.live->validation, config_.max_chunk_bytes));
  }
  // The manifest before the description: a subscriber that has the description knows what to fetch.
  if (!record.live->files.empty()) {
    for (const auto& part : make_manifests(record.id, record.revisions, record.live->content_hash, record.live->files,
                                           config_.max_chunk_bytes)) {
      publisher_->publish(channel(record.id, "MANIFEST"), part);
    }
  }
  const auto messages = make_description(record, config_.max_chunk_bytes);
  for (const auto& chunk : messages.json_chunks) publisher_->publish(channel(record.id, "DESCRIPTION_CHUNK"), chunk);
  for (const auto& chunk : messages.urdf_chunks) publisher_->publish(channel(record.id, "URDF_CHUNK"), chunk);
  publisher_->publish(channel(record.id, "DESCRIPTION"), messages.description);
  for (const auto& table : make_inertia_tables(record, config_.max_chunk_bytes)) {
    publisher_->publish(channel(record.id, "INERTIA"), table);
  }
  return 1;
}

std::size_t Daemon::publish_all() {
  std::size_t count = 0;
  for (const auto& [source, record] : registry_.all()) count += publish_model(record);
  return count;
}

void Daemon::publish_status() {
  rdtf::status_t status;
  status.utime = now_utime();
  status.version = "rdtfd 0.1.0";
  status.pid = static_cast<std::int32_t>(::getpid());
  status.uptime = std::chrono::duration<double>(Clock::now() - started_).count();
  status.num_watched_dirs = static_cast<std::int32_t>(config_.watch.size());
  status.conversions = counters_.conversions;
  status.rejections = counters_.rejections;
  status.skipped_unchanged = counters_.skipped_unchanged;
  status.rescans = counters_.rescans;
  std::int32_t pending = static_cast<std::int32_t>(settle_.size());
  for (const auto& [source, record] : registry_.all()) {
    if (record.live) status.model_ids.push_back(record.id);
    if (record.in_flight) ++pending;
  }
  pending += static_cast<std::int32_t>(retries_.size());
  status.pending = pending;
  status.num_models = static_cast<std::int32_t>(status.model_ids.size());
  status.dropped_messages = static_cast<std::int64_t>(bus_.dropped());
  status.coalesced_requests = static_cast<std::int64_t>(request_throttle_.coalesced());
  status.send_queue_bytes = static_cast<std::int64_t>(publisher_->queued_bytes());
  status.send_dropped = static_cast<std::int64_t>(publisher_->dropped());
  status.live_real_time_factor = 0;  // lcm-gen leaves fields uninitialised.
  status.simulations_behind = 0;
  status.simulations_failed = 0;
  const BlobCounters& blobs = blobs_.counters();
  status.blob_requests = blobs.requests;
  status.blob_chunks_sent = blobs.chunks_sent;
  status.blob_bytes_sent = blobs.bytes_sent;
  status.blob_unavailable = blobs.unavailable;
  status.blob_requests_dropped = blobs.dropped + static_cast<std::int64_t>(bus_.blob_requests_undecodable());
  if (simulation_) {
    const LiveTiming timing = simulation_->timing();
    status.live_real_time_factor = timing.real_time_factor;
    status.simulations_behind = timing.behind;
    status.simulations_failed = static_cast<std::int64_t>(timing.failed);
  }
  // Ahead of anything queued: the heartbeat stays on time under any backlog.
  publisher_->publish(config_.channel_prefix + "/STATUS", status, Publisher::Priority::kUrgent);
}

// BusInput catches what its handlers throw (counted and logged as drops); these catch the rest, so
// that no exception unwinds through liblcm's C frames.
void Daemon::on_request_datagram(const lcm::ReceiveBuffer* buffer, const std::string& channel) noexcept {
  try {
    bus_.request_datagram(channel, buffer->data, buffer->data_size);
  } catch (...) {
    handler_failed();
  }
}

void Daemon::on_command_datagram(const lcm::ReceiveBuffer* buffer, const std::string& channel) noexcept {
  try {
    bus_.command_datagram(channel, buffer->data, buffer->data_size);
  } catch (...) {
    handler_failed();
  }
}

void Daemon::on_blob_request_datagram(const lcm::ReceiveBuffer* buffer, const std::string& channel) noexcept {
  try {
    bus_.blob_request_datagram(channel, buffer->data, buffer->data_size);
  } catch (...) {
    handler_failed();
  }
}

void Daemon::handler_failed() noexcept {
  ++handler_failures_;
  try {
    log_line("an LCM handler failed outside the bus input (" + std::to_string(handler_failures_) + " since start)");
  } catch (...) {
  }
}

void Daemon::on_request(const rdtf::request_t& request) {
  // Only ids of models that exist are remembered by the throttle, so a flood of made-up ids
  // costs nothing.
  if (!request.model_id.empty() && registry_.find_id(request.model_id) == nullptr) return;
  if (!request_throttle_.admit(request.model_id, Clock::now())) return;
  // Cut, not escaped: log_line escapes every line it writes (escaping here too would double it).
  answer_request(request.model_id, request.requester.substr(0, 80));
}

// `requester` is already escaped for the log (it comes from the bus).
void Daemon::answer_request(const std::string& model_id, const std::string& requester) {
  const auto start = Clock::now();
  if (model_id.empty()) {
    const std::size_t count = publish_all();
    log_line("republished every model on request of '" + requester + "' (" + std::to_string(count) +
             " models), queued in " + since(start));
    return;
  }
  if (ModelRecord* record = registry_.find_id(model_id)) {
    publish_model(*record);
    log_line("republished " + record->id + " on request of '" + requester + "', queued in " + since(start));
  }
}

// Requests that came while the same model's last answer was recent: one answer for all of them.
void Daemon::answer_deferred_requests(Clock::time_point now) {
  for (const std::string& model_id : request_throttle_.take_due(now)) {
    answer_request(model_id, "(repeated requests, " + std::to_string(request_throttle_.coalesced()) +
                                 " answered together since start)");
  }
}

void Daemon::start_simulation_host() {
  simulation_.reset();
  if (!config_.simulate) return;
  SimulationHostOptions options;
  options.lcm_url = config_.lcm_url;
  options.channel_prefix = config_.channel_prefix;
  options.simulation = simulation_options(config_);
  options.state_rate_hz = config_.state_rate_hz;
  options.real_time_factor = config_.real_time_factor;
  options.joint_command_lifetime =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(config_.joint_command_timeout_s));
  simulation_ = std::make_unique<SimulationHost>(options);
  for (const auto& [source, record] : registry_.all()) {
    const bool usable = record.live && !(record.live->validation && !record.live->validation->passed);
    if (usable) simulation_->load(record.id, record.revisions, record.live->content_hash, record.live->robot);
  }
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
  config_ = std::move(*fresh);
  settle_.set_settle(config_.settle);
  settle_.set_max_open_wait(config_.max_open_wait);
  if (lcm_changed && !connect_lcm(error)) log_line("SIGHUP: " + error);
  publisher_->set_rate(config_.chunk_rate_bytes_per_s);
  blobs_.set_max_message_bytes(config_.max_chunk_bytes);
  read_budget_->set_capacity(config_.max_read_bytes_in_flight);
  if (simulation_changed) start_simulation_host();
  // New conversion settings (density, limits) may change any model: convert them all again. A
  // model whose result comes out the same keeps its revision (apply), and a reload that changes
  // no conversion setting converts nothing: the rescan finds every content unchanged.
  if (conversion_changed) {
    for (auto& [source, record] : registry_.all()) record.last_hash.clear();
  }
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
  auto now = Clock::now();
  // Sleep until the earliest of: a model settles, the publisher may send, a periodic message.
  Clock::time_point wake = now + max_wait;
  blobs_.pump(*publisher_, config_.channel_prefix);
  if (blobs_.ready(*publisher_)) wake = now;  // Files to check, or room in the send queue for chunks.
  if (auto deadline = settle_.next_deadline()) wake = std::min(wake, *deadline);
  if (auto send = publisher_->drain(now)) wake = std::min(wake, *send);
  if (config_.republish_period.count() > 0) wake = std::min(wake, next_republish_);
  for (const auto& [source, retry] : retries_) wake = std::min(wake, retry.due);
  if (watches_failing_) wake = std::min(wake, next_watch_retry_);
  if (!pending_events_.empty()) wake = now;  // A burst still being handled: no sleep.
  wake = std::min(wake, next_status_);
  if (auto deferred = request_throttle_.next_due()) wake = std::min(wake, *deferred);
  const auto timeout = std::chrono::duration_cast<std::chrono::milliseconds>(wake - now).count();

  pollfd fds[4] = {{watcher_.fd(), POLLIN, 0}, {lcm_->getFileno(), POLLIN, 0},
                   {wake_fd_, POLLIN, 0}, {signal_fd_, POLLIN, 0}};
  const int ready = ::poll(fds, 4, static_cast<int>(std::max<long long>(timeout, 0) + (timeout > 0 ? 1 : 0)));
  if (ready > 0) {
    if (fds[3].revents & POLLIN) handle_signals();
    if (fds[0].revents & POLLIN) handle_file_events();
    if (fds[2].revents & POLLIN) handle_outcomes(kOutcomesPerTurn);
    // Every datagram waiting (up to a bound), so that requests that came together are answered
    // together: identical blob requests then share one pass.
    if (fds[1].revents & POLLIN) {
      for (std::size_t handled = 0; handled < kDatagramsPerTurn && lcm_->handleTimeout(0) > 0; ++handled) {
      }
    }
  }
  process_file_events(kFileEventsPerTurn);
  now = Clock::now();
  check_watches(now);
  retry_due(now);
  dispatch_due();
  answer_deferred_requests(now);
  if (config_.republish_period.count() > 0 && now >= next_republish_) {
    const auto start = Clock::now();
    const std::size_t count = publish_all();
    // One line per period, not per model: it repeats for as long as the daemon runs.
    log_line("republished " + std::to_string(count) + " models (every " +
             std::to_string(config_.republish_period.count()) + " ms), queued in " + since(start));
    next_republish_ = now + config_.republish_period;
  }
  if (now >= next_status_) {
    publish_status();
    next_status_ = now + config_.status_period;
  }
  blobs_.pump(*publisher_, config_.channel_prefix);
  publisher_->drain(Clock::now());
}

int Daemon::run() {
  while (!stop_) step(std::chrono::milliseconds(1000));
  // Let conversions in flight finish: their outputs are written atomically, so nothing is
  // half-done either way, and waiting keeps the registry consistent with the output folder. A
  // dynamics check in progress is cancelled (it writes nothing before its verdict), and its
  // revision, never judged, is dropped.
  cancel_validations_ = true;
  {
    std::lock_guard lock(mutex_);
    jobs_.clear();
    workers_stop_ = true;
  }
  work_ready_.notify_all();
  for (auto& worker : workers_) worker.join();
  workers_.clear();
  {
    std::lock_guard lock(mutex_);
    std::erase_if(outcomes_, [](const ConversionOutcome& outcome) { return outcome.cancelled; });
  }
  handle_outcomes(std::numeric_limits<std::size_t>::max());
  const auto flush_until = Clock::now() + std::chrono::seconds(2);
  while (publisher_->queued() > 0 && Clock::now() < flush_until) {
    if (auto next = publisher_->drain(Clock::now())) std::this_thread::sleep_until(*next);
  }
  log_line("rdtfd stopped");
  return 0;
}

}  // namespace rdtf::daemon
