#include "blob_server.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openssl/evp.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>

#include <rdtf/blob_chunk_t.hpp>

#include "messages.h"
#include "safe_decode.h"

namespace rdtf::daemon {
namespace {

class UniqueFd {
 public:
  explicit UniqueFd(int fd = -1) : fd_(fd) {}
  ~UniqueFd() { reset(); }
  UniqueFd(UniqueFd&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  UniqueFd& operator=(UniqueFd&& other) noexcept {
    if (this != &other) {
      reset();
      fd_ = other.fd_;
      other.fd_ = -1;
    }
    return *this;
  }
  int get() const { return fd_; }
  void reset() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_;
};

// Opens <root>/<relative> for reading: the output folder as configured, then every folder below
// it and the file itself without following a symlink; the file must be a regular file with one
// link (an output of ours never has more; a hard link may be a file from elsewhere).
UniqueFd open_below(const std::filesystem::path& root, const std::filesystem::path& relative, struct stat& info,
                    std::string& why) {
  std::vector<std::string> parts;
  for (const auto& part : relative) {
    const std::string text = part.string();
    if (text.empty() || text == "." || text == ".." || text == "/") {
      why = "its path " + relative.string() + " leaves the output folder";
      return UniqueFd();
    }
    parts.push_back(text);
  }
  if (parts.empty()) {
    why = "empty path";
    return UniqueFd();
  }
  UniqueFd dir(::open(root.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (dir.get() < 0) {
    why = "cannot open the output folder " + root.string() + ": " + std::strerror(errno);
    return UniqueFd();
  }
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    UniqueFd next(::openat(dir.get(), parts[i].c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
    if (next.get() < 0) {
      why = "cannot open the folder " + parts[i] + " (a symbolic link is never followed): " + std::strerror(errno);
      return UniqueFd();
    }
    dir = std::move(next);
  }
  UniqueFd file(::openat(dir.get(), parts.back().c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY | O_CLOEXEC));
  if (file.get() < 0) {
    why = std::string("cannot open it (a symbolic link is never followed): ") + std::strerror(errno);
    return UniqueFd();
  }
  if (::fstat(file.get(), &info) != 0) {
    why = std::string("cannot stat it: ") + std::strerror(errno);
    return UniqueFd();
  }
  if (!S_ISREG(info.st_mode) || info.st_nlink != 1) {
    why = S_ISREG(info.st_mode) ? "it has " + std::to_string(info.st_nlink) + " hard links" : "it is not a regular file";
    return UniqueFd();
  }
  return file;
}

std::string cut(const std::string& text) { return lcm_safe::printable(text, 80); }

}  // namespace

bool is_sha256_hex(const std::string& text) {
  return text.size() == 64 && std::all_of(text.begin(), text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

// ---------------------------------------------------------------------------------------------
// BlobIndex

void BlobIndex::set_model(const std::string& model_id, const std::filesystem::path& folder,
                          const std::vector<OutputFile>& files) {
  remove_model(model_id);
  auto& hashes = hashes_of_model_[model_id];
  for (const OutputFile& file : files) {
    by_hash_[file.sha256].push_back({model_id, folder.native(), file.path, file.size});
    hashes.push_back(file.sha256);
  }
}

void BlobIndex::remove_model(const std::string& model_id) {
  auto it = hashes_of_model_.find(model_id);
  if (it == hashes_of_model_.end()) return;
  for (const std::string& hash : it->second) {
    auto sources = by_hash_.find(hash);
    if (sources == by_hash_.end()) continue;
    std::erase_if(sources->second, [&](const BlobSource& s) { return s.model_id == model_id; });
    if (sources->second.empty()) by_hash_.erase(sources);
  }
  hashes_of_model_.erase(it);
}

const BlobSource* BlobIndex::find(const std::string& sha256) const {
  auto it = by_hash_.find(sha256);
  return it == by_hash_.end() || it->second.empty() ? nullptr : &it->second.front();
}

// ---------------------------------------------------------------------------------------------
// BlobServer

// What identifies a file's bytes without reading them: the same inode, size and times as when it
// was last hashed and found to match (any write in place changes mtime and ctime).
struct BlobServer::FileStamp {
  dev_t device;
  ino_t inode;
  off_t size;
  timespec modified;
  timespec changed;
  bool operator==(const FileStamp& o) const {
    return device == o.device && inode == o.inode && size == o.size && modified.tv_sec == o.modified.tv_sec &&
           modified.tv_nsec == o.modified.tv_nsec && changed.tv_sec == o.changed.tv_sec &&
           changed.tv_nsec == o.changed.tv_nsec;
  }
};

struct BlobServer::Job {
  std::string sha256;
  BlobSource source;
  std::string requester;      // The first to ask (in BLOB_UNAVAILABLE when it fails).
  std::int32_t chunk_size = 0;
  std::int64_t count = 0;     // Chunks of the blob.
  std::vector<bool> wanted;   // Chunks still to send.
  std::int64_t wanted_count = 0;
  std::int64_t cursor = 0;    // The next chunk to look at (in index order, wrapping).
  // Chunks queued in the Publisher and perhaps not sent yet: index -> the Publisher's enqueued()
  // count for it, and the same in queue order (oldest first) to forget them as they leave.
  std::map<std::int64_t, std::uint64_t> in_queue;
  std::deque<std::pair<std::uint64_t, std::int64_t>> in_queue_order;
  UniqueFd fd;
  bool opened = false;
  bool verified = false;
  FileStamp stamp{};
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> hash{nullptr, EVP_MD_CTX_free};
  std::int64_t hashed = 0;
};

BlobServer::BlobServer(Log log) : log_(std::move(log)) { set_max_message_bytes(max_message_bytes_); }

BlobServer::~BlobServer() = default;

void BlobServer::set_max_message_bytes(std::size_t max_message_bytes) {
  max_message_bytes_ = max_message_bytes;
  rdtf::blob_chunk_t empty;
  empty.utime = 0;
  empty.sha256 = std::string(64, '0');
  empty.blob_size = 0;
  empty.chunk_size = 0;
  empty.index = 0;
  empty.count = 0;
  empty.size = 0;
  const auto overhead = static_cast<std::size_t>(empty.getEncodedSize());
  // max_chunk_bytes is at least 1024 (config ranges): far above the chunk's 109 bytes of fields.
  chunk_size_ = static_cast<std::int32_t>(max_message_bytes > overhead + 256 ? max_message_bytes - overhead : 256);
}

void BlobServer::forget_verified() {
  std::erase_if(verified_, [&](const auto& entry) { return index_.find(entry.first) == nullptr; });
}

void BlobServer::set_model(const std::string& model_id, const std::filesystem::path& folder,
                           const std::vector<OutputFile>& files) {
  index_.set_model(model_id, folder, files);
  forget_verified();
}

void BlobServer::remove_model(const std::string& model_id) {
  index_.remove_model(model_id);
  forget_verified();
}

void BlobServer::note(const std::string& line) {
  const auto now = Clock::now();
  if (now < next_note_) {
    ++notes_unlogged_;
    return;
  }
  next_note_ = now + std::chrono::seconds(1);
  log_(line + (notes_unlogged_ > 0 ? " (and " + std::to_string(notes_unlogged_) + " blob events not logged in the last second)" : ""));
  notes_unlogged_ = 0;
}

namespace {

// A token bucket: true (and one token less) when a token is there.
template <typename Bucket, typename TimePoint>
bool take(Bucket& bucket, TimePoint now, double rate, double burst) {
  if (bucket.last == TimePoint{}) {
    bucket.tokens = burst;
  } else {
    bucket.tokens = std::min(burst, bucket.tokens + rate * std::chrono::duration<double>(now - bucket.last).count());
  }
  bucket.last = now;
  if (bucket.tokens < 1) return false;
  bucket.tokens -= 1;
  return true;
}

}  // namespace

bool BlobServer::admit(const std::string& requester, Clock::time_point now) {
  // Made-up names cost a map entry each: past 1024 everyone starts afresh (the global bucket holds).
  if (buckets_.size() >= 1024 && buckets_.count(requester) == 0) buckets_.clear();
  return take(all_, now, kAllRequestsPerSecond, kAllRequestBurst) &&
         take(buckets_[requester], now, kRequestsPerSecond, kRequestBurst);
}

std::string BlobServer::request(const rdtf::blob_request_t& request, Clock::time_point now, Publisher& out,
                                const std::string& prefix) {
  auto drop = [&](const std::string& why) {
    ++counters_.dropped;
    return "blob request from '" + cut(request.requester) + "': " + why;
  };
  if (request.num_ranges <= 0) return drop("no blobs asked for");
  const auto ranges = static_cast<std::size_t>(request.num_ranges);
  if (request.sha256.size() != ranges || request.first_chunk.size() != ranges || request.num_chunks.size() != ranges) {
    return drop("num_ranges does not match its arrays");  // Only a message not from the decoder.
  }
  if (request.num_ranges > kMaxRanges) {
    return drop(std::to_string(request.num_ranges) + " ranges, over the limit of " + std::to_string(kMaxRanges) +
                " per request");
  }
  for (std::int32_t i = 0; i < request.num_ranges; ++i) {
    const std::string where = "range " + std::to_string(i) + ": ";
    if (!is_sha256_hex(request.sha256[static_cast<std::size_t>(i)])) {
      return drop(where + "sha256 '" + cut(request.sha256[static_cast<std::size_t>(i)]) +
                  "' is not 64 lowercase hex digits");
    }
    const std::int32_t first = request.first_chunk[static_cast<std::size_t>(i)];
    const std::int32_t count = request.num_chunks[static_cast<std::size_t>(i)];
    if (first < 0) return drop(where + "first_chunk " + std::to_string(first) + " is negative");
    if (count == 0 || count < -1) {
      return drop(where + "num_chunks " + std::to_string(count) + " is neither -1 (to the end) nor positive");
    }
  }
  if (!admit(request.requester, now)) {
    return drop("over the limit of " + std::to_string(static_cast<int>(kRequestsPerSecond)) +
                " requests/s per requester and " + std::to_string(static_cast<int>(kAllRequestsPerSecond)) +
                " in all");
  }
  ++counters_.requests;
  const std::string requester = request.requester.substr(0, 80);
  std::vector<std::pair<std::string, std::string>> refused;
  std::size_t unanswered = 0;
  for (std::size_t i = 0; i < ranges; ++i) {
    const std::int32_t count = request.num_chunks[i];
    const std::string why = add(request.sha256[i], request.first_chunk[i],
                                count < 0 ? std::numeric_limits<std::int64_t>::max() : count, requester, out.departed());
    if (why.empty()) continue;
    if (take(answers_, now, kUnavailablePerSecond, kUnavailableBurst)) {
      refused.emplace_back(request.sha256[i], why);
    } else {
      ++unanswered;
    }
  }
  if (unanswered > 0) {
    ++counters_.dropped;
    note("blob request from '" + cut(requester) + "': " + std::to_string(unanswered) +
         " blobs it asked for are not served and go unanswered: over " +
         std::to_string(static_cast<int>(kUnavailablePerSecond)) + " BLOB_UNAVAILABLE answers a second");
  }
  if (!refused.empty()) {
    unavailable(requester, refused, out, prefix);
    note("blob request from '" + cut(requester) + "': " + std::to_string(refused.size()) + " of " +
         std::to_string(request.num_ranges) + " unavailable, the first " + refused.front().first.substr(0, 16) +
         ": " + refused.front().second);
  }
  return {};
}

std::string BlobServer::add(const std::string& sha256, std::int64_t first, std::int64_t count,
                            const std::string& requester, std::uint64_t departed) {
  auto it = jobs_.find(sha256);
  if (it == jobs_.end()) {
    const BlobSource* source = index_.find(sha256);
    if (source == nullptr) return "not a file of any live revision";
    const std::int64_t chunks = std::max<std::int64_t>(1, (source->size + chunk_size_ - 1) / chunk_size_);
    if (chunks > std::numeric_limits<std::int32_t>::max()) return "too large for chunk indices";
    if (first >= chunks) {
      return "chunk " + std::to_string(first) + " asked for, but the blob has " + std::to_string(chunks) +
             " chunks of " + std::to_string(chunk_size_) + " bytes";
    }
    if (jobs_.size() >= kMaxJobs) {
      return "the daemon is sending " + std::to_string(kMaxJobs) + " blobs already: ask again later";
    }
    auto job = std::make_unique<Job>();
    job->sha256 = sha256;
    job->source = *source;
    job->requester = requester;
    job->chunk_size = chunk_size_;
    job->count = chunks;
    job->wanted.assign(static_cast<std::size_t>(chunks), false);
    it = jobs_.emplace(sha256, std::move(job)).first;
  }
  Job& job = *it->second;
  // A job being sent keeps the chunk size it started with: its indices mean the same to everyone.
  if (first >= job.count) {
    return "chunk " + std::to_string(first) + " asked for, but the blob has " + std::to_string(job.count) +
           " chunks of " + std::to_string(job.chunk_size) + " bytes";
  }
  const std::int64_t end = count >= job.count - first ? job.count : first + count;
  const bool was_idle = job.wanted_count == 0;
  for (std::int64_t i = first; i < end; ++i) {
    if (job.wanted[static_cast<std::size_t>(i)]) continue;
    // Still waiting in the send queue: it goes to every subscriber anyway (multicast).
    const auto queued = job.in_queue.find(i);
    if (queued != job.in_queue.end() && queued->second > departed) continue;
    job.wanted[static_cast<std::size_t>(i)] = true;
    ++job.wanted_count;
  }
  if (was_idle && job.wanted_count > 0) order_.push_back(sha256);
  return {};
}

bool BlobServer::open(Job& job, std::string& why) {
  struct stat info {};
  job.fd = open_below(job.source.folder, job.source.path, info, why);
  if (job.fd.get() < 0) return false;
  if (info.st_size != job.source.size) {
    why = "it changed on disk: " + std::to_string(info.st_size) + " bytes, the manifest says " +
          std::to_string(job.source.size);
    return false;
  }
  job.opened = true;
  job.stamp = FileStamp{info.st_dev, info.st_ino, info.st_size, info.st_mtim, info.st_ctim};
  auto known = verified_.find(job.sha256);
  job.verified = known != verified_.end() && *known->second == job.stamp;
  if (!job.verified) {
    job.hash.reset(EVP_MD_CTX_new());
    EVP_DigestInit_ex(job.hash.get(), EVP_sha256(), nullptr);
  }
  return true;
}

bool BlobServer::verify(Job& job, std::size_t& budget, std::string& why) {
  std::vector<std::uint8_t> buffer(1 << 20);
  while (job.hashed < job.source.size && budget > 0) {
    const std::size_t want = static_cast<std::size_t>(
        std::min<std::int64_t>(static_cast<std::int64_t>(std::min(buffer.size(), budget)), job.source.size - job.hashed));
    const ssize_t n = ::pread(job.fd.get(), buffer.data(), want, job.hashed);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      why = n == 0 ? "it changed on disk (shorter than the manifest says)" : std::string("read failed: ") + std::strerror(errno);
      return false;
    }
    EVP_DigestUpdate(job.hash.get(), buffer.data(), static_cast<std::size_t>(n));
    job.hashed += n;
    budget -= std::min(budget, static_cast<std::size_t>(n));
  }
  if (job.hashed < job.source.size) return false;  // Not done: the next turn goes on.
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(job.hash.get(), digest, &length);
  job.hash.reset();
  if (to_hex({digest, length}) != job.sha256) {
    why = "it changed on disk: its bytes no longer have the manifest's SHA-256";
    return false;
  }
  job.verified = true;
  verified_[job.sha256] = std::make_unique<FileStamp>(job.stamp);
  return true;
}

void BlobServer::send_next(Job& job, Publisher& out, const std::string& prefix) {
  std::int64_t index = job.cursor;
  while (!job.wanted[static_cast<std::size_t>(index)]) index = (index + 1) % job.count;
  rdtf::blob_chunk_t chunk;
  chunk.utime = now_utime();
  chunk.sha256 = job.sha256;
  chunk.blob_size = job.source.size;
  chunk.chunk_size = job.chunk_size;
  chunk.index = static_cast<std::int32_t>(index);
  chunk.count = static_cast<std::int32_t>(job.count);
  const std::int64_t offset = index * job.chunk_size;
  const auto size = static_cast<std::size_t>(std::min<std::int64_t>(job.chunk_size, job.source.size - offset));
  chunk.data.resize(size);
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pread(job.fd.get(), chunk.data.data() + done, size - done, offset + static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += static_cast<std::size_t>(n);
  }
  if (done < size) {
    // Truncated after it was checked: stop; the subscriber's hash check catches what it has.
    fail(job.sha256, "it changed on disk while being sent (shorter than the manifest says)", out, prefix);
    return;
  }
  chunk.size = static_cast<std::int32_t>(size);
  out.publish(prefix + "/BLOB", chunk);
  job.in_queue[index] = out.enqueued();
  job.in_queue_order.emplace_back(out.enqueued(), index);
  ++counters_.chunks_sent;
  counters_.bytes_sent += static_cast<std::int64_t>(size);
  job.wanted[static_cast<std::size_t>(index)] = false;
  --job.wanted_count;
  job.cursor = (index + 1) % job.count;
  // Done with this pass: out of the round robin; the job stays while its chunks wait in the queue.
  if (job.wanted_count == 0) std::erase(order_, job.sha256);
}

void BlobServer::fail(const std::string& sha256, const std::string& why, Publisher& out, const std::string& prefix) {
  auto it = jobs_.find(sha256);
  if (it == jobs_.end()) return;
  const Job& job = *it->second;
  note("blob " + sha256.substr(0, 16) + " (" + job.source.model_id + "/" + job.source.path + ") not served: " + why);
  unavailable(job.requester, {{sha256, why}}, out, prefix);
  verified_.erase(sha256);
  std::erase(order_, sha256);
  jobs_.erase(it);
}

void BlobServer::unavailable(const std::string& requester, const std::vector<std::pair<std::string, std::string>>& blobs,
                             Publisher& out, const std::string& prefix) {
  counters_.unavailable += static_cast<std::int64_t>(blobs.size());
  rdtf::blob_unavailable_t message;
  message.utime = now_utime();
  message.requester = requester;
  message.num_blobs = 0;
  const std::size_t fields = static_cast<std::size_t>(message.getEncodedSize());
  std::size_t size = fields;
  auto flush = [&] {
    message.num_blobs = static_cast<std::int32_t>(message.sha256.size());
    out.publish(prefix + "/BLOB_UNAVAILABLE", message);
    message.sha256.clear();
    message.reason.clear();
    size = fields;
  };
  for (const auto& [sha, why] : blobs) {
    const std::size_t row = 4 + sha.size() + 1 + 4 + why.size() + 1;
    if (!message.sha256.empty() && size + row > max_message_bytes_) flush();
    message.sha256.push_back(sha);
    message.reason.push_back(why);
    size += row;
  }
  flush();
}

void BlobServer::forget_departed(std::uint64_t departed) {
  for (auto it = jobs_.begin(); it != jobs_.end();) {
    Job& job = *it->second;
    while (!job.in_queue_order.empty() && job.in_queue_order.front().first <= departed) {
      const auto [seq, index] = job.in_queue_order.front();
      if (auto mark = job.in_queue.find(index); mark != job.in_queue.end() && mark->second == seq) job.in_queue.erase(mark);
      job.in_queue_order.pop_front();
    }
    if (job.wanted_count == 0 && job.in_queue_order.empty()) {
      it = jobs_.erase(it);
    } else {
      ++it;
    }
  }
}

void BlobServer::publisher_replaced() {
  for (auto& [sha, job] : jobs_) {
    job->in_queue.clear();
    job->in_queue_order.clear();
  }
  forget_departed(0);
}

bool BlobServer::ready(const Publisher& out) const {
  const std::size_t open = std::min(order_.size(), kOpenJobs);
  for (std::size_t i = 0; i < open; ++i) {
    const Job& job = *jobs_.at(order_[i]);
    if (!job.opened || !job.verified) return true;  // Checking the file needs no send queue room.
  }
  return open > 0 && out.queued_bytes() < kQueueBytes;
}

void BlobServer::pump(Publisher& out, const std::string& prefix) {
  forget_departed(out.departed());
  std::size_t budget = kVerifyBytesPerPump;
  // Open and check the jobs to be sent next (a bounded share of hashing per turn).
  for (std::size_t i = 0; i < std::min(order_.size(), kOpenJobs);) {
    Job& job = *jobs_.at(order_[i]);
    std::string why;
    const bool ok = (job.opened || open(job, why)) && (job.verified || verify(job, budget, why));
    if (!ok && !why.empty()) {
      fail(job.sha256, why, out, prefix);  // Removed from order_: the same i is the next job.
      continue;
    }
    ++i;
  }
  while (out.queued_bytes() < kQueueBytes && !order_.empty()) {
    const std::size_t open = std::min(order_.size(), kOpenJobs);
    Job* next = nullptr;
    for (std::size_t tried = 0; tried < open && next == nullptr; ++tried) {
      Job& job = *jobs_.at(order_[turn_++ % open]);
      if (job.verified) next = &job;
    }
    if (next == nullptr) return;  // Every open job is still being checked.
    send_next(*next, out, prefix);
  }
}

}  // namespace rdtf::daemon
