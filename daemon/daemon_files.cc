// rdtfd's view of the watched folders: file events, rescans, which model a file belongs to, and
// the output folder's leftovers of an earlier run.
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <fstream>
#include <optional>
#include <set>

#include "daemon.h"
#include "daemon_internal.h"
#include "messages.h"
#include "rdtf/atomic_file.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/gltf.h"
#include "rdtf/urdf.h"

namespace rdtf::daemon {
namespace {

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

}  // namespace

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
void Daemon::check_watches(Clock::time_point now) {
  const auto& unwatched = watcher_->unwatched();
  if (unwatched.empty()) {
    if (watches_failing_) log_line("every folder is watched again");
    watches_failing_ = false;
    watch_retries_ = 0;
    return;
  }
  if (!watches_failing_) {
    watches_failing_ = true;
    next_watch_retry_ = now + kWatchRetryPeriod;
    for (const auto& [folder, missing, why] : unwatched) {
      if (missing) {
        log_line("watched folder " + folder.string() + " is missing; looking for it every second");
        publish_daemon_error(codes::WATCH_FAILED, folder.string(),
                             "cannot watch " + folder.string() +
                                 ": it is missing (deleted or moved away); its models were removed, and "
                                 "it is looked for every second and watched again when it is back");
      } else {
        publish_daemon_error(codes::WATCH_FAILED, folder.string(),
                             why + "; what could be read of it was converted once, and the folder is tried "
                                   "again every second for a while, then less often (up to once a minute)");
      }
    }
    return;
  }
  if (now >= next_watch_retry_) {
    // Every second at first (a limit raised, a folder made again); then, for a folder that stays
    // unwatchable (its permissions), less often, since each retry rescans every folder.
    // A missing folder is looked for every second (a stat each, docs/daemon.md); only a folder
    // that is there and cannot be watched backs off.
    const bool all_missing = std::all_of(unwatched.begin(), unwatched.end(), [](const auto& entry) { return entry.missing; });
    watch_retries_ = all_missing ? 0 : watch_retries_ + 1;
    auto period = kWatchRetryPeriod;
    for (int k = 8; k < watch_retries_ && period < kWatchRetryLongest; ++k) period *= 2;
    next_watch_retry_ = now + std::min<Clock::duration>(period, kWatchRetryLongest);
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
  if (!relative.empty() && *relative.begin() != "..") return true;
  // Below a hidden folder of a watched folder (the watcher does not watch them; a rescan or an
  // event of a folder moved in may still name such a path).
  const auto in_root = path.lexically_relative(root_of(path));
  for (const auto& part : in_root.parent_path()) {
    const std::string folder = part.string();
    if (!folder.empty() && folder.front() == '.' && folder != "." && folder != "..") return true;
  }
  return false;
}

std::filesystem::path Daemon::root_of(const std::filesystem::path& source) const {
  for (const auto& root : config_.watch) {
    const auto relative = source.lexically_relative(root);
    if (!relative.empty() && *relative.begin() != "..") return root;
  }
  return source.parent_path();
}

void Daemon::note_change(const std::filesystem::path& path, FileChange change) {
  if (ignored(path)) return;
  const auto now = clock_->now();
  auto touch = [&](const std::filesystem::path& model) {
    if (ModelRecord* record = registry_.find(model)) {
      const bool was_quiet = !record->schedule.pending();
      const ModelActions actions =
          transition(*record, [&](ModelSchedule& schedule) { return schedule.file_changed(now, change); });
      // A save of a live model begins: SAVING, so that a viewer can make ready for the revision
      // that may follow (lcmtypes/rdtf_model_saving_t.lcm). A rescan touches every model and
      // announces nothing.
      if (was_quiet && record->schedule.pending() && record->live && !rescanning_) {
        publisher_->publish(channel(record->id, "SAVING"), make_model_saving(*record, config_.settle));
      }
      on_settling(*record, actions);
    }
  };
  if (is_model_file(path)) {
    if (registry_.find(path) == nullptr) {
      ModelRecord& record = registry_.ensure(path, choose_model_id(path));
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

bool Daemon::held_by_a_file_here(const std::filesystem::path& source) const {
  if (registry_.all().count(source) != 0 || !is_model_file(source) || ignored(source)) return false;
  const bool watched = std::any_of(config_.watch.begin(), config_.watch.end(), [&](const auto& root) {
    const auto relative = source.lexically_relative(root);
    return !relative.empty() && *relative.begin() != "..";
  });
  struct stat info {};
  return watched && ::lstat(source.c_str(), &info) == 0 && S_ISREG(info.st_mode);
}

// The id of the n-th file (from 1) whose name sanitises to `source`'s: the name, then "_2", "_3", ...
std::string Daemon::alike_id(const std::filesystem::path& source, int n) const {
  const std::size_t max_id = kMaxChannelLength - config_.channel_prefix.size() - 1 - kLongestKind;
  // Three characters kept free for a "_N" that tells apart ids that sanitise alike; from the 100th
  // on the suffix is longer and the name is shortened for it, or RDTF/<id>/DESCRIPTION_CHUNK
  // passed LCM's 63 characters, LCM refused every send on it and the send queue stopped behind it
  // (s100java D6).
  if (n <= 1) return model_id_for(source, config_.watch, max_id - 3);
  const std::string suffix = "_" + std::to_string(n);
  return (suffix.size() <= 3 ? model_id_for(source, config_.watch, max_id - 3)
                             : model_id_for(source, config_.watch, max_id - suffix.size())) +
         suffix;
}

// Ids that sanitise alike ("c 1.gltf", "c_1.gltf") are numbered as their files are found, which
// after a restart may be another order. Each file keeps the id an earlier run gave it (its revision
// state names the file), or subscribers following it would switch robots; an id whose state names
// another file still here is that file's. A file new to the folder takes the first id free of both:
// one whose file is gone (deleted while rdtfd was stopped), else one never used. Only names with
// such a history read more than one state: up to 16 unused ids past the last used one.
std::string Daemon::choose_model_id(const std::filesystem::path& source) const {
  std::optional<std::string> first_free;
  int unused_in_a_row = 0;
  for (int n = 1; n < 100000 && unused_in_a_row < 16; ++n) {
    const std::string id = alike_id(source, n);
    const bool live = registry_.find_id(id) != nullptr;
    ModelState state;
    std::string why;
    const auto loaded = RevisionStore::load(config_.output, id, state, why);
    // Out of descriptors no state says anything, and every one would fail alike (100,000 of them,
    // on the loop): the first id free of live models, as for a name without a history. Its state is
    // read when its first conversion starts (Daemon::state_known).
    if (loaded == RevisionStore::LoadResult::kUnavailable) break;
    if (loaded == RevisionStore::LoadResult::kLoaded && state.source == source.string()) {
      if (!live) return id;  // its own
      continue;
    }
    const bool used = loaded != RevisionStore::LoadResult::kAbsent;
    unused_in_a_row = used ? 0 : unused_in_a_row + 1;
    // An id no file ever held, the first: nothing of this name has a history.
    if (n == 1 && !used && !live) return id;
    const bool reserved = used && loaded == RevisionStore::LoadResult::kLoaded && held_by_a_file_here(state.source);
    if (!live && !reserved && !first_free) first_free = id;
  }
  if (first_free) return *first_free;
  // Past 100,000 alike names: the next id not live (ids may then move across restarts).
  int n = 1;
  while (registry_.find_id(alike_id(source, n)) != nullptr) ++n;
  return alike_id(source, n);
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
  watcher_->clear();
  std::vector<std::filesystem::path> files;
  for (const auto& root : config_.watch) {
    std::string error;
    auto found = watcher_->watch_tree(root, error);
    if (!error.empty()) log_line("watch error: " + error);
    files.insert(files.end(), found.begin(), found.end());
  }
  // Known models that are no longer there get converted too: the conversion finds them gone.
  const auto now = clock_->now();
  for (auto& [source, record] : registry_.all()) {
    const ModelActions actions =
        transition(record, [&](ModelSchedule& schedule) { return schedule.file_changed(now, FileChange::kTouched); });
    on_settling(record, actions);
  }
  rescanning_ = true;
  for (const auto& file : files) note_change(file, FileChange::kClosed);
  rescanning_ = false;
  start_prepared_jobs(now);
  log_line(std::string("rescan (") + why + "): " + std::to_string(files.size()) + " files, " +
           std::to_string(watcher_->watch_count()) + " folders watched");
}

void Daemon::handle_file_events() {
  std::string error;
  auto events = watcher_->read_events(error);
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
        if (!ignored(event.path)) open_for_writing_.opened(event.path, clock_->now());
        note_change(event.path, FileChange::kModified);
        break;
      case FileEvent::Kind::kWritten:
      case FileEvent::Kind::kRemoved:
        open_for_writing_.closed(event.path);
        note_change(event.path, FileChange::kClosed);
        break;
      case FileEvent::Kind::kAttributes:
        // chmod 644 on a file that could not be read, a second hard link removed: a model refused
        // for them converts now (an unchanged one is found so by its content hash). A writer that
        // still holds the file open still holds the model back (open_for_writing_).
        note_change(event.path, FileChange::kClosed);
        break;
    }
  }
  start_prepared_jobs(clock_->now());
}

}  // namespace rdtf::daemon
