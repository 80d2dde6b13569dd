// read_beneath (core/gltf/confined_files.h): what rdtfd makes of a model it cannot read. A model
// behind a folder that cannot be searched (chmod 000) is still there: refused, so that rdtfd keeps
// serving its last good revision, where "gone" would publish REMOVED. Root is not stopped by
// chmod 000, so as root the read runs in a child process as user nobody (65534).
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../core/gltf/confined_files.h"
#include "support/test_support.h"

namespace rdtf::internal {
namespace {

namespace fs = std::filesystem;

// read_beneath of `path` below `root` as an unprivileged user: the result, and `why` through a pipe.
std::pair<ReadBeneath, std::string> read_unprivileged(const fs::path& root, const fs::path& path) {
  const auto read = [&](std::string& why) {
    std::vector<std::uint8_t> out;
    return read_beneath(root, path, 1 << 20, out, why);
  };
  if (::geteuid() != 0) {
    std::string why;
    const ReadBeneath result = read(why);
    return {result, why};
  }
  int pipe_fds[2];
  EXPECT_EQ(::pipe(pipe_fds), 0);
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(pipe_fds[0]);
    if (::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(100);
    std::string why;
    const ReadBeneath result = read(why);
    (void)!::write(pipe_fds[1], why.data(), why.size());
    ::_exit(static_cast<int>(result));
  }
  ::close(pipe_fds[1]);
  std::string why;
  char buffer[512];
  for (ssize_t n; (n = ::read(pipe_fds[0], buffer, sizeof(buffer))) > 0;) why.append(buffer, static_cast<std::size_t>(n));
  ::close(pipe_fds[0]);
  int status = 0;
  EXPECT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_NE(WEXITSTATUS(status), 100) << "could not become user nobody";
  return {static_cast<ReadBeneath>(WEXITSTATUS(status)), why};
}

TEST(ReadBeneath, AModelBehindAFolderThatCannotBeSearchedIsRefusedNotGone) {
  testing::TempDir dir;
  const fs::path root = fs::canonical(dir.path());
  fs::permissions(root, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                            fs::perms::others_read | fs::perms::others_exec);
  fs::create_directories(root / "s1");
  testing::write_file(root / "s1" / "m.gltf", "{}");
  fs::permissions(root / "s1" / "m.gltf", fs::perms::all);

  // Readable, then missing: read, then gone.
  EXPECT_EQ(read_unprivileged(root, root / "s1" / "m.gltf").first, ReadBeneath::kRead);
  EXPECT_EQ(read_unprivileged(root, root / "s1" / "other.gltf").first, ReadBeneath::kGone);

  fs::permissions(root / "s1", fs::perms::none);
  const auto [result, why] = read_unprivileged(root, root / "s1" / "m.gltf");
  fs::permissions(root / "s1", fs::perms::owner_all);  // So that the folder can be removed.
  EXPECT_EQ(result, ReadBeneath::kRefused);
  EXPECT_EQ(why, "is in folder s1, which cannot be opened: Permission denied");
}

// Out of descriptors, a model that is there is neither gone (rdtfd published REMOVED for "the
// watched folder: Too many open files") nor refused for good (helper sweep s106fd D1: 51 models
// rejected until someone saved them again): it is unavailable, and rdtfd tries it again. Each open
// on the way fails in turn: the watched folder (0 free), the folder below it (1 free: the watched
// folder holds it), the file itself (1 free, a model in the watched folder). With 2 free the model
// below a folder is read: the watched folder's descriptor is closed once the next one is open.
TEST(ReadBeneath, OutOfDescriptorsAModelIsUnavailableNeitherGoneNorRefused) {
  testing::TempDir dir;
  const fs::path root = fs::canonical(dir.path());
  fs::create_directories(root / "s1");
  testing::write_file(root / "s1" / "m.gltf", "{}");
  testing::write_file(root / "top.gltf", "{}");
  const auto read_with = [&](int headroom, const fs::path& path) {
    std::vector<std::uint8_t> out;
    std::string why;
    const testing::DescriptorHeadroom limited(headroom);
    EXPECT_TRUE(limited.ok());
    const ReadBeneath result = read_beneath(root, path, 1 << 20, out, why);
    return std::pair{result, why};
  };
  const auto [root_result, root_why] = read_with(0, root / "s1" / "m.gltf");
  EXPECT_EQ(root_result, ReadBeneath::kUnavailable) << root_why;
  EXPECT_EQ(root_why, "the watched folder " + root.string() + ": Too many open files");
  const auto [folder_result, folder_why] = read_with(1, root / "s1" / "m.gltf");
  EXPECT_EQ(folder_result, ReadBeneath::kUnavailable) << folder_why;
  EXPECT_EQ(folder_why, "is in folder s1, which cannot be opened: Too many open files");
  const auto [file_result, file_why] = read_with(1, root / "top.gltf");
  EXPECT_EQ(file_result, ReadBeneath::kUnavailable) << file_why;
  EXPECT_EQ(file_why, "cannot be opened: Too many open files");
  EXPECT_EQ(read_with(2, root / "s1" / "m.gltf").first, ReadBeneath::kRead);
}

}  // namespace
}  // namespace rdtf::internal
