// InotifyWatcher (daemon/watcher.h) on a real folder, in-process: which events the ways files get
// saved, renamed, deleted and moved give. The daemon's handling of those events is stepped with a
// fake watcher in daemon_loop_test.cc; together they cover a save from the kernel to the bus.
#include "watcher.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;
using Kind = FileEvent::Kind;

class Watcher : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(watcher_.ok());
    fs::create_directories(tmp_ / "watch");
    root_ = fs::canonical(tmp_ / "watch");
  }
  // What the kernel queued so far, as "KIND name" (inotify queues an event when the call that
  // causes it returns: no waiting).
  std::vector<std::string> events() {
    std::string error;
    std::vector<std::string> out;
    for (const FileEvent& event : watcher_.read_events(error)) {
      const char* kind = event.kind == Kind::kModified  ? "modified"
                         : event.kind == Kind::kWritten ? "written"
                         : event.kind == Kind::kRemoved ? "removed"
                                                        : "rescan";
      out.push_back(std::string(kind) + " " + event.path.lexically_relative(root_).string());
    }
    EXPECT_EQ(error, "");
    return out;
  }
  std::vector<std::string> watch() {
    std::string error;
    std::vector<std::string> files;
    for (const auto& file : watcher_.watch_tree(root_, error)) files.push_back(file.lexically_relative(root_).string());
    EXPECT_EQ(error, "");
    std::sort(files.begin(), files.end());
    return files;
  }

  rdtf::testing::TempDir tmp_;
  fs::path root_;
  InotifyWatcher watcher_;
};

using Events = std::vector<std::string>;

TEST_F(Watcher, TheInitialScanListsEveryFileBelowTheRoot) {
  fs::create_directories(root_ / "sub" / "deep");
  rdtf::testing::write_file(root_ / "a.gltf", "a");
  rdtf::testing::write_file(root_ / "sub" / "deep" / "b.glb", "b");
  EXPECT_EQ(watch(), (Events{"a.gltf", "sub/deep/b.glb"}));
  EXPECT_EQ(watcher_.watch_count(), 3u);
  EXPECT_TRUE(events().empty());
}

// Each level of the walk holds a descriptor. Out of them, a folder that is watched but cannot be
// listed hid its subfolders, which went unwatched without a word (s106fd D4): now it is unwatched,
// with the reason, so rdtfd says so and walks again; with descriptors back, every folder is seen.
// Under the sanitizers, UBSan's vptr check opens a pipe at the first call through a (vtable, type)
// it has not met, and with no descriptor free reports a false "invalid vptr"
// (docs/notes/ubsan-descriptors.md): the same walk is made once first with descriptors free, so
// that the starved walk meets only calls already checked.
TEST_F(Watcher, AFolderThatCannotBeListedIsUnwatchedNotSkipped) {
  fs::create_directories(root_ / "sub" / "deep");
  rdtf::testing::write_file(root_ / "a.gltf", "a");
  rdtf::testing::write_file(root_ / "sub" / "deep" / "b.glb", "b");
  EXPECT_EQ(watch(), (Events{"a.gltf", "sub/deep/b.glb"}));
  watcher_.clear();
  std::string error;
  std::vector<fs::path> files;
  {
    const rdtf::testing::DescriptorHeadroom one(1);  // the root's listing only
    ASSERT_TRUE(one.ok());
    files = watcher_.watch_tree(root_, error);
  }
  EXPECT_EQ(files, (std::vector<fs::path>{root_ / "a.gltf"}));
  ASSERT_EQ(watcher_.unwatched().size(), 1u) << error;
  EXPECT_EQ(watcher_.unwatched()[0].folder, root_ / "sub");
  EXPECT_FALSE(watcher_.unwatched()[0].missing);
  EXPECT_EQ(watcher_.unwatched()[0].why, "cannot list " + (root_ / "sub").string() + ": Too many open files");
  EXPECT_EQ(error, watcher_.unwatched()[0].why);
  watcher_.clear();
  EXPECT_EQ(watch(), (Events{"a.gltf", "sub/deep/b.glb"}));
  EXPECT_TRUE(watcher_.unwatched().empty());
  EXPECT_EQ(watcher_.watch_count(), 3u);
}

// Removes what `dir` (an open folder) holds, by descriptors: paths below it may be longer than
// PATH_MAX, which std::filesystem::remove_all cannot reach.
void remove_below(int dir) {
  const int listing = ::dup(dir);
  ASSERT_GE(listing, 0);
  DIR* entries = ::fdopendir(listing);
  ASSERT_NE(entries, nullptr);
  std::vector<std::string> names;
  while (const dirent* entry = ::readdir(entries)) {
    const std::string name = entry->d_name;
    if (name != "." && name != "..") names.push_back(name);
  }
  ::closedir(entries);
  for (const std::string& name : names) {
    const int sub = ::openat(dir, name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (sub >= 0) {
      remove_below(sub);
      ::close(sub);
      ASSERT_EQ(::unlinkat(dir, name.c_str(), AT_REMOVEDIR), 0) << name;
    } else {
      ASSERT_EQ(::unlinkat(dir, name.c_str(), 0), 0) << name;
    }
  }
}

// Folders whose paths are longer than PATH_MAX cannot be watched, each for the same reason with
// its own path of 4 KB: the reasons are one log line of a readable length (it reached 231 KB).
TEST_F(Watcher, FoldersThatAllFailAreOneLineOfReadableLength) {
  const std::string name(40, 'd'), leaf(250, 'f');
  int dir = ::open(root_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  ASSERT_GE(dir, 0);
  const int top = ::dup(dir);
  // A folder whose path is 3850 to 3890 bytes long, short of PATH_MAX (4096), then 30 folders in
  // it whose paths are beyond it (251 bytes more).
  for (std::size_t length = root_.string().size(); length + name.size() + 1 <= 3890; length += name.size() + 1) {
    ASSERT_EQ(::mkdirat(dir, name.c_str(), 0755), 0);
    const int next = ::openat(dir, name.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    ASSERT_GE(next, 0);
    ::close(dir);
    dir = next;
  }
  for (int k = 0; k < 30; ++k) {
    ASSERT_EQ(::mkdirat(dir, (leaf.substr(2) + (k < 10 ? "0" : "") + std::to_string(k)).c_str(), 0755), 0);
  }
  ::close(dir);
  std::string error;
  watcher_.watch_tree(root_, error);
  EXPECT_EQ(watcher_.unwatched().size(), 30u);
  EXPECT_NE(error.find("File name too long"), std::string::npos) << error.substr(0, 300);
  EXPECT_LT(error.size(), 2048u + 1024u + 30u) << "reasons past 2 KB are left out, with a word";
  EXPECT_TRUE(error.ends_with("; and more folders alike")) << error.substr(error.size() - std::min<std::size_t>(error.size(), 100));
  remove_below(top);
  ::close(top);
}

TEST_F(Watcher, AnInPlaceSaveIsModifiedWhileOpenThenWrittenWhenClosed) {
  watch();
  const int fd = ::open((root_ / "a.gltf").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::write(fd, "part", 4), 4);
  EXPECT_EQ(events(), (Events{"modified a.gltf", "modified a.gltf"}));  // Created, written.
  ASSERT_EQ(::write(fd, "more", 4), 4);
  EXPECT_EQ(events(), (Events{"modified a.gltf"}));
  ::close(fd);
  EXPECT_EQ(events(), (Events{"written a.gltf"}));
  // Appends, each opened and closed: one written each.
  for (int i = 0; i < 2; ++i) {
    const int append = ::open((root_ / "a.gltf").c_str(), O_WRONLY | O_APPEND);
    ASSERT_EQ(::write(append, "x", 1), 1);
    ::close(append);
  }
  EXPECT_EQ(events(), (Events{"modified a.gltf", "written a.gltf", "modified a.gltf", "written a.gltf"}));
}

// A link or a FIFO is whole when made (no write, so no close, follows): written at once. Taken as
// open, it used to hold its folder back for max_open_wait (5 s).
TEST_F(Watcher, ALinkOrAFifoIsWrittenWhenMade) {
  rdtf::testing::write_file(root_ / "a.gltf", "a");
  watch();
  fs::create_symlink("a.gltf", root_ / "soft.gltf");
  fs::create_hard_link(root_ / "a.gltf", root_ / "hard.gltf");
  ASSERT_EQ(::mkfifo((root_ / "pipe.gltf").c_str(), 0644), 0);
  EXPECT_EQ(events(), (Events{"written soft.gltf", "written hard.gltf", "written pipe.gltf"}));
  // A new file of one name may still be written: modified until closed, as before.
  const int fd = ::open((root_ / "b.gltf").c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
  ASSERT_GE(fd, 0);
  EXPECT_EQ(events(), (Events{"modified b.gltf"}));
  ::close(fd);
  EXPECT_EQ(events(), (Events{"written b.gltf"}));
}

TEST_F(Watcher, ASaveByRenameIsTheTemporaryWrittenThenTheModelWritten) {
  rdtf::testing::write_file(root_ / "a.gltf", "v1");
  watch();
  rdtf::testing::write_file(root_ / "a.gltf.tmp", "v2");
  fs::rename(root_ / "a.gltf.tmp", root_ / "a.gltf");
  const Events got = events();
  ASSERT_FALSE(got.empty());
  // The temporary's events (ignored by the daemon by name), then the model's: moved to = written.
  EXPECT_EQ(got.back(), "written a.gltf");
  EXPECT_EQ(got[got.size() - 2], "removed a.gltf.tmp");
}

TEST_F(Watcher, ARenameIsARemovalAndAWriteAndADeleteARemoval) {
  rdtf::testing::write_file(root_ / "a.gltf", "a");
  watch();
  fs::rename(root_ / "a.gltf", root_ / "b.gltf");
  EXPECT_EQ(events(), (Events{"removed a.gltf", "written b.gltf"}));
  fs::remove(root_ / "b.gltf");
  EXPECT_EQ(events(), (Events{"removed b.gltf"}));
}

TEST_F(Watcher, MovingAModelOutIsARemovalAndMovingOneInAWrite) {
  fs::create_directories(tmp_ / "elsewhere");
  rdtf::testing::write_file(root_ / "a.gltf", "a");
  rdtf::testing::write_file(tmp_ / "elsewhere" / "b.gltf", "b");
  watch();
  fs::rename(root_ / "a.gltf", tmp_ / "elsewhere" / "a.gltf");
  fs::rename(tmp_ / "elsewhere" / "b.gltf", root_ / "b.gltf");
  EXPECT_EQ(events(), (Events{"removed a.gltf", "written b.gltf"}));
}

TEST_F(Watcher, ANewFolderIsWatchedAndTheFilesAlreadyInItReported) {
  watch();
  fs::create_directories(tmp_ / "staging" / "z");
  rdtf::testing::write_file(tmp_ / "staging" / "z" / "z.gltf", "z");
  fs::rename(tmp_ / "staging" / "z", root_ / "moved");
  EXPECT_EQ(events(), (Events{"written moved/z.gltf"}));
  rdtf::testing::write_file(root_ / "moved" / "y.gltf", "y");  // Watched from now on.
  EXPECT_EQ(events(), (Events{"modified moved/y.gltf", "modified moved/y.gltf", "written moved/y.gltf"}));
  // A folder moved out: a rescan finds which models went (asked twice: by the parent's event and
  // by the folder's own; the daemon's loop does one for all the rescans waiting).
  fs::rename(root_ / "moved", tmp_ / "gone");
  EXPECT_EQ(events(), (Events{"rescan ", "rescan "}));
}

}  // namespace
}  // namespace rdtf::daemon
