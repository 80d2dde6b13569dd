#include "rdtf/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <random>

namespace rdtf {
namespace {

std::string errno_text(const char* what) { return std::string(what) + ": " + std::strerror(errno); }

bool write_all(int fd, const std::uint8_t* data, std::size_t size, std::string& why) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      why = errno_text("write");
      return false;
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

bool write_file_atomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes,
                           std::string& why) {
  const std::filesystem::path folder = path.has_parent_path() ? path.parent_path() : ".";
  std::random_device random;
  // A leading dot and a .tmp suffix: watchers (ours included) ignore such names.
  const std::filesystem::path temporary =
      folder / ("." + path.filename().string() + "." + std::to_string(::getpid()) + "-" +
                std::to_string(random()) + ".tmp");
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    why = errno_text(("create " + temporary.string()).c_str());
    return false;
  }
  bool ok = write_all(fd, bytes.data(), bytes.size(), why);
  if (ok && ::fsync(fd) != 0) {
    why = errno_text("fsync");
    ok = false;
  }
  if (::close(fd) != 0 && ok) {
    why = errno_text("close");
    ok = false;
  }
  if (ok && ::rename(temporary.c_str(), path.c_str()) != 0) {
    why = errno_text(("rename to " + path.string()).c_str());
    ok = false;
  }
  if (!ok) {
    ::unlink(temporary.c_str());
    return false;
  }
  const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    ::fsync(dir);  // Makes the rename durable; a failure here loses nothing already visible.
    ::close(dir);
  }
  return true;
}

bool write_file_atomically(const std::filesystem::path& path, std::string_view text,
                           std::string& why) {
  return write_file_atomically(
      path, std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()),
      why);
}

}  // namespace rdtf
