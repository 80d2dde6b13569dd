// rdtf_client: what every subscriber of rdtfd needs, in one place (docs/lcm.md, "The client
// library").
//
//   lcm::LCM lcm(url);
//   rdtf::client::Options options;
//   options.model = "arm3.gltf";               // or options.pattern = "arms/.*"; both empty: all
//   options.blobs = rdtf::client::Blobs::kAll;  // kNone for a controller
//   rdtf::client::Callbacks callbacks;
//   callbacks.on_revision = [](std::shared_ptr<const rdtf::client::Snapshot> s) { ... };
//   rdtf::client::Client client(lcm, options, callbacks);   // subscribes, sends a request_t
//   while (running) { lcm.handleTimeout(50); client.tick(); }
//
// It reassembles a revision's parts (DESCRIPTION, DESCRIPTION_CHUNK, URDF_CHUNK, the INERTIA
// parts, the MANIFEST parts, its VALIDATION) by (model_id, revision, content_hash), checks every
// size and hash, fetches the blobs the caller wants that it does not hold (a blob held from any
// earlier revision or model is never asked for again), re-requests what was lost with back-off,
// and hands the caller only complete, consistent snapshots; joint and link states only when they
// carry the revision and content hash of the model's current snapshot.
//
// Threading: a Client is used from the thread that dispatches its lcm::LCM (handlers and tick()
// run there; it has no thread of its own and is not thread-safe). It does no file I/O and never
// waits: a handler costs the decode, the copy of a chunk and, when a blob or document completes,
// its SHA-256 (about 2 ms per MB here). Memory is bounded by Limits.
//
// Every datagram is decoded with rdtf::lcm_safe::decode (schema check first). One that is
// malformed, inconsistent or beyond a limit is dropped with a reason (Callbacks::on_drop, or a
// rate-limited line on stderr) and never stops the rest.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <rdtf/description_t.hpp>
#include <rdtf/file_t.hpp>
#include <rdtf/inertia_table_t.hpp>
#include <rdtf/joint_state_t.hpp>
#include <rdtf/link_state_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/model_removed_t.hpp>
#include <rdtf/model_saving_t.hpp>
#include <rdtf/validation_report_t.hpp>

namespace lcm {
class LCM;
class Subscription;
}

namespace rdtf::client {

using Clock = std::chrono::steady_clock;

// Bounds on what the bus may make a client hold. A claim beyond one is dropped with a reason.
struct Limits {
  std::int64_t max_document_bytes = std::int64_t{64} << 20;  // one RDTF JSON or URDF text
  std::int32_t max_chunks = 1 << 16;          // DESCRIPTION_CHUNKs or URDF_CHUNKs of one document
  std::int32_t max_links = 1 << 16;           // links of one inertia table
  std::int32_t max_parts = 1 << 12;           // INERTIA or MANIFEST messages of one revision
  std::int32_t max_files = 1 << 16;           // files of one manifest
  std::int64_t max_blob_bytes = std::int64_t{1} << 30;         // one blob
  std::int64_t max_fetch_bytes = std::int64_t{1} << 30;        // blobs being received at once
  // Blobs held. Over it, those no snapshot the client or its caller holds are evicted, least
  // recently used first, when a blob arrives and at each tick(). 0: hold only what is in use.
  std::int64_t max_store_bytes = std::int64_t{4} << 30;
  std::size_t max_pending_revisions = 4;      // incomplete revisions held per model (oldest dropped)
  std::int64_t max_pending_bytes = std::int64_t{256} << 20;  // chunks held by every incomplete revision
  std::size_t max_models = 4096;              // models followed at once
};

// Which blobs (files of a revision's manifest) a snapshot comes with.
enum class Blobs {
  kNone,  // none: no MANIFEST needed, nothing fetched (a controller)
  kAll,   // every file of the manifest (`rdtf pull`, a viewer)
};

struct Options {
  std::string prefix = "RDTF";  // rdtfd's channel prefix
  std::string model;            // one model id (exact), or ...
  std::string pattern;          // ... an LCM regular expression of model ids; both empty: all models
  Blobs blobs = Blobs::kNone;
  // With Blobs::kAll: fetch only the files of these manifest roles ("rdtf", "buffer", "image",
  // "urdf", "urdf_mesh"); empty: every file. A viewer drawing the glTF needs no URDF meshes.
  std::set<std::string> blob_roles;
  bool states = true;           // deliver JOINT_STATE and LINK_STATE
  bool send_requests = true;    // false: never send request_t (wait for rdtfd's republications)
  std::string requester;        // names this client in requests; default "rdtf_client <host> <pid>"
  Limits limits;
  // Re-requests: the first after `retry_initial` without progress, doubled up to `retry_max`.
  Clock::duration retry_initial = std::chrono::milliseconds(250);
  Clock::duration retry_max = std::chrono::seconds(2);
  // A blob whose chunks stop arriving for this long has its missing chunks asked for again.
  Clock::duration chunk_gap = std::chrono::milliseconds(150);
};

// One complete revision of one model, every part checked.
struct Snapshot {
  // As published, with rdtf_json and urdf filled in whole (reassembled from chunks when sent so).
  rdtf::description_t description;
  // Every link of the revision (the INERTIA parts joined; num_links is their total).
  rdtf::inertia_table_t inertia;
  // The revision's VALIDATION, when the description says it was validated.
  std::optional<rdtf::validation_report_t> validation;
  // The output files of the revision (MANIFEST), when it arrived (always with Blobs::kAll).
  std::vector<rdtf::file_t> manifest;
  bool has_manifest = false;
  // The bytes of every manifest file (of Options::blob_roles when set), by SHA-256 (Blobs::kAll;
  // empty with kNone).
  std::map<std::string, std::shared_ptr<const std::string>> blobs;

  const std::string& model_id() const { return description.model_id; }
  std::int64_t revision() const { return description.revision; }
  const std::string& content_hash() const { return description.content_hash; }
  // The bytes of a manifest file by its path, or nullptr.
  const std::string* file(const std::string& path) const;
};

struct Callbacks {
  // A model's new live revision (complete; replaces the previous snapshot of that model).
  std::function<void(std::shared_ptr<const Snapshot>)> on_revision;
  // ERROR: a save that could not be converted, or a command rdtfd rejected.
  std::function<void(const rdtf::model_error_t&)> on_error;
  // REMOVED: the model is gone (its snapshot is forgotten).
  std::function<void(const rdtf::model_removed_t&)> on_removed;
  // SAVING: a save of a live model is settling; a new revision or an ERROR may follow.
  std::function<void(const rdtf::model_saving_t&)> on_saving;
  // States stamped with the current snapshot's revision and content hash (others are not handed over).
  std::function<void(const Snapshot&, const rdtf::joint_state_t&)> on_joint_state;
  std::function<void(const Snapshot&, const rdtf::link_state_t&)> on_link_state;
  // A datagram or an assembled part dropped, with the reason. Unset: a rate-limited line on stderr.
  std::function<void(const std::string& channel, const std::string& reason)> on_drop;
  // Something the client cannot fix by retrying soon (a blob rdtfd says it does not serve, a
  // blob whose bytes keep failing their hash). Unset: a line on stderr.
  std::function<void(const std::string& model_id, const std::string& problem)> on_problem;
};

// What went over the bus for this client (bench/, tests).
struct Stats {
  std::uint64_t datagrams = 0;          // received on the client's subscriptions
  std::uint64_t bytes = 0;              // their payload bytes
  std::uint64_t dropped = 0;            // dropped with a reason
  std::uint64_t blob_chunks = 0;        // BLOB chunks used
  std::uint64_t blob_bytes = 0;         // payload bytes of those chunks
  std::uint64_t blob_chunks_ignored = 0;  // chunks of blobs not wanted or already held
  std::uint64_t blobs_fetched = 0;      // blobs received whole and checked
  std::uint64_t requests_sent = 0;      // request_t
  std::uint64_t blob_requests_sent = 0; // blob_request_t
  std::uint64_t blob_retries = 0;       // blob_request_t ranges for chunks already asked for once
  std::uint64_t blob_chunks_reasked = 0;  // chunks in those ranges (lost ones, or not yet sent)
  std::int64_t blob_chunk_size = 0;     // the largest chunk_size of the chunks used (bytes)
  std::uint64_t revisions = 0;          // snapshots handed over
};

class Client {
 public:
  // Sends an encoded message (for tests and fuzzing without LCM).
  using Publish = std::function<void(const std::string& channel, const std::vector<std::uint8_t>& bytes)>;

  // Subscribes on `lcm` (which the caller owns and dispatches; it must outlive the client) and
  // sends a request_t so that a late joiner gets the live revisions at once.
  Client(lcm::LCM& lcm, Options options, Callbacks callbacks);
  // Without LCM: datagrams come through on_datagram(), messages go out through `publish`.
  Client(Publish publish, Options options, Callbacks callbacks);
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  // Retries what was lost. Call it after each dispatch, at least every 100 ms.
  void tick() { tick(Clock::now()); }
  void tick(Clock::time_point now);

  // One datagram's payload as a subscription hands it (called by the LCM handlers).
  void on_datagram(const std::string& channel, const void* data, std::size_t size, Clock::time_point now);

  // The current snapshot of a model, or nullptr.
  std::shared_ptr<const Snapshot> snapshot(const std::string& model_id) const;
  // What the newest incomplete revision of a model still lacks, for a message ("revision 3:
  // INERTIA (2 of 5 links); blob 1f2e3d4c5b6a (arm.bin): 1200 of 4720 chunks"); "" when none of
  // its revisions is incomplete.
  std::string waiting_for(const std::string& model_id) const;
  // Every model id heard of: on the subscribed channels and in rdtfd's STATUS (live models).
  std::set<std::string> models_seen() const;
  // The channels (LCM regular expressions) the client subscribes to.
  std::vector<std::string> channels() const;
  Stats stats() const;

 private:
  struct State;
  void subscribe(lcm::LCM& lcm);
  std::unique_ptr<State> state_;
  lcm::LCM* lcm_ = nullptr;
  std::vector<lcm::Subscription*> subscriptions_;
};

// Whether `path` (from a manifest) is a safe relative path: not empty, '/'-separated, no empty,
// "." or ".." part, not absolute, no backslash or control character. Empty when fine; else why not.
std::string check_relative_path(const std::string& path);

// Plain lower-case hex SHA-256 of bytes (as sha256sum prints it).
std::string sha256_hex(const void* data, std::size_t size);

}  // namespace rdtf::client
