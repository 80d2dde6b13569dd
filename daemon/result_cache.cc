#include "result_cache.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <random>

#include <nlohmann/json.hpp>

#include "../core/gltf/confined_files.h"
#include "rdtf/atomic_file.h"
#include "rdtf/version.h"
#include "revision_store.h"

namespace rdtf::daemon {
namespace {

// Raised whenever what an entry holds, or how the key is made, changes meaning.
constexpr const char* kCacheFormat = "rdtfd-results 4";  // 2: joint limits say whether a range was given; 3: node extras ignored; 4: the verdict's live stepper
// An entry is a few KiB for a small robot; one of a robot with thousands of links is far below this.
constexpr std::uint64_t kMaxEntryBytes = std::uint64_t{64} << 20;

bool is_entry_name(const std::string& name) {
  return name.size() == 2 + 32 + 5 && name.rfind("r-", 0) == 0 && name.compare(name.size() - 5, 5, ".json") == 0;
}

std::int64_t modified_ns(const struct stat& info) {
  return static_cast<std::int64_t>(info.st_mtim.tv_sec) * 1'000'000'000 + info.st_mtim.tv_nsec;
}

// Writes under a temporary name in the same folder (the form remove_stale_temporaries knows) and
// renames: a reader sees the old entry or the new one, never a mix. No fsync: an entry the crash
// tore is caught by its checksum and recomputed, so the cache never waits for the disk.
bool write_entry(const std::filesystem::path& path, const std::string& text, std::string& why) {
  static thread_local std::mt19937_64 random(std::random_device{}());
  const auto temporary = path.parent_path() / ("." + path.filename().string() + "." + std::to_string(::getpid()) +
                                               "-" + std::to_string(random() % 1000000000) + ".tmp");
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd < 0) {
    why = temporary.string() + ": " + std::strerror(errno);
    return false;
  }
  std::size_t done = 0;
  while (done < text.size()) {
    const auto n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += static_cast<std::size_t>(n);
  }
  const int write_errno = errno;
  const bool closed = ::close(fd) == 0;
  if (done != text.size() || !closed) {
    why = temporary.string() + ": " + std::strerror(done != text.size() ? write_errno : errno);
    ::unlink(temporary.c_str());
    return false;
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    why = path.string() + ": " + std::strerror(errno);
    ::unlink(temporary.c_str());
    return false;
  }
  return true;
}

// What stands for the code of a build whose commit does not name it.
std::string executable_identity() {
  struct stat info {};
  if (::stat("/proc/self/exe", &info) != 0) return "unknown";
  return std::to_string(info.st_size) + "@" + std::to_string(modified_ns(info));
}

}  // namespace

std::string settings_key(const DaemonConfig& config) {
  nlohmann::json settings = nlohmann::json::object();
  for (const ConfigKey& key : config_registry()) {
    if ((key.reload & kReconvert) != 0) settings[key.name] = key.get(config);
  }
  const std::string commit = git_commit();
  nlohmann::json all = {{"format", kCacheFormat}, {"version", version()}, {"commit", commit}, {"settings", settings}};
  if (commit == "unknown" || commit.find("-dirty") != std::string::npos) all["executable"] = executable_identity();
  return sha256_hex(all.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

ResultCache::ResultCache(std::filesystem::path folder, std::size_t max_entries)
    : folder_(std::move(folder)), max_entries_(std::max<std::size_t>(max_entries, 1)) {}

std::filesystem::path ResultCache::folder_for(const std::filesystem::path& output_root) {
  return RevisionStore::folder_for(output_root) / "results";
}

std::filesystem::path ResultCache::file_for(const std::string& source) const {
  // A slot per model file: a new result for the same model replaces the old one, so edits do not
  // grow the cache; only models that went away leave entries for eviction to remove.
  return folder_ / ("r-" + sha256_hex(source).substr(0, 32) + ".json");
}

std::size_t ResultCache::open() {
  std::lock_guard lock(eviction_);
  return evict_locked();
}

std::size_t ResultCache::evict_locked() {
  std::vector<std::pair<std::int64_t, std::filesystem::path>> by_age;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(folder_, ec), end; !ec && it != end; it.increment(ec)) {
    struct stat info {};
    if (!is_entry_name(it->path().filename().string()) || ::lstat(it->path().c_str(), &info) != 0 ||
        !S_ISREG(info.st_mode)) {
      continue;
    }
    by_age.emplace_back(modified_ns(info), it->path());
  }
  std::size_t removed = 0;
  if (by_age.size() > max_entries_) {
    // Down to 90% of the bound, so that a cache at its bound does not list its folder per entry.
    const std::size_t keep = max_entries_ - max_entries_ / 10;
    std::sort(by_age.begin(), by_age.end());
    for (std::size_t i = 0; i + keep < by_age.size(); ++i) {
      if (::unlink(by_age[i].second.c_str()) == 0) ++removed;
    }
  }
  entries_ = by_age.size() - removed;
  evicted_ += removed;
  return removed;
}

ResultCache::Lookup ResultCache::find(const std::string& source, const std::string& key,
                                      const std::string& content_hash, CachedResult& out, std::string& why) {
  const auto path = file_for(source);
  std::vector<std::uint8_t> bytes;
  std::string read_why;
  struct stat info {};
  if (::lstat(path.c_str(), &info) != 0) return Lookup::kMiss;
  if (!internal::read_regular_file(path, kMaxEntryBytes, bytes, read_why)) {
    why = path.string() + ": " + read_why;
    return Lookup::kRefused;
  }
  std::string entry_why;
  auto entry = cache_entry_from_text(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
                                     entry_why);
  if (!entry) {
    why = path.string() + ": " + entry_why;
    return Lookup::kRefused;
  }
  if (entry->source != source || entry->key != key || entry->content_hash != content_hash) return Lookup::kMiss;
  ::utimensat(AT_FDCWD, path.c_str(), nullptr, AT_SYMLINK_NOFOLLOW);  // Used now (least recently used goes first).
  out = std::move(*entry);
  return Lookup::kHit;
}

bool ResultCache::store(const CachedResult& result, std::string& why) {
  std::error_code ec;
  std::filesystem::create_directories(folder_, ec);
  if (ec) {
    why = "cannot make " + folder_.string() + ": " + ec.message();
    return false;
  }
  const auto path = file_for(result.source);
  struct stat info {};
  const bool replaces = ::lstat(path.c_str(), &info) == 0;
  if (!write_entry(path, cache_entry_text(result), why)) return false;
  if (!replaces && ++entries_ > max_entries_) {
    std::lock_guard lock(eviction_);
    if (entries_ > max_entries_) evict_locked();
  }
  return true;
}

}  // namespace rdtf::daemon
