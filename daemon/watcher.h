// Recursive directory watching with inotify. Turns kernel events into what the daemon cares
// about: a file changed (or is being written), a file went away, the view was lost (rescan).
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace rdtf::daemon {

struct FileEvent {
  enum class Kind {
    kModified,  // Written but not yet closed: an in-place save in progress.
    kWritten,   // Closed after writing, created, or moved in: content may be new.
    kRemoved,   // Deleted or moved out.
    kAttributes,  // Permissions or hard links changed: a file refused for them may be read now.
    kRescan,    // Events were lost (queue overflow) or a watched tree moved: rescan everything.
  };
  Kind kind;
  std::filesystem::path path;  // Absolute; empty for kRescan.
};

// Folders found since the last clear() that could not be watched (their files were still
// listed): changes there go unseen until a later watch_tree succeeds. `missing`: the folder was
// not there (a watched folder deleted), rather than inotify refusing the watch.
struct UnwatchedFolder {
  std::filesystem::path folder;
  bool missing = false;
  std::string why;  // "cannot watch <folder>: <the system's reason>".
};

// What the daemon needs of a watcher (ports.h): inotify here, made-up events in tests.
class FileWatcher {
 public:
  virtual ~FileWatcher() = default;
  virtual bool ok() const = 0;
  // Readable when events wait; -1 when there is nothing to poll (read_events() every turn).
  virtual int fd() const = 0;
  // Watches `root` and every folder below it. Returns the files found (for the initial scan);
  // `error` tells of folders that could not be watched (e.g. max_user_watches reached).
  virtual std::vector<std::filesystem::path> watch_tree(const std::filesystem::path& root, std::string& error) = 0;
  // Drops every watch (before a full rescan or a config reload).
  virtual void clear() = 0;
  // What happened since the last call (non-blocking).
  virtual std::vector<FileEvent> read_events(std::string& error) = 0;
  virtual std::size_t watch_count() const = 0;
  virtual const std::vector<UnwatchedFolder>& unwatched() const = 0;
};

class InotifyWatcher final : public FileWatcher {
 public:
  InotifyWatcher();
  ~InotifyWatcher() override;
  InotifyWatcher(const InotifyWatcher&) = delete;
  InotifyWatcher& operator=(const InotifyWatcher&) = delete;

  bool ok() const override { return fd_ >= 0; }
  int fd() const override { return fd_; }

  // Watches `root` and every folder below it. Returns the files found (for the initial scan);
  // `error` tells of folders that could not be watched (e.g. max_user_watches reached).
  std::vector<std::filesystem::path> watch_tree(const std::filesystem::path& root, std::string& error) override;

  // Drops every watch (before a full rescan or a config reload).
  void clear() override;

  // Reads what the kernel has queued (non-blocking). New folders are watched as they appear and
  // the files already in them reported as written.
  std::vector<FileEvent> read_events(std::string& error) override;

  std::size_t watch_count() const override { return folders_.size(); }
  using Unwatched = UnwatchedFolder;
  const std::vector<Unwatched>& unwatched() const override { return unwatched_; }

 private:
  void add_folder(const std::filesystem::path& folder, std::vector<std::filesystem::path>& files,
                  std::string& error);
  int add_watch(const std::filesystem::path& folder);

  int fd_ = -1;
  std::map<int, std::filesystem::path> folders_;  // watch descriptor -> folder
  std::vector<Unwatched> unwatched_;
  std::vector<std::filesystem::path> roots_;  // Given to watch_tree since the last clear().
};

}  // namespace rdtf::daemon
