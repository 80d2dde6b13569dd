#include "blob_fetch.h"

#include <algorithm>
#include <chrono>

#include "assembly.h"

namespace rdtf::client::detail {
namespace {

// A blob_request_t fits one Ethernet frame: with LCM's header, the channel's name and the IP and
// UDP headers, 1,200 encoded bytes stay below 1,500. A request the IP layer splits into fragments
// is lost when any fragment is (16 fragments, 256 ranges, arrived 3% of the time at 20% loss):
// and the request is what recovers lost chunks. 77 bytes a range (hash, first, count).
constexpr std::size_t kMaxRequestBytes = 1200;
constexpr std::size_t kRangeBytes = 4 + 64 + 1 + 4 + 4;
// Requests are paced below rdtfd's limit of 50 a second per requester (daemon/blob_server.h),
// beyond which it drops them: a client that lost much asks for it over several ticks (560 ranges
// a second).
constexpr double kRequestsPerSecond = 40;
constexpr double kRequestBurst = 40;
// A chunk fits one datagram; anything claiming more is not rdtfd's.
constexpr std::int64_t kMaxChunkBytes = 4 << 20;
constexpr int kMaxHashFailures = 3;

std::string str(std::int64_t value) { return std::to_string(value); }

}  // namespace

std::shared_ptr<const std::string> BlobStore::find(const std::string& sha256) {
  const auto it = blobs_.find(sha256);
  if (it == blobs_.end()) return nullptr;
  it->second.used = ++clock_;
  return it->second.bytes;
}

void BlobStore::insert(const std::string& sha256, std::shared_ptr<const std::string> bytes) {
  if (blobs_.count(sha256)) return;
  bytes_ += static_cast<std::int64_t>(bytes->size());
  blobs_[sha256] = Held{std::move(bytes), ++clock_};
  trim();
}

void BlobStore::trim() {
  // Evict what only the store holds (no snapshot refers to it), least recently used first.
  while (bytes_ > capacity_) {
    auto victim = blobs_.end();
    for (auto it = blobs_.begin(); it != blobs_.end(); ++it) {
      if (it->second.bytes.use_count() == 1 && (victim == blobs_.end() || it->second.used < victim->second.used)) {
        victim = it;
      }
    }
    if (victim == blobs_.end()) break;
    bytes_ -= static_cast<std::int64_t>(victim->second.bytes->size());
    blobs_.erase(victim);
  }
}

void BlobFetcher::want(const std::string& sha256, std::int64_t size, const std::string& waiter, Clock::time_point now) {
  auto [it, added] = fetches_.try_emplace(sha256);
  it->second.waiters.insert(waiter);
  if (!added) return;
  it->second.size = size;
  it->second.due = now;
  it->second.backoff = options_.retry_initial;
}

void BlobFetcher::release(const std::string& waiter) {
  for (auto it = fetches_.begin(); it != fetches_.end();) {
    it->second.waiters.erase(waiter);
    if (it->second.waiters.empty()) {
      if (it->second.active) active_bytes_ -= it->second.size;
      it = fetches_.erase(it);
    } else {
      ++it;
    }
  }
}

std::string BlobFetcher::progress(const std::string& sha256) const {
  const auto it = fetches_.find(sha256);
  if (it == fetches_.end()) return "not fetched";
  const Fetch& f = it->second;
  if (!f.active) return "waiting for room (max_fetch_bytes)";
  if (f.count < 0) return "no chunk received";
  return str(f.received) + " of " + str(f.count) + " chunks";
}

void BlobFetcher::reset(Fetch& fetch) {
  fetch.chunk_size = -1;
  fetch.count = -1;
  fetch.data.clear();
  fetch.data.shrink_to_fit();
  fetch.have.clear();
  fetch.received = 0;
  fetch.resume = 0;
}

std::string BlobFetcher::on_chunk(const rdtf::blob_chunk_t& c, Clock::time_point now) {
  if (!is_sha256_hex(c.sha256)) return "sha256 is not 64 lower-case hex digits";
  const auto it = fetches_.find(c.sha256);
  if (it == fetches_.end()) {
    ++stats_.blob_chunks_ignored;  // Another client's blob, or one held already.
    return "";
  }
  Fetch& f = it->second;
  if (!f.active) {
    ++stats_.blob_chunks_ignored;  // Not asked for yet (another client's request): no memory for it.
    return "";
  }
  if (c.blob_size != f.size) {
    return "blob " + c.sha256.substr(0, 12) + ": blob_size " + str(c.blob_size) + " but the manifest says " + str(f.size);
  }
  std::int64_t count = 1;
  if (f.size > 0) {
    if (c.chunk_size <= 0 || c.chunk_size > kMaxChunkBytes) return "chunk_size " + str(c.chunk_size) + " out of range";
    count = (f.size + c.chunk_size - 1) / c.chunk_size;
  } else if (c.chunk_size < 0) {
    return "chunk_size " + str(c.chunk_size) + " is negative";
  }
  if (c.count != count) return "count " + str(c.count) + " but a blob of this size has " + str(count) + " chunks";
  if (c.index < 0 || c.index >= c.count) return "index " + str(c.index) + " outside 0.." + str(c.count - 1);
  const std::int64_t offset = static_cast<std::int64_t>(c.index) * c.chunk_size;
  const std::int64_t expected = f.size == 0 ? 0 : std::min<std::int64_t>(c.chunk_size, f.size - offset);
  if (c.size != expected) return "chunk " + str(c.index) + " of " + str(c.size) + " bytes, expected " + str(expected);
  if (f.chunk_size >= 0 && f.chunk_size != c.chunk_size) reset(f);  // rdtfd restarted with another chunk size.
  if (f.chunk_size < 0) {
    f.chunk_size = c.chunk_size;
    f.count = c.count;
    f.data.assign(static_cast<std::size_t>(f.size), '\0');
    f.have.assign(static_cast<std::size_t>(f.count), false);
  }
  if (f.have[static_cast<std::size_t>(c.index)]) {
    ++stats_.blob_chunks_ignored;
    return "";
  }
  std::copy(c.data.begin(), c.data.end(), f.data.begin() + offset);
  f.have[static_cast<std::size_t>(c.index)] = true;
  ++f.received;
  ++stats_.blob_chunks;
  stats_.blob_bytes += static_cast<std::uint64_t>(c.size);
  stats_.blob_chunk_size = std::max<std::int64_t>(stats_.blob_chunk_size, c.chunk_size);
  last_chunk_ = now;
  f.due = now + options_.chunk_gap;
  f.backoff = options_.retry_initial;
  if (f.received == f.count) complete(c.sha256, f);
  return "";
}

void BlobFetcher::complete(const std::string& sha256, Fetch& f) {
  if (sha256_hex(f.data.data(), f.data.size()) != sha256) {
    reset(f);
    if (++f.hash_failures < kMaxHashFailures) {
      f.due = Clock::time_point{};  // Ask again at the next tick.
      return;
    }
    if (f.active) active_bytes_ -= f.size;
    fetches_.erase(sha256);
    done_(sha256, "blob " + sha256 + ": its chunks joined to other bytes " + str(kMaxHashFailures) + " times");
    return;
  }
  auto bytes = std::make_shared<const std::string>(std::move(f.data));
  if (f.active) active_bytes_ -= f.size;
  fetches_.erase(sha256);
  ++stats_.blobs_fetched;
  store_.insert(sha256, bytes);
  // The store may evict at once when it is full: the waiter gets the bytes through `held`.
  held_[sha256] = std::move(bytes);
  done_(sha256, "");
  held_.erase(sha256);
}

std::vector<std::pair<std::string, std::string>> BlobFetcher::on_unavailable(const rdtf::blob_unavailable_t& answer,
                                                                             Clock::time_point now) {
  std::vector<std::pair<std::string, std::string>> out;
  for (std::size_t i = 0; i < answer.sha256.size() && i < answer.reason.size(); ++i) {
    const auto it = fetches_.find(answer.sha256[i]);
    if (it == fetches_.end()) continue;
    for (const auto& waiter : it->second.waiters) {
      out.emplace_back(waiter, "blob " + answer.sha256[i] + " not available: " + answer.reason[i]);
    }
    // Asked again later: a newer revision (whose DESCRIPTION the caller will request) may serve it.
    it->second.due = now + options_.retry_max;
  }
  return out;
}

std::shared_ptr<const std::string> BlobFetcher::just_completed(const std::string& sha256) const {
  const auto it = held_.find(sha256);
  return it == held_.end() ? nullptr : it->second;
}

void BlobFetcher::tick(Clock::time_point now) {
  for (auto& [sha, f] : fetches_) {
    if (f.active) continue;
    if (active_bytes_ > 0 && active_bytes_ + f.size > options_.limits.max_fetch_bytes) continue;
    f.active = true;
    active_bytes_ += f.size;
  }
  if (!refilled_) {
    tokens_ = kRequestBurst;
  } else if (now > *refilled_) {
    tokens_ = std::min(kRequestBurst, tokens_ + std::chrono::duration<double>(now - *refilled_).count() * kRequestsPerSecond);
  }
  refilled_ = now;
  // While chunks of some blob keep coming, rdtfd is still sending what was asked: a blob queued
  // behind others is not asked for again.
  const bool streaming = now < last_chunk_ + options_.chunk_gap;
  rdtf::blob_request_t request;
  request.utime = 0;
  request.num_ranges = 0;
  auto flush = [&] {
    if (request.num_ranges == 0) return;
    send_(request);
    ++stats_.blob_requests_sent;
    tokens_ -= 1;
    request.sha256.clear();
    request.first_chunk.clear();
    request.num_chunks.clear();
    request.num_ranges = 0;
  };
  // False when no request may be sent now: the range waits for a later tick.
  auto add = [&](const std::string& sha, std::int32_t first, std::int32_t count, bool again) {
    if (request.num_ranges > 0 && static_cast<std::size_t>(request.getEncodedSize()) + kRangeBytes > kMaxRequestBytes) {
      flush();
    }
    if (request.num_ranges == 0 && tokens_ < 1) return false;
    if (again) stats_.blob_chunks_reasked += static_cast<std::uint64_t>(count);
    request.sha256.push_back(sha);
    request.first_chunk.push_back(first);
    request.num_chunks.push_back(count);
    ++request.num_ranges;
    return true;
  };
  for (auto& [sha, f] : fetches_) {
    if (!f.active) continue;
    // A round of asking (every missing range of the blob, once) may take several ticks; one
    // under way goes on whatever comes meanwhile.
    if (f.resume == 0 && (now < f.due || (streaming && f.requested_once))) continue;
    std::int32_t stopped_at = -1;
    if (f.chunk_size < 0) {
      if (!add(sha, 0, -1, false)) break;
    } else {
      for (std::int32_t i = f.resume; i < f.count;) {
        if (f.have[static_cast<std::size_t>(i)]) {
          ++i;
          continue;
        }
        std::int32_t j = i;
        while (j < f.count && !f.have[static_cast<std::size_t>(j)]) ++j;
        if (!add(sha, i, j - i, f.requested_once)) {
          stopped_at = i;
          break;
        }
        i = j;
      }
    }
    if (stopped_at >= 0) {
      f.resume = stopped_at;
      break;
    }
    f.resume = 0;
    if (f.requested_once) ++stats_.blob_retries;
    f.requested_once = true;
    f.due = now + f.backoff;
    f.backoff = std::min<Clock::duration>(f.backoff * 2, options_.retry_max);
  }
  flush();
}

}  // namespace rdtf::client::detail
