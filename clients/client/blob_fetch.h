// Content-addressed blobs: the store of blobs held (shared by every model and revision, so a blob
// is fetched once) and the fetches under way. A fetch asks rdtfd on <prefix>/BLOB_REQUEST, takes
// the chunks on <prefix>/BLOB (any client's: chunks are multicast), checks each against the size
// the manifest gave, and the whole against its SHA-256; chunks that stop coming are asked for
// again by range, after `chunk_gap`, then with back-off. No I/O; the caller passes the clock.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <rdtf/blob_chunk_t.hpp>
#include <rdtf/blob_request_t.hpp>
#include <rdtf/blob_unavailable_t.hpp>

#include "rdtf/client.h"

namespace rdtf::client::detail {

class BlobStore {
 public:
  explicit BlobStore(std::int64_t capacity) : capacity_(capacity) {}
  std::shared_ptr<const std::string> find(const std::string& sha256);
  // Adds a checked blob; evicts the least recently used blobs nobody else holds while over capacity.
  void insert(const std::string& sha256, std::shared_ptr<const std::string> bytes);
  // Evicts, while over capacity, the least recently used blobs nobody else holds (any more).
  void trim();
  std::int64_t bytes() const { return bytes_; }

 private:
  struct Held {
    std::shared_ptr<const std::string> bytes;
    std::uint64_t used = 0;
  };
  std::int64_t capacity_;
  std::int64_t bytes_ = 0;
  std::uint64_t clock_ = 0;
  std::map<std::string, Held> blobs_;
};

class BlobFetcher {
 public:
  using SendRequest = std::function<void(const rdtf::blob_request_t&)>;
  // A blob completed (checked and stored) or failed for good; `problem` is "" on success.
  using Done = std::function<void(const std::string& sha256, const std::string& problem)>;

  BlobFetcher(const Options& options, BlobStore& store, SendRequest send, Done done, Stats& stats)
      : options_(options), store_(store), send_(std::move(send)), done_(std::move(done)), stats_(stats) {}

  // `waiter` (a model id) needs the blob `sha256` of `size` bytes. Already fetching: joins.
  void want(const std::string& sha256, std::int64_t size, const std::string& waiter, Clock::time_point now);
  // `waiter` needs none of its blobs any more (a newer revision, the model removed).
  void release(const std::string& waiter);
  bool fetching(const std::string& sha256) const { return fetches_.count(sha256) > 0; }
  // How far the fetch of `sha256` is, for a message: "1200 of 4720 chunks", "not answered yet".
  std::string progress(const std::string& sha256) const;
  // Inside a Done callback: the blob that just completed (the store may already have evicted it).
  std::shared_ptr<const std::string> just_completed(const std::string& sha256) const;

  // "" when the chunk was used or is of no blob fetched; else why it was dropped.
  std::string on_chunk(const rdtf::blob_chunk_t& chunk, Clock::time_point now);
  // rdtfd does not serve some blobs: returns the waiters of those it names, with the reason.
  std::vector<std::pair<std::string, std::string>> on_unavailable(const rdtf::blob_unavailable_t& answer,
                                                                  Clock::time_point now);
  // Sends the requests that are due: new fetches, and missing chunks of stalled ones.
  void tick(Clock::time_point now);

 private:
  struct Fetch {
    std::int64_t size = 0;
    std::int32_t chunk_size = -1;  // -1: no chunk yet
    std::int32_t count = -1;
    std::string data;
    std::vector<bool> have;
    std::int32_t received = 0;
    std::set<std::string> waiters;
    bool active = false;           // requested (its bytes count against max_fetch_bytes)
    bool requested_once = false;
    Clock::time_point due{};       // when to ask (again)
    Clock::duration backoff{};
    std::int32_t resume = 0;       // where a round of asking, cut short by the pacing, goes on
    int hash_failures = 0;
  };
  void reset(Fetch& fetch);
  void complete(const std::string& sha256, Fetch& fetch);

  const Options& options_;
  BlobStore& store_;
  SendRequest send_;
  Done done_;
  Stats& stats_;
  std::map<std::string, Fetch> fetches_;
  std::int64_t active_bytes_ = 0;
  Clock::time_point last_chunk_{};
  double tokens_ = 0;  // requests that may be sent now (paced: blob_fetch.cc)
  std::optional<Clock::time_point> refilled_;
  std::map<std::string, std::shared_ptr<const std::string>> held_;
};

}  // namespace rdtf::client::detail
