// One conversion of one model, as a worker thread runs it: read, hash, convert, write the
// outputs. Plain values in and out; the event loop decides what to publish.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "rdtf/convert.h"
#include "rdtf/diagnostics.h"
#include "rdtf/diff.h"
#include "rdtf/dynamics.h"
#include "rdtf/gltf.h"
#include "rdtf/urdf.h"
#include "rdtf/robot.h"
#include "rdtf/summary.h"

#include "blob_manifest.h"

namespace rdtf::daemon {

class ResultCache;
struct VerdictMemo;
struct ConversionOutcome;
// A prepared conversion's outputs, written into a stage folder and not yet moved into place
// (conversion.cc).
struct StagedOutputs;

// The bytes conversions may read at once, across every worker: a conversion holds what it will
// read (the model and every file it names) from before its first read to its end.
class ReadBudget {
 public:
  explicit ReadBudget(std::uint64_t capacity) : capacity_(capacity) {}
  void set_capacity(std::uint64_t capacity);
  // Waits until `bytes` more fit, or until nothing is held (so that one conversion always runs).
  void acquire(std::uint64_t bytes);
  void release(std::uint64_t bytes);
  std::uint64_t held() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable freed_;
  std::uint64_t capacity_;
  std::uint64_t held_ = 0;
};

struct ConversionJob {
  std::string model_id;
  std::filesystem::path root;        // The watched folder the model lies in (canonical).
  std::filesystem::path source;      // The model file: root / a path with no symlink on it.
  std::filesystem::path output_dir;  // This model's own output folder.
  // The output folder output_dir lies in: nothing between the two may be a symlink, since rdtfd
  // writes and removes files only inside it. Empty: output_dir is created as it is.
  std::filesystem::path output_root;
  ConvertOptions options;
  std::string previous_hash;         // Content last converted (good or bad): skip when equal.
  std::optional<ValidationOptions> validation;  // Run the dynamics check when given.
  std::optional<UrdfOptions> urdf;              // Write <output_dir>/urdf/robot.urdf when given.
  // publish_failed: a revision that fails the dynamics check is published, so its outputs are
  // written too. Otherwise such a revision writes nothing: the live revision's files stay.
  bool write_failed = false;
  // The live revision's outputs (what LCM advertises): their files stay until a newer revision
  // has been committed whole, whatever happens to this one. Its manifest when it has one (then
  // the texts are not read back for this), else its texts.
  std::vector<OutputFile> live_files;
  std::string live_rdtf_json;
  std::string live_urdf;
  // What one conversion may read, the model and every file it names (each time it is named).
  std::uint64_t max_read_bytes = std::uint64_t{1} << 30;
  std::shared_ptr<ReadBudget> budget;  // Shared by every worker; none: no limit across workers.
  // Reads each file the model names (once per conversion); empty: the loader's own. Tests count
  // and interfere with reads through it.
  ConfinedReader read_file;
  // Results of earlier conversions (result_cache.h), under `cache_key` (settings_key()): a hit whose
  // outputs are still on disk is the outcome, without converting, checking or writing. None: no cache.
  std::shared_ptr<ResultCache> cache;
  std::string cache_key;
  // The gate's last verdict on this model (verdict_memo.h): reused when the robot, its geometry's
  // bounds, the file and cache_key are exactly those it was computed for. None: the check runs.
  std::shared_ptr<const VerdictMemo> verdict;
  // Converting while settling (docs/daemon.md, "Converting while settling"): the outputs are
  // written into a stage folder and left there (ConversionOutcome::staged); the daemon commits them
  // at the deadline with a job whose `commit` is that outcome, or drops them when the model
  // changed meanwhile.
  bool prepare = false;
  // This job only moves a prepared outcome's staged outputs into place and hands it on.
  std::shared_ptr<ConversionOutcome> commit;
  // Small (the model and the files it named last time hold at most kExpressBytes, or a commit):
  // the express worker may take it, so that a save of a small model never waits behind large
  // conversions that hold every worker (ThreadJobRunner).
  bool express = false;
  // Why the loop cannot number a result of this model now (its revision state not read for want of
  // descriptors): the job reads and writes nothing and comes back as a failure to try again.
  std::string not_now;
};

inline constexpr std::uint64_t kExpressBytes = std::uint64_t{16} << 20;

// The dynamics check of a revision, without the ODE world.
struct ValidationSummary {
  bool passed = false;
  double simulated_time = 0;
  std::uint64_t steps = 0;
  double energy_drift = 0;
  double worst_joint_error = 0;
  double wall_time = 0;
  Diagnostics diagnostics;
  std::string summary_line;
  // The stepper of the run that is the verdict (kWorldStep or kQuickStep; kAuto when nothing was
  // simulated), which the live simulation of the revision takes: a model is simulated as it was
  // judged, whatever the settings say later (a reload to quick_step kept a revision that only
  // dWorldStep holds live, and simulated it with QuickStep: s104rev D1).
  Stepper live_stepper = Stepper::kAuto;
  // Judged with dWorldStep after the automatic stepper's QuickStep run failed (SIM_QUICKSTEP_FAILED).
  bool after_quickstep_failed = false;
};

// What a good conversion leaves behind: all a publisher needs, no reference to the document.
//
// The output paths are strings, not std::filesystem::path: libstdc++'s path keeps a heap list of
// its components, about 450 bytes for each of these two, and rdtfd keeps one ConvertedModel for
// every live model (docs/benchmarks.md, "Memory at 10,000 models").
struct ConvertedModel {
  std::string content_hash;
  std::string output_path;
  std::string rdtf_json;
  Robot robot;
  RobotTotals totals;
  std::optional<ValidationSummary> validation;
  // False for a revision that failed the dynamics check and was not written (output_path,
  // rdtf_json, urdf_path and urdf are then empty).
  bool written = false;
  std::string urdf_path;  // Empty when no URDF was written.
  std::string urdf;
  RobotFacts facts;  // What a DELTA compares (rdtf/diff.h), with the URDF names and geometry digests.
  // Every file the revision's output folder holds (the manifest); empty when not written.
  std::vector<OutputFile> files;
};

// The live simulation's stepper for a revision: its verdict's, where it was simulated.
inline Stepper live_stepper(const ConvertedModel& revision) {
  return revision.validation ? revision.validation->live_stepper : Stepper::kAuto;
}
inline bool after_quickstep_failed(const ConvertedModel& revision) {
  return revision.validation && revision.validation->after_quickstep_failed;
}

// Where a conversion's time went, for the log's "converted" line (docs/benchmarks.md breaks a
// save's latency down by these).
struct StageTimes {
  std::chrono::microseconds read{0};     // The model and its files read, the content hashed.
  std::chrono::microseconds convert{0};  // Loaded, converted, the revision's facts taken.
  std::chrono::microseconds check{0};    // The dynamics check (the gate).
  std::chrono::microseconds write{0};    // The outputs staged and moved into place.
  std::chrono::microseconds cache{0};    // The result cache looked up (its entry is written after
                                         // the hand-over: ConversionOutcome::after_handover).
};

struct ConversionOutcome {
  enum class Kind { kConverted, kUnchanged, kRejected, kVanished };
  Kind kind = Kind::kRejected;
  std::string model_id;
  std::filesystem::path source;
  std::string content_hash;                  // Of what was read ("" when nothing could be).
  // The settings it was converted under (the job's cache_key): a reload that changes them while
  // the job runs makes its result stale, and the model is converted again.
  std::string cache_key;
  std::optional<ConvertedModel> converted;   // For kConverted.
  Diagnostics diagnostics;                   // Errors for kRejected; warnings otherwise.
  // Files the model refers to, and their targets where it names them through a symlink.
  std::vector<std::filesystem::path> dependencies;
  std::chrono::microseconds duration{0};
  StageTimes stages;
  // When the worker finished it (the event loop's pick-up delay is measured from here).
  std::chrono::steady_clock::time_point finished{};
  // The failure was the environment's, not the model's (an output could not be written: disk
  // full, read-only folder): the daemon tries the same content again after a back-off.
  bool retry = false;
  // The dynamics check was cancelled (the daemon is stopping): nothing was written or judged.
  bool cancelled = false;
  // The result came from the result cache (nothing was converted, checked or written).
  bool from_cache = false;
  // The dynamics check ran and its verdict may be reused (not cancelled, not decided by the
  // machine's load, a cache_key given): what the daemon keeps for the next save of the model.
  std::shared_ptr<const VerdictMemo> verdict;
  // The check did not run: job.verdict applied to this conversion exactly.
  bool verdict_reused = false;
  // What the cache had to say for the log: an entry refused (torn, altered), outputs that no longer
  // match one. Empty when nothing.
  std::string cache_note;
  // Work the revision's publication need not wait for: storing the result in the cache (about
  // 0.8 ms of an 8 ms save to publish). Whoever runs the job calls it once the outcome is on its
  // way to the loop (ThreadJobRunner: right after handing it over, on the worker's thread); it
  // touches nothing the outcome holds and logs its own failure. Empty when there is none.
  std::function<void()> after_handover;
  // From a job with `prepare` (its result waits for the deadline, or is dropped).
  bool prepared = false;
  // A prepared result's outputs, staged and not committed (their stage folder goes with the last
  // owner); null once committed, and for results that write nothing.
  std::shared_ptr<StagedOutputs> staged;
  // Converted ahead of the deadline, while the model settled: the log says so.
  bool while_settling = false;
};

ConversionOutcome run_conversion(const ConversionJob& job);

// The key a job's result is stored and found under in the result cache: its cache_key and its
// output folder.
std::string cache_entry_key(const ConversionJob& job);

// Content hash of several files: hex SHA-256 over each part's length (8 bytes, little endian)
// followed by its bytes, so that moving bytes from one file to the next changes it. A null part
// (a file not read) counts as a length of 2^64 - 1 and no bytes.
std::string sha256_hex(const std::vector<const std::vector<std::uint8_t>*>& parts);
// The content hash of a model: its bytes, then each file it names (`named`, in the order of its
// buffers and images, as often as named) as read in `files` (a null part when it could not be read).
std::string content_hash(const std::vector<std::uint8_t>& model, const std::vector<std::filesystem::path>& named,
                         const SourceFiles& files);
// Lowercase hex of a digest's bytes.
std::string to_hex(std::span<const unsigned char> bytes);

// Plain hex SHA-256 of a text (e.g. rdtf_json_sha256, checkable with sha256sum).
std::string sha256_hex(std::string_view text);

// The digest that names the files beside the daemon's outputs (plain SHA-256, as sha256sum
// prints it): the .bin of a .rdtf.gltf and the meshes of a robot.urdf are content-addressed, so
// that renaming the primary file into place commits the whole set (docs/daemon.md, "Outputs").
std::string output_digest(std::span<const std::uint8_t> bytes);

}  // namespace rdtf::daemon
