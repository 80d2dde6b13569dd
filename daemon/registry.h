// Every model the daemon knows: its id, the files it refers to, and the last good revision it
// serves (kept when a later save is broken).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "conversion.h"
#include "model_schedule.h"
#include "revision_store.h"

namespace rdtf {
class model_error_t;
}  // namespace rdtf

namespace rdtf::daemon {

struct ModelRecord {
  std::string id;
  std::filesystem::path source;
  std::int64_t revisions = 0;              // Number of the revision served (0: none yet).
  // Revision numbers handed out: accepted revisions and revisions the dynamics check rejected
  // (their VALIDATION carries the number), so that one number never means two contents.
  std::int64_t numbered = 0;
  // Numbers up to this are reserved by a durable save of the state file (ModelState::reserved):
  // handing one out needs no fsync.
  std::int64_t reserved = 0;
  std::optional<ConvertedModel> live;      // The revision served (number: `revisions`).
  std::string last_hash;                   // Content last converted, good or bad.
  std::vector<std::filesystem::path> dependencies;
  ModelSchedule schedule;                  // Where its scheduling stands (model_schedule.h).
  std::optional<Clock::time_point> timer;  // schedule's deadline as filed in the daemon's timer index.
  // The live revision of an earlier run (the state file), until the first conversion: the same
  // result keeps its number, another one is diffed against it.
  std::optional<StoredRevision> restored;
  // Its state file could not be read for want of descriptors or memory: read again before any
  // number is handed out (numbering from the clock for good would answer a failure that passes).
  bool state_unread = false;
  std::string live_result;  // result_digest() of `live`, computed once.
  // `live`'s rdtf_json and urdf were released after its first publication (release_live_texts):
  // live_texts() reads them from its output files.
  bool texts_on_disk = false;
  // The gate's last verdict on this model (verdict_memo.h), handed to its next conversion. Kept
  // whatever became of the revision it judged: a verdict depends only on what it was computed from.
  std::shared_ptr<const VerdictMemo> verdict;
  // A conversion made while the model settled, waiting for its deadline (model_schedule.h,
  // holds_prepared()): its outputs are staged, not yet in place.
  std::optional<ConversionOutcome> prepared;
  // The ERROR of its last save refused while no revision of it is live: a REQUEST for the model
  // is answered with it again, since a subscriber that came late has nothing else to learn why.
  // Dropped once a revision goes live.
  std::shared_ptr<const rdtf::model_error_t> refusal;
};

// The live revision's two primary texts, as its DESCRIPTION carries them.
struct LiveTexts {
  std::string rdtf_json;
  std::string urdf;
};

// A record holds its live revision's .rdtf.gltf document and URDF only until they are first
// published: with 10,000 models they were a quarter of rdtfd's heap (docs/benchmarks.md). Later
// publications read them back from the output files, which rdtfd wrote and the manifest (`files`)
// describes by size and SHA-256.
void release_live_texts(ModelRecord& record);
// The texts of the live revision: from memory before release_live_texts, else from its output
// files. False, with why, when a file can no longer be read or no longer is what the manifest
// says (changed or removed behind rdtfd's back): no description must then be published from it.
bool live_texts(const ModelRecord& record, LiveTexts& texts, std::string& why);
// Whether `candidate`'s texts are the live revision's, given that their manifests (`files`) are
// equal: compared as they are while in memory; once released, by the manifest, whose entries hold
// each text's size and SHA-256 (a text is only released when the manifest describes it).
bool same_live_texts(const ModelRecord& record, const ConvertedModel& candidate);

// Model ids: the model's path below its watched folder ("arm3.gltf", "sub/robot.glb"), prefixed
// by that folder's name when several folders are watched ("<name>_<position>" when two share a
// name), with characters outside
// [A-Za-z0-9._/-] replaced by '_'; shortened (keeping the end and a hash) to fit LCM's channel
// names. A regex on the id selects one model's channels.
std::string model_id_for(const std::filesystem::path& source,
                         const std::vector<std::filesystem::path>& roots, std::size_t max_length);

class Registry {
 public:
  ModelRecord& ensure(const std::filesystem::path& source, const std::string& id);
  ModelRecord* find(const std::filesystem::path& source);
  ModelRecord* find_id(const std::string& id);
  const ModelRecord* find_id(const std::string& id) const;
  void erase(const std::filesystem::path& source);
  // Models that refer to `file` (a .bin or image).
  std::vector<std::filesystem::path> dependents(const std::filesystem::path& file) const;
  std::map<std::filesystem::path, ModelRecord>& all() { return models_; }
  const std::map<std::filesystem::path, ModelRecord>& all() const { return models_; }

 private:
  std::map<std::filesystem::path, ModelRecord> models_;
  std::map<std::string, std::filesystem::path> ids_;  // id -> source: find_id in log time.
};

bool is_model_file(const std::filesystem::path& path);

}  // namespace rdtf::daemon

namespace rdtf::daemon {

// Lasting revision numbers (revision_store.h) for the records of the registry.
// Seeds a record just made from its state file: the highest number handed out and the live
// revision of the earlier run (ModelRecord::restored, when the model file is the same). A state
// file that cannot be trusted is ignored, and the record numbers from revision_floor_now(), above
// any number it can have handed out. A state file that cannot be read now (out of descriptors)
// sets `state_unread` and changes nothing else; a later call reads it again. Returns a line for
// the log when it was refused or not read, else "".
// The file's `numbered` is trusted: after a possible power loss the start raised every file's
// `numbered` to its `reserved` first (RevisionStore::number_from_reserves).
std::string restore_revisions(const std::filesystem::path& output_root, ModelRecord& record);

// The revision a record serves in its stored form: the live one, else the one of the earlier run.
std::optional<StoredRevision> stored_live(const ModelRecord& record);

// Writes the record's state: its id, source and `numbered`, and `live` as the live revision;
// durably, reserving the next kReservedRevisions numbers, when `numbered` is above the record's
// reserve. "" or why it failed.
std::string save_revisions(const std::filesystem::path& output_root, ModelRecord& record,
                           const std::optional<StoredRevision>& live);

}  // namespace rdtf::daemon
