#include "rdtf/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

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

constexpr std::size_t kNameDigits = 16;

bool is_name_digits(std::string_view text) {
  return text.size() == kNameDigits && std::all_of(text.begin(), text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

// "<at least one character>.<16 hex digits>"
bool ends_with_name_digits(std::string_view text) {
  return text.size() > kNameDigits + 1 && text[text.size() - kNameDigits - 1] == '.' &&
         is_name_digits(text.substr(text.size() - kNameDigits));
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

std::string content_addressed_name(std::string_view stem, std::string_view extension,
                                   std::span<const std::uint8_t> bytes, const ContentDigest& digest) {
  const std::string hex = digest(bytes);
  if (hex.size() < kNameDigits || !is_name_digits(std::string_view(hex).substr(0, kNameDigits))) {
    throw std::invalid_argument("content digest '" + hex + "' does not start with " +
                                std::to_string(kNameDigits) + " lowercase hex digits");
  }
  if (ends_with_name_digits(stem)) stem.remove_suffix(kNameDigits + 1);
  return std::string(stem) + "." + hex.substr(0, kNameDigits) + std::string(extension);
}

bool is_content_addressed_name(std::string_view file_name) {
  if (ends_with_name_digits(file_name)) return true;
  const auto dot = file_name.rfind('.');
  return dot != std::string_view::npos && dot + 1 < file_name.size() &&
         ends_with_name_digits(file_name.substr(0, dot));
}

int remove_unreferenced(const std::filesystem::path& folder, const std::set<std::string>& keep) {
  std::vector<std::filesystem::path> unreferenced;
  std::error_code error;
  for (std::filesystem::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    std::error_code type_error;
    const std::string name = it->path().filename().string();
    if (std::filesystem::is_regular_file(it->symlink_status(type_error)) && is_content_addressed_name(name) &&
        keep.count(name) == 0) {
      unreferenced.push_back(it->path());
    }
  }
  int removed = 0;
  for (const auto& path : unreferenced) {
    std::error_code remove_error;
    if (std::filesystem::remove(path, remove_error)) ++removed;
  }
  return removed;
}

void remove_created(const std::vector<std::filesystem::path>& created) {
  for (const auto& path : created) {
    std::error_code error;
    std::filesystem::remove(path, error);
  }
}

}  // namespace rdtf
