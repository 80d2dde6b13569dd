// Content-addressed blobs on LCM (docs/lcm.md, "Files and blobs"): the files of every model's
// live revision, by SHA-256, in chunks that each fit one datagram.
//
// A request (<prefix>/BLOB_REQUEST) names blobs, whole or chunk ranges of them. Each blob asked
// for becomes one job, shared by everyone who asks for it until it is sent (multicast: every
// subscriber receives each chunk), so identical requests within one pass cost one pass. Jobs are
// fed into the Publisher lazily, a chunk at a time, while its queue holds less than kQueueBytes:
// a blob of hundreds of MB never sits in memory or in the send queue, and the Publisher's pacing
// by receive-buffer cost applies to every chunk. A file is read from below the output folder
// without following any symlink, and its bytes are checked against the hash before the first
// chunk goes (a file changed on disk is answered as unavailable, never sent as the blob).
//
// What cannot be served is answered on <prefix>/BLOB_UNAVAILABLE with a reason; what is malformed
// or over a limit is dropped unanswered, counted and logged (BusInput, at most once a second).
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <rdtf/blob_request_t.hpp>
#include <rdtf/blob_unavailable_t.hpp>

#include "blob_manifest.h"
#include "publisher.h"

namespace rdtf::daemon {

// A file of a live revision: <folder>/<path>, `size` bytes.
struct BlobSource {
  std::string model_id;
  // The model's output folder (<output>/<model_id>). A string, not a path: libstdc++'s path keeps
  // a list of its components on the heap, and the index holds this for every file of every model.
  std::string folder;
  std::string path;              // Relative, as in the manifest.
  std::int64_t size = 0;
};

// sha256 -> where the blob is, over the live revision of every model.
class BlobIndex {
 public:
  // The model's live revision is now `files` (in `folder`): the previous revision's go.
  void set_model(const std::string& model_id, const std::filesystem::path& folder, const std::vector<OutputFile>& files);
  void remove_model(const std::string& model_id);
  // A place that holds the blob (the first model that listed it), or null.
  const BlobSource* find(const std::string& sha256) const;
  std::size_t size() const { return by_hash_.size(); }

 private:
  std::map<std::string, std::vector<BlobSource>> by_hash_;
  std::map<std::string, std::vector<std::string>> hashes_of_model_;
};

struct BlobCounters {
  std::int64_t requests = 0;          // Requests taken.
  std::int64_t chunks_sent = 0;       // Chunks queued in the Publisher.
  std::int64_t bytes_sent = 0;        // Blob bytes in them.
  std::int64_t unavailable = 0;       // Blobs answered as unavailable.
  std::int64_t dropped = 0;           // Requests dropped (malformed, over a limit).
};

// Whether `text` is a SHA-256 as the manifest writes it: 64 lowercase hex digits.
bool is_sha256_hex(const std::string& text);

class BlobServer {
 public:
  using Clock = std::chrono::steady_clock;
  using Log = std::function<void(const std::string&)>;

  // Limits (docs/lcm.md, "Files and blobs").
  static constexpr std::size_t kQueueBytes = 1024 * 1024;     // Chunks fed while the send queue is below.
  static constexpr std::int32_t kMaxRanges = 256;             // Per request.
  static constexpr std::size_t kMaxJobs = 1024;               // Distinct blobs waiting to be sent.
  static constexpr std::size_t kOpenJobs = 8;                 // Sent at once, round robin (open files).
  static constexpr std::size_t kVerifyBytesPerPump = 16 << 20;  // Hashed per turn of the event loop.
  static constexpr double kRequestsPerSecond = 50;            // Per requester name ...
  static constexpr double kRequestBurst = 100;
  static constexpr double kAllRequestsPerSecond = 500;        // ... and over all requesters.
  static constexpr double kAllRequestBurst = 1000;
  // BLOB_UNAVAILABLE entries a second (a request of 256 unknown hashes is answered with 256): so
  // that a flood of such requests cannot fill the send queue with answers. Beyond, the rest of a
  // request goes unanswered, counted as dropped and logged.
  static constexpr double kUnavailablePerSecond = 2000;
  static constexpr double kUnavailableBurst = 4000;

  explicit BlobServer(Log log);
  ~BlobServer();
  BlobServer(const BlobServer&) = delete;
  BlobServer& operator=(const BlobServer&) = delete;

  // The live revisions (forwarded to the index; verification results of blobs gone are forgotten).
  void set_model(const std::string& model_id, const std::filesystem::path& folder, const std::vector<OutputFile>& files);
  void remove_model(const std::string& model_id);
  const BlobIndex& index() const { return index_; }

  // Chunks and answers encode to at most `max_message_bytes` (the daemon's max_chunk_bytes).
  void set_max_message_bytes(std::size_t max_message_bytes);
  std::int32_t chunk_size() const { return chunk_size_; }

  // One schema-checked request. "" when taken (answered now with BLOB_UNAVAILABLE for what cannot
  // be served, the rest queued), else why it was dropped unanswered (the caller logs and counts it).
  std::string request(const rdtf::blob_request_t& request, Clock::time_point now, Publisher& out,
                      const std::string& prefix);
  // Verifies files (a bounded slice) and feeds chunks while out's queue is below kQueueBytes.
  void pump(Publisher& out, const std::string& prefix);
  // Whether pump would do something now (then the event loop does not sleep).
  bool ready(const Publisher& out) const;
  std::size_t jobs() const { return jobs_.size(); }
  // The daemon made a new Publisher (LCM reconnected): what the old one held is no longer known.
  void publisher_replaced();
  const BlobCounters& counters() const { return counters_; }

 private:
  struct Job;
  struct Bucket {
    double tokens = 0;
    Clock::time_point last{};
  };
  struct FileStamp;
  bool admit(const std::string& requester, Clock::time_point now);
  // Adds chunks [first, first + count) of the blob to its job; "" or why it cannot be served.
  // Chunks still waiting in the send queue (queued after `departed`) are not queued again.
  std::string add(const std::string& sha256, std::int64_t first, std::int64_t count, const std::string& requester,
                  std::uint64_t departed);
  void forget_departed(std::uint64_t departed);  // Drops marks of chunks sent; ends jobs done.
  bool open(Job& job, std::string& why);
  bool verify(Job& job, std::size_t& budget, std::string& why);  // False: failed (`why`) or not done.
  void send_next(Job& job, Publisher& out, const std::string& prefix);
  void fail(const std::string& sha256, const std::string& why, Publisher& out, const std::string& prefix);
  void unavailable(const std::string& requester, const std::vector<std::pair<std::string, std::string>>& blobs,
                   Publisher& out, const std::string& prefix);
  void note(const std::string& line);  // Logged at most once a second; the rest counted.
  void forget_verified();

  Log log_;
  BlobIndex index_;
  std::size_t max_message_bytes_ = 60000;
  std::int32_t chunk_size_ = 0;
  std::map<std::string, std::unique_ptr<Job>> jobs_;  // By sha256.
  std::deque<std::string> order_;                     // Jobs in arrival order; the first kOpenJobs are sent.
  std::size_t turn_ = 0;                              // Round robin among the open jobs.
  std::map<std::string, std::unique_ptr<FileStamp>> verified_;  // Files whose bytes matched.
  std::map<std::string, Bucket> buckets_;             // Per requester.
  Bucket all_;
  Bucket answers_;
  BlobCounters counters_;
  Clock::time_point next_note_{};
  std::uint64_t notes_unlogged_ = 0;
};

}  // namespace rdtf::daemon
