#include "confined_files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <limits>
#include <memory>

#include "../geometry/big_arrays.h"
#include "rdtf/percent_decode.h"
#include "rdtf/shortage.h"

namespace rdtf::internal {
namespace {

std::string describe_file_type(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

bool is_inside(const std::filesystem::path& folder, const std::filesystem::path& real) {
  const std::string root = folder.string();
  const std::string candidate = real.string();
  if (root == "/") return true;
  return candidate.size() > root.size() && candidate.compare(0, root.size(), root) == 0 &&
         candidate[root.size()] == '/';
}

// A file descriptor that closes itself.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

// Opens `path` for reading and checks it is a regular file of at most max_bytes; when `folder`
// is given, also that its real location (resolved through /proc, so no symlink race) is inside.
std::optional<std::uint64_t> open_checked(const std::filesystem::path* folder,
                                          const std::filesystem::path& path,
                                          std::uint64_t max_bytes, int& fd_out,
                                          std::string& why, int* error = nullptr) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) {
    if (error != nullptr) *error = errno;
    why = std::string(std::strerror(errno));
    return std::nullopt;
  }
  fd_out = fd;
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    if (error != nullptr) *error = errno;
    why = std::string(std::strerror(errno));
    return std::nullopt;
  }
  if (!S_ISREG(info.st_mode)) {
    why = "is " + describe_file_type(info.st_mode) + ", not a regular file";
    return std::nullopt;
  }
  if (folder != nullptr) {
    std::error_code where_error;
    const auto real =
        std::filesystem::read_symlink("/proc/self/fd/" + std::to_string(fd), where_error);
    if (where_error) {
      if (error != nullptr) *error = where_error.value();
      why = "cannot tell where it really is: " + where_error.message();
      return std::nullopt;
    }
    // The target is not named: a message must not tell where a link points (it may be a probe).
    if (!is_inside(*folder, real)) {
      why = "leads outside the model's folder " + folder->string() + " through a symbolic link";
      return std::nullopt;
    }
    // Another name of the same file may lie anywhere on the file system: a hard link made in the
    // folder to a file outside it is indistinguishable from the file itself.
    if (info.st_nlink > 1) {
      why = "has " + std::to_string(info.st_nlink) +
            " hard links: a file with several names may be a file from outside the model's folder, "
            "so it is refused (copy it instead)";
      return std::nullopt;
    }
  }
  const auto size = static_cast<std::uint64_t>(info.st_size);
  if (size > max_bytes) {
    why = "is " + std::to_string(size) + " bytes, over the limit of " + std::to_string(max_bytes);
    return std::nullopt;
  }
  return size;
}

bool read_all(int fd, std::uint64_t size, std::vector<std::uint8_t>& out, std::string& why, int* error = nullptr) {
  out.resize(static_cast<std::size_t>(size));
  std::size_t done = 0;
  while (done < out.size()) {
    const ssize_t n = ::read(fd, out.data() + done, out.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (error != nullptr) *error = errno;
      why = std::string(std::strerror(errno));
      return false;
    }
    if (n == 0) {
      why = "file shrank while being read (" + std::to_string(done) + " of " +
            std::to_string(size) + " bytes)";
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

bool is_data_uri(std::string_view uri) { return uri.substr(0, 5) == "data:"; }

std::optional<std::filesystem::path> resolve_uri(const std::filesystem::path& folder,
                                                 std::string_view uri, std::string& why) {
  if (uri.empty()) {
    why = "the URI is empty";
    return std::nullopt;
  }
  // A scheme is letters, digits, '+', '-', '.' before the first ':' (RFC 3986 section 3.1).
  const auto colon = uri.find(':');
  const auto slash = uri.find('/');
  if (colon != std::string_view::npos && (slash == std::string_view::npos || colon < slash)) {
    why = "URIs with a scheme ('" + std::string(uri.substr(0, colon)) +
          ":') are refused: only paths relative to the model's folder are allowed";
    return std::nullopt;
  }
  if (uri.find_first_of("?#") != std::string_view::npos) {
    why = "URIs with a query or fragment are refused";
    return std::nullopt;
  }
  const auto decoded = rdtf::percent_decode(uri, &why);
  if (!decoded) return std::nullopt;
  if (decoded->find('\0') != std::string::npos) {
    why = "the decoded URI contains a NUL byte";
    return std::nullopt;
  }
  if (decoded->front() == '/' || decoded->find('\\') != std::string::npos) {
    why = "absolute paths and backslashes are refused: only paths relative to the model's "
          "folder are allowed";
    return std::nullopt;
  }
  // Walk the segments, refusing any ".." that would climb above the folder.
  std::filesystem::path relative;
  int depth = 0;
  std::size_t start = 0;
  while (start <= decoded->size()) {
    auto end = decoded->find('/', start);
    if (end == std::string::npos) end = decoded->size();
    const std::string segment = decoded->substr(start, end - start);
    if (segment == "..") {
      if (depth == 0) {
        why = "'../' leaves the model's folder";
        return std::nullopt;
      }
      relative = relative.parent_path();
      --depth;
    } else if (!segment.empty() && segment != ".") {
      relative /= segment;
      ++depth;
    }
    start = end + 1;
  }
  if (depth == 0) {
    why = "the URI names the model's folder itself, not a file";
    return std::nullopt;
  }
  return folder / relative;
}

bool read_confined_file(const std::filesystem::path& folder, const std::filesystem::path& path,
                        std::uint64_t max_bytes, std::vector<std::uint8_t>& out,
                        std::string& why) {
  int raw_fd = -1;
  const auto size = open_checked(&folder, path, max_bytes, raw_fd, why);
  Fd fd(raw_fd);
  if (!size) return false;
  return read_all(fd.get(), *size, out, why);
}

std::optional<std::uint64_t> read_confined_file_within(const std::filesystem::path& folder,
                                                       const std::filesystem::path& path,
                                                       std::uint64_t max_bytes,
                                                       std::vector<std::uint8_t>& out, std::string& why,
                                                       int* error) {
  if (error != nullptr) *error = 0;
  int raw_fd = -1;
  const auto size =
      open_checked(&folder, path, std::numeric_limits<std::uint64_t>::max(), raw_fd, why, error);
  Fd fd(raw_fd);
  if (!size || *size > max_bytes) return size;
  // A buffer is kept as it is read (the loader moves it into the asset): huge pages for a large one.
  reserve_huge(out, static_cast<std::size_t>(*size));
  if (!read_all(fd.get(), *size, out, why, error)) {
    out.clear();
    return std::nullopt;
  }
  return size;
}

std::optional<std::uint64_t> confined_file_size(const std::filesystem::path& folder,
                                                const std::filesystem::path& path,
                                                std::string& why) {
  int raw_fd = -1;
  const auto size =
      open_checked(&folder, path, std::numeric_limits<std::uint64_t>::max(), raw_fd, why);
  Fd fd(raw_fd);
  return size;
}

bool read_regular_file(const std::filesystem::path& path, std::uint64_t max_bytes,
                       std::vector<std::uint8_t>& out, std::string& why) {
  int raw_fd = -1;
  const auto size = open_checked(nullptr, path, max_bytes, raw_fd, why);
  Fd fd(raw_fd);
  if (!size) return false;
  return read_all(fd.get(), *size, out, why);
}


// An open that failed for want of the system's, not because of the file (is_shortage): the file may
// well be there, neither gone (rdtfd would publish REMOVED) nor refused for good.
ReadBeneath read_beneath(const std::filesystem::path& root, const std::filesystem::path& path,
                         std::uint64_t max_bytes, std::vector<std::uint8_t>& out, std::string& why) {
  const auto relative = path.lexically_normal().lexically_relative(root);
  if (relative.empty() || *relative.begin() == ".." || relative.is_absolute()) {
    why = "is not below the watched folder " + root.string();
    return ReadBeneath::kGone;
  }
  int raw_dir = ::open(root.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (raw_dir < 0) {
    const int error = errno;
    why = "the watched folder " + root.string() + ": " + std::strerror(error);
    return is_shortage(error) ? ReadBeneath::kUnavailable : ReadBeneath::kGone;
  }
  auto dir = std::make_unique<Fd>(raw_dir);
  std::vector<std::string> parts;
  for (const auto& part : relative) parts.push_back(part.string());
  // Every folder on the way is opened with O_NOFOLLOW: a folder swapped for a symlink (to a folder
  // outside) ends the walk instead of leading out.
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    const int next = ::openat(dir->get(), parts[i].c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (next < 0) {
      const int error = errno;
      why = "is in folder " + parts[i] + ", which " +
            (error == ELOOP || error == ENOTDIR ? std::string("is no longer a folder (a symbolic link or a file)")
                                                : "cannot be opened: " + std::string(std::strerror(error)));
      // A folder that cannot be searched (chmod 000) still holds the model: refused, not gone, so
      // that rdtfd keeps serving its last good revision until the folder is readable again.
      if (is_shortage(error)) return ReadBeneath::kUnavailable;
      return error == EACCES || error == EPERM ? ReadBeneath::kRefused : ReadBeneath::kGone;
    }
    dir = std::make_unique<Fd>(next);
  }
  const int raw_fd = ::openat(dir->get(), parts.back().c_str(),
                              O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (raw_fd < 0) {
    const int error = errno;
    if (error == ELOOP) {
      why = "is a symbolic link: rdtfd reads no model through a symbolic link, wherever it points";
      return ReadBeneath::kRefused;
    }
    why = std::string("cannot be opened: ") + std::strerror(error);
    if (is_shortage(error)) return ReadBeneath::kUnavailable;
    return error == ENOENT || error == ENOTDIR ? ReadBeneath::kGone : ReadBeneath::kRefused;
  }
  Fd fd(raw_fd);
  struct stat info {};
  if (::fstat(fd.get(), &info) != 0) {
    why = std::string("cannot be examined: ") + std::strerror(errno);
    return ReadBeneath::kRefused;
  }
  if (S_ISDIR(info.st_mode)) {
    why = "is a directory";
    return ReadBeneath::kGone;
  }
  if (!S_ISREG(info.st_mode)) {
    why = "is " + describe_file_type(info.st_mode) + ", not a regular file";
    return ReadBeneath::kRefused;
  }
  if (info.st_nlink > 1) {
    why = "has " + std::to_string(info.st_nlink) +
          " hard links: a file with several names may be a file from outside the watched folder, so it "
          "is refused (copy it instead)";
    return ReadBeneath::kRefused;
  }
  const auto size = static_cast<std::uint64_t>(info.st_size);
  if (size > max_bytes) {
    why = "is " + std::to_string(size) + " bytes, over the limit of " + std::to_string(max_bytes);
    return ReadBeneath::kRefused;
  }
  return read_all(fd.get(), size, out, why) ? ReadBeneath::kRead : ReadBeneath::kRefused;
}

}  // namespace rdtf::internal
