#include "watcher.h"

#include <sys/inotify.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <optional>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <fstream>
#include <string>
#include <string_view>

#include "rdtf/atomic_file.h"

namespace rdtf::daemon {
namespace {

constexpr std::uint32_t kFolderMask = IN_CLOSE_WRITE | IN_MODIFY | IN_CREATE | IN_DELETE | IN_ATTRIB |
                                      IN_MOVED_FROM | IN_MOVED_TO | IN_DELETE_SELF |
                                      IN_MOVE_SELF | IN_ONLYDIR | IN_DONT_FOLLOW | IN_EXCL_UNLINK;

std::string watch_error(const std::filesystem::path& folder) {
  const int error = errno;
  std::string text = "cannot watch " + folder.string() + ": " + std::strerror(error);
  if (error == ENOSPC) {
    text += " (inotify watches exhausted: raise /proc/sys/fs/inotify/max_user_watches)";
  }
  return text;
}

// Test seam: when RDTFD_TEST_INOTIFY_LIMIT_FILE names a file holding a number N, at most N
// folders are watched and further inotify_add_watch calls fail with ENOSPC, as when the kernel's
// max_user_watches is reached (that limit is system-wide here, so tests must not lower it).
// Without the file, no limit is applied: deleting it "raises the limit".
std::optional<std::size_t> injected_watch_limit() {
  const char* file = std::getenv("RDTFD_TEST_INOTIFY_LIMIT_FILE");
  if (file == nullptr) return std::nullopt;
  std::ifstream in(file);
  std::size_t limit = 0;
  if (!(in >> limit)) return std::nullopt;
  return limit;
}

// A stage folder of an output being written (StagedOutput: ".<name>.<pid>-<random>.tmp"), e.g.
// of `rdtf convert` writing into a watched folder: its files are moved out when whole.
bool is_staging_folder(const std::filesystem::path& folder) {
  return rdtf::temporary_writer_pid(folder.filename().string()).has_value();
}

// Hidden folders (.git, a desktop's .Trash, rdtfd's own .rdtfd-state when the output lies in a
// watched folder) hold no models: not watched, not listed. (A stage folder is hidden too.)
// Whether a name just created is whole at once: not a regular file (a symbolic link, a FIFO, a
// socket, a device), or a regular file with another name (a hard link: link() makes a name for
// bytes already written). A file opened with O_CREAT has one name and may still be written.
bool made_whole(const std::filesystem::path& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return false;  // Gone already: its removal follows.
  return !S_ISREG(st.st_mode) || st.st_nlink > 1;
}

bool skipped_folder(const std::filesystem::path& folder) {
  const std::string name = folder.filename().string();
  return (!name.empty() && name.front() == '.') || is_staging_folder(folder);
}

}  // namespace

int InotifyWatcher::add_watch(const std::filesystem::path& folder) {
  if (const auto limit = injected_watch_limit(); limit && folders_.size() >= *limit) {
    errno = ENOSPC;
    return -1;
  }
  return ::inotify_add_watch(fd_, folder.c_str(), kFolderMask);
}

InotifyWatcher::InotifyWatcher() : fd_(::inotify_init1(IN_NONBLOCK | IN_CLOEXEC)) {}

InotifyWatcher::~InotifyWatcher() {
  if (fd_ >= 0) ::close(fd_);
}

void InotifyWatcher::clear() {
  for (const auto& [wd, folder] : folders_) ::inotify_rm_watch(fd_, wd);
  folders_.clear();
  unwatched_.clear();
  roots_.clear();
}

namespace {

// One more reason in `error` (one log line), unless it says that already; beyond about 2 KB the
// rest are left out, with a word: a tree of folders that all fail (a chain deeper than PATH_MAX)
// made one line of 231 KB repeating the same reason. The line stays within about 3 KB.
void add_reason(std::string& error, std::string why) {
  static constexpr std::string_view kMore = "; and more folders alike";
  // A path of kilobytes (PATH_MAX is 4096) keeps its head and its tail.
  if (why.size() > 1024) why = why.substr(0, 480) + "..." + why.substr(why.size() - 480);
  if (error.find(why) != std::string::npos || error.ends_with(kMore)) return;
  if (error.size() + why.size() > 2048 && !error.empty()) {
    error += kMore;
    return;
  }
  if (!error.empty()) error += "; ";
  error += why;
}

}  // namespace

void InotifyWatcher::add_folder(const std::filesystem::path& folder,
                                std::vector<std::filesystem::path>& files, std::string& error) {
  // Watch first, then list: a file created in between shows up in both, never in neither.
  const int wd = add_watch(folder);
  if (wd < 0) {
    const bool missing = errno == ENOENT || errno == ENOTDIR;
    // A subfolder that went between its listing and its watch is simply gone (its parent's events
    // tell); only a watched folder itself is looked for again.
    if (missing && std::find(roots_.begin(), roots_.end(), folder) == roots_.end()) return;
    const std::string why = missing ? "cannot watch " + folder.string() + ": it is missing" : watch_error(folder);
    add_reason(error, why);
    // Still list it: its models are converted now, and seen again when a retry can watch it.
    unwatched_.push_back({folder, missing, why});
  } else {
    folders_[wd] = folder;
  }
  std::error_code ec;
  for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code type_error;
    if (it->is_directory(type_error) && !it->is_symlink(type_error)) {
      if (skipped_folder(it->path())) continue;
      add_folder(it->path(), files, error);
    } else if (it->is_regular_file(type_error)) {
      files.push_back(it->path());
    }
  }
  // A folder watched but not listed whole (out of descriptors: each level of the walk holds one)
  // hides its subfolders, which then went unwatched without a word (s106fd D4). It counts as not
  // watched, so that it is said and the walk is tried again, as for a watch that failed. A folder
  // gone meanwhile is its parent's event, not this.
  // errno values (the directory iterator's are the system's), compared and said without asking
  // the error's category: no call through a vtable where descriptors may have run out
  // (docs/notes/ubsan-descriptors.md).
  if (ec && wd >= 0 && ec.value() != ENOENT && ec.value() != ENOTDIR) {
    const std::string why = "cannot list " + folder.string() + ": " + std::strerror(ec.value());
    add_reason(error, why);
    unwatched_.push_back({folder, false, why});
  }
}

std::vector<std::filesystem::path> InotifyWatcher::watch_tree(const std::filesystem::path& root,
                                                              std::string& error) {
  std::vector<std::filesystem::path> files;
  roots_.push_back(root);
  add_folder(root, files, error);
  return files;
}

std::vector<FileEvent> InotifyWatcher::read_events(std::string& error) {
  std::vector<FileEvent> events;
  alignas(inotify_event) char buffer[64 * 1024];
  for (;;) {
    const ssize_t n = ::read(fd_, buffer, sizeof(buffer));
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno != EAGAIN) error = std::string("inotify read: ") + std::strerror(errno);
      break;
    }
    if (n == 0) break;
    for (ssize_t offset = 0; offset < n;) {
      const auto* event = reinterpret_cast<const inotify_event*>(buffer + offset);
      offset += static_cast<ssize_t>(sizeof(inotify_event) + event->len);
      // Events lost, or the file system of a watched folder unmounted (a USB disk, an NFS or sshfs
      // mount gone; IN_IGNORED follows for every watch on it): the rescan finds what is left.
      if (event->mask & (IN_Q_OVERFLOW | IN_UNMOUNT)) {
        events.push_back({FileEvent::Kind::kRescan, {}});
        continue;
      }
      const auto folder = folders_.find(event->wd);
      if (folder == folders_.end()) continue;
      if (event->mask & (IN_DELETE_SELF | IN_MOVE_SELF)) {
        // The folder itself went: its files are gone from our view. A subfolder's parent tells
        // of its deletion; a watched folder has no watched parent, so its deletion is the
        // rescan's to find (it then reports the folder missing and looks for it again).
        const bool root = std::find(roots_.begin(), roots_.end(), folder->second) != roots_.end();
        if ((event->mask & IN_MOVE_SELF) || root) events.push_back({FileEvent::Kind::kRescan, {}});
        continue;
      }
      if (event->mask & IN_IGNORED) {
        folders_.erase(folder);
        continue;
      }
      if (event->len == 0) continue;
      const std::filesystem::path path = folder->second / event->name;
      if (event->mask & IN_ISDIR) {
        if (skipped_folder(path)) continue;
        // A subfolder's permissions changed (chmod 755 on a folder that could not be searched):
        // what it holds may be readable now.
        if (event->mask & IN_ATTRIB) {
          events.push_back({FileEvent::Kind::kRescan, {}});
          continue;
        }
        if (event->mask & (IN_CREATE | IN_MOVED_TO)) {
          std::vector<std::filesystem::path> files;
          add_folder(path, files, error);
          for (auto& file : files) events.push_back({FileEvent::Kind::kWritten, std::move(file)});
        } else if (event->mask & (IN_DELETE | IN_MOVED_FROM)) {
          // Files of a folder moved out of the tree: a rescan finds which models went.
          events.push_back({FileEvent::Kind::kRescan, {}});
        }
        continue;
      }
      if (event->mask & (IN_DELETE | IN_MOVED_FROM)) {
        events.push_back({FileEvent::Kind::kRemoved, path});
      } else if (event->mask & (IN_CLOSE_WRITE | IN_MOVED_TO)) {
        events.push_back({FileEvent::Kind::kWritten, path});
      } else if (event->mask & IN_ATTRIB) {
        events.push_back({FileEvent::Kind::kAttributes, path});
      } else if ((event->mask & IN_CREATE) && made_whole(path)) {
        // A symbolic link, a hard link, a FIFO: made whole by one call, never written, so no
        // close follows. Taken as open, it held its folder back for max_open_wait.
        events.push_back({FileEvent::Kind::kWritten, path});
      } else if (event->mask & (IN_MODIFY | IN_CREATE)) {
        // Created or written and still open: a close (IN_CLOSE_WRITE) will follow.
        events.push_back({FileEvent::Kind::kModified, path});
      }
    }
  }
  return events;
}

}  // namespace rdtf::daemon
