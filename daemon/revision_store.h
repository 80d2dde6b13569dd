// Revision numbers that last across restarts of rdtfd (docs/lcm.md, "Revision numbers"): for each
// model one small file, <output>/.rdtfd-state/m-<32 hex digits of SHA-256(model id)>.json, with the
// highest number handed out and the live revision (number, content hash, a digest of the result
// and the facts a DELTA compares). Replaced atomically (temporary file, rename) before a number is
// published, and made durable (fsync) only when the number is above the block reserved so far:
// then the file reserves the next kReservedRevisions numbers at once (docs/daemon.md, "Revision
// state"). Read defensively: anything but a whole, well-formed file for that model is refused with
// the reason, and the caller numbers from a floor no earlier number can reach.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "conversion.h"
#include "rdtf/diff.h"

namespace rdtf::daemon {

// The live revision as remembered: enough to keep its number for the same result and to diff
// the next revision against it.
struct StoredRevision {
  std::int64_t revision = 0;
  std::string content_hash;
  std::string result_digest;  // result_digest() of the ConvertedModel
  RobotFacts facts;
};

// How many numbers one durable save reserves: a model is fsynced once per this many revisions.
inline constexpr std::int64_t kReservedRevisions = 100;

struct ModelState {
  std::string model_id;
  std::string source;           // The model file's path when it was saved.
  std::int64_t numbered = 0;    // Highest revision number handed out (accepted or rejected).
  // No number above this was handed out. Only a durable save raises it, so after a power loss
  // (which can take back the saves since) it still bounds every number the bus has seen. At least
  // `numbered`; a file of an earlier version without it reads as `numbered`.
  std::int64_t reserved = 0;
  std::optional<StoredRevision> live;
};

// What a revision's publication depends on besides the content hash: the same files converted with
// other settings (a reload, a restart with another config) that give other outputs or another
// verdict are another result, and so another number.
std::string result_digest(const ConvertedModel& model);

// The state as JSON text, and back. from_json refuses (nothing, with `why`) anything that is not
// exactly such a document: wrong or missing fields, numbers out of range or not finite, a live
// revision above `numbered`.
std::string state_to_json(const ModelState& state);
std::optional<ModelState> state_from_json(std::string_view text, std::string& why);

// The facts a DELTA compares, as the state file holds them (also the result cache's form). The
// reader refuses (nothing, with `why`) anything but such an object.
nlohmann::json facts_to_json(const RobotFacts& facts);
std::optional<RobotFacts> facts_from_json(const nlohmann::json& json, std::string& why);

// Revision numbers above any this daemon can have handed out before now: microseconds since the
// Unix epoch. Numbers are handed out one at a time, each after a conversion and an fsync (far more
// than a microsecond), so a number counted up from an earlier floor (or from 1) is below the
// clock's reading when it was handed out. Used when a model's state file exists but cannot be
// trusted.
std::int64_t revision_floor_now();

class RevisionStore {
 public:
  // The folder below the output root that holds the state files.
  static std::filesystem::path folder_for(const std::filesystem::path& output_root);
  static std::filesystem::path file_for(const std::filesystem::path& output_root, const std::string& model_id);

  enum class LoadResult { kAbsent, kLoaded, kRefused, kUnavailable };
  // Reads the state of `model_id`: kAbsent when there is no file, kRefused (with `why`) when it is
  // not a regular file, larger than 64 MiB, torn, malformed or about another model, kUnavailable
  // (with `why`) when it could not be read for want of descriptors or memory (rdtf/shortage.h).
  static LoadResult load(const std::filesystem::path& output_root, const std::string& model_id, ModelState& state,
                         std::string& why);
  // After a power loss may have taken back saves made without an fsync: every state file's
  // `numbered` raised to its `reserved` (no number above it was handed out), then the file system
  // synced, so that numbering from `numbered` never hands a number out twice. Files that are
  // refused are left (a start refuses them again). Returns how many were raised; false with `why`
  // when a file could not be rewritten or the sync failed.
  static bool number_from_reserves(const std::filesystem::path& output_root, int& raised, std::string& why);
  // Replaces it atomically (folder made as needed), and with `durable` also fsyncs the file and its
  // folder before returning. False with `why` when that failed.
  static bool save(const std::filesystem::path& output_root, const ModelState& state, bool durable, std::string& why);
};

}  // namespace rdtf::daemon
