#include "rdtf/atomic_file.h"
#include "rdtf/shortage.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <mutex>
#include <random>
#include <regex>
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
                           std::string& why, Durability durability) {
  return write_file_atomically(path, std::span<const std::span<const std::uint8_t>>(&bytes, 1), why, durability);
}

bool write_file_atomically(const std::filesystem::path& path,
                           std::span<const std::span<const std::uint8_t>> pieces, std::string& why,
                           Durability durability) {
  const bool durable = durability == Durability::kDurable;
  const std::filesystem::path folder = path.has_parent_path() ? path.parent_path() : ".";
  std::random_device random;
  // A leading dot and a .tmp suffix: watchers (ours included) ignore such names.
  const std::filesystem::path temporary =
      folder / ("." + path.filename().string() + "." + std::to_string(::getpid()) + "-" +
                std::to_string(random()) + ".tmp");
  // 0666 less the umask, as cp and compilers create files: under umask 002 a group shares the
  // outputs as it shares their folders, under 077 they stay private (s103env D6).
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) {
    why = errno_text(("create " + temporary.string()).c_str());
    return false;
  }
  bool ok = true;
  for (const auto& piece : pieces) {
    ok = write_all(fd, piece.data(), piece.size(), why);
    if (!ok) break;
  }
  if (ok && durable && ::fsync(fd) != 0) {
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
  if (!durable) return true;
  const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    ::fsync(dir);  // Makes the rename durable; a failure here loses nothing already visible.
    ::close(dir);
  }
  return true;
}

bool write_staged_file(const std::filesystem::path& path, std::span<const std::span<const std::uint8_t>> pieces,
                       std::string& why) {
  // O_NOFOLLOW: the stage is ours, but a name made from the model must not lead out of it.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0666);  // as above
  if (fd < 0) {
    why = errno_text(("create " + path.string()).c_str());
    return false;
  }
  bool ok = true;
  for (const auto& piece : pieces) {
    ok = write_all(fd, piece.data(), piece.size(), why);
    if (!ok) break;
  }
  if (::close(fd) != 0 && ok) {
    why = errno_text("close");
    ok = false;
  }
  if (!ok) ::unlink(path.c_str());
  return ok;
}

bool write_staged_file(const std::filesystem::path& path, std::string_view text, std::string& why) {
  const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  return write_staged_file(path, std::span<const std::span<const std::uint8_t>>(&bytes, 1), why);
}

bool file_holds(const std::filesystem::path& path, std::span<const std::span<const std::uint8_t>> pieces) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return false;
  struct stat info {};
  std::uint64_t total = 0;
  for (const auto& piece : pieces) total += piece.size();
  bool same = ::fstat(fd, &info) == 0 && S_ISREG(info.st_mode) && static_cast<std::uint64_t>(info.st_size) == total;
  std::vector<std::uint8_t> buffer(same ? std::min<std::uint64_t>(total, 1 << 16) : 0);
  for (std::size_t i = 0; same && i < pieces.size(); ++i) {
    for (std::size_t at = 0; same && at < pieces[i].size();) {
      const std::size_t want = std::min(buffer.size(), pieces[i].size() - at);
      const ssize_t n = ::read(fd, buffer.data(), want);
      if (n < 0 && errno == EINTR) continue;
      same = n > 0 && std::equal(buffer.begin(), buffer.begin() + n, pieces[i].begin() + static_cast<std::ptrdiff_t>(at));
      at += n > 0 ? static_cast<std::size_t>(n) : 0;
    }
  }
  ::close(fd);
  return same;
}

bool write_file_atomically(const std::filesystem::path& path, std::string_view text,
                           std::string& why, Durability durability) {
  return write_file_atomically(
      path, std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()),
      why, durability);
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

std::optional<long> temporary_writer_pid(std::string_view file_name) {
  static const std::regex kTemporary(R"(\..+\.([0-9]{1,9})-[0-9]+\.tmp)");
  std::match_results<std::string_view::const_iterator> match;
  if (!std::regex_match(file_name.begin(), file_name.end(), match, kTemporary)) return std::nullopt;
  return std::stol(match[1].str());
}

std::optional<StagedOutput> StagedOutput::create(const std::filesystem::path& folder, std::string_view name,
                                                 std::string& why) {
  std::random_device random;
  const std::filesystem::path stage =
      folder / ("." + std::string(name) + "." + std::to_string(::getpid()) + "-" + std::to_string(random()) + ".tmp");
  if (::mkdir(stage.c_str(), 0755) != 0) {
    why = errno_text(("create " + stage.string()).c_str());
    return std::nullopt;
  }
  return StagedOutput(stage);
}

namespace {

std::mutex left_behind_mutex;
std::vector<std::filesystem::path> left_behind;  // Stages a destructor could not remove.

}  // namespace

StagedOutput::~StagedOutput() {
  if (folder_.empty()) return;
  std::error_code error;
  std::filesystem::remove_all(folder_, error);
  std::error_code exists_error;
  if (error && std::filesystem::exists(std::filesystem::symlink_status(folder_, exists_error))) {
    const std::lock_guard<std::mutex> lock(left_behind_mutex);
    left_behind.push_back(folder_);
  }
}

std::vector<std::filesystem::path> StagedOutput::remove_left_behind() {
  const std::lock_guard<std::mutex> lock(left_behind_mutex);
  std::erase_if(left_behind, [](const std::filesystem::path& folder) {
    std::error_code error;
    std::filesystem::remove_all(folder, error);
    std::error_code exists_error;
    return !std::filesystem::exists(std::filesystem::symlink_status(folder, exists_error));
  });
  return left_behind;
}

namespace {

bool same_bytes(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(std::filesystem::symlink_status(b, error)) ||
      std::filesystem::file_size(a, error) != std::filesystem::file_size(b, error) || error) {
    return false;
  }
  std::ifstream first(a, std::ios::binary);
  std::ifstream second(b, std::ios::binary);
  std::vector<char> x(1 << 16), y(1 << 16);
  while (first && second) {
    first.read(x.data(), static_cast<std::streamsize>(x.size()));
    second.read(y.data(), static_cast<std::streamsize>(y.size()));
    if (first.gcount() != second.gcount() ||
        !std::equal(x.begin(), x.begin() + first.gcount(), y.begin())) {
      return false;
    }
  }
  return first.eof() && second.eof();
}

// Every file's data on disk before any of them is renamed into place: a rename that survives a
// power loss then never names a file whose data did not. Writeback of a batch of them is started
// first, so that the fsyncs wait for one round of the disk a batch instead of one a file; batches,
// because a descriptor a file held 20,001 meshes open at once and failed with "Too many open files"
// under any usual open-file limit (s104rev N1). A batch also ends where the process's limit is
// reached, or memory is short (rdtf/shortage.h): a daemon already holding descriptors may have fewer
// than kBatch free, and a batch of one still makes progress. Only a file that cannot be opened
// with no other held is an error.
bool sync_files(const std::filesystem::path& folder, const std::vector<std::filesystem::path>& files,
                std::string& why) {
  constexpr std::size_t kBatch = 128;
  std::size_t next = 0;
  while (next < files.size()) {
    const std::size_t first = next;
    std::vector<int> fds;
    bool ok = true;
    while (next < files.size() && fds.size() < kBatch) {
      const int fd = ::open((folder / files[next]).c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
      if (fd < 0) {
        if (is_shortage(errno) && !fds.empty()) break;  // Sync what is held, go on.
        why = errno_text(("open " + (folder / files[next]).string()).c_str());
        ok = false;
        break;
      }
      ::sync_file_range(fd, 0, 0, SYNC_FILE_RANGE_WRITE);  // Only a hint: the fsync below decides.
      fds.push_back(fd);
      ++next;
    }
    for (std::size_t i = 0; i < fds.size(); ++i) {
      if (ok && ::fsync(fds[i]) != 0) {
        why = errno_text(("fsync " + (folder / files[first + i]).string()).c_str());
        ok = false;
      }
      ::close(fds[i]);
    }
    if (!ok) return false;
  }
  return true;
}

// Every regular file below `folder`, relative to it, those of `last` left out.
bool staged_files(const std::filesystem::path& folder, const std::vector<std::filesystem::path>& last,
                  std::vector<std::filesystem::path>& files, std::string& why) {
  std::error_code error;
  for (std::filesystem::recursive_directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    std::error_code type_error;
    if (!it->is_regular_file(type_error)) continue;
    const auto relative = it->path().lexically_relative(folder);
    if (std::find(last.begin(), last.end(), relative) == last.end()) files.push_back(relative);
  }
  if (error) {
    why = "cannot list " + folder.string() + ": " + error.message();
    return false;
  }
  return true;
}

}  // namespace

bool StagedOutput::sync(std::string& why) {
  std::vector<std::filesystem::path> files;
  if (!staged_files(folder_, {}, files, why) || !sync_files(folder_, files, why)) return false;
  synced_.insert(files.begin(), files.end());
  return true;
}

bool StagedOutput::commit(const std::filesystem::path& target, const std::vector<std::filesystem::path>& last,
                          std::string& why, bool keep_identical, Durability durability) {
  const bool durable = durability == Durability::kDurable;
  std::vector<std::filesystem::path> files;
  if (!staged_files(folder_, last, files, why)) return false;
  std::error_code error;
  for (const auto& file : last) {
    std::error_code exists_error;
    if (std::filesystem::exists(folder_ / file, exists_error)) files.push_back(file);
  }
  if (keep_identical) {
    std::erase_if(files, [&](const std::filesystem::path& file) { return same_bytes(folder_ / file, target / file); });
  }
  if (durable) {
    std::vector<std::filesystem::path> unsynced;
    for (const auto& file : files) {
      if (!synced_.contains(file)) unsynced.push_back(file);
    }
    if (!sync_files(folder_, unsynced, why)) return false;
  }
  std::set<std::filesystem::path> folders;
  for (const auto& file : files) {
    const auto destination = target / file;
    std::filesystem::create_directories(destination.parent_path(), error);
    if (error) {
      why = "cannot create " + destination.parent_path().string() + ": " + error.message();
      return false;
    }
    if (::rename((folder_ / file).c_str(), destination.c_str()) != 0) {
      why = errno_text(("rename to " + destination.string()).c_str());
      return false;
    }
    folders.insert(destination.parent_path());
  }
  if (!durable) return true;
  for (const auto& folder : folders) {
    const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir >= 0) {
      ::fsync(dir);  // Makes the renames durable; a failure here loses nothing already visible.
      ::close(dir);
    }
  }
  return true;
}

void remove_created(const std::vector<std::filesystem::path>& created) {
  for (const auto& path : created) {
    std::error_code error;
    std::filesystem::remove(path, error);
  }
}

}  // namespace rdtf
