// rdtfd's persistent result cache (docs/daemon.md, "Result cache"): what converting and checking a
// model's content gave, kept across restarts, so that a restart over unchanged models publishes
// them without converting or validating them again.
//
// One entry per model file (a slot named by a hash of its path) in <output>/.rdtfd-state/results/,
// holding the key it was computed under (the settings, version and commit: settings_key()), the
// content hash, the verdict and numbers of the dynamics check, the conversion's diagnostics, the
// robot and its facts, and the SHA-256 of every output file the conversion wrote. An entry is used
// only when its model, key and content hash are the caller's and the outputs on disk still match it
// (conversion.cc checks them); anything else converts again and replaces the entry.
//
// Crash safety: each entry is one file, written whole under a temporary name and renamed into
// place, with a SHA-256 of its body in its first line. A torn or altered entry (a crash before the
// data reached the disk, a flipped byte) fails that check and is refused with the reason: the model
// is converted again and the entry rewritten. Nothing from an entry is trusted before the check.
//
// Bounded: at most `max_entries` entries (the config key max_cached_results); beyond, the least
// recently used (file modification time: set when written, touched when used) are removed.
#pragma once

#include <atomic>
#include <cstddef>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "blob_manifest.h"
#include "config.h"
#include "conversion.h"
#include "rdtf/robot.h"

namespace rdtf::daemon {

struct CachedResult {
  std::string key;           // settings_key() it was computed under.
  std::string source;        // The model file.
  std::string content_hash;  // Of what was converted (conversion.h, content_hash()).
  bool written = false;      // The outputs were written (see ConvertedModel::written).
  std::string output_name;   // The .rdtf.gltf in the model's output folder ("" when not written).
  std::string rdtf_sha256;   // Of that file's bytes.
  bool has_urdf = false;     // urdf/robot.urdf was written.
  std::string urdf_sha256;
  std::vector<OutputFile> files;  // The manifest: every file of the output folder, with its hash and size.
  std::optional<ValidationSummary> validation;
  Diagnostics diagnostics;   // The conversion's warnings and infos.
  Robot robot;
  RobotFacts facts;
};

// The entry as its file holds it: "rdtfd-results 4 <hex SHA-256 of the body>\n" then the body (JSON).
std::string cache_entry_text(const CachedResult& result);
// Refuses (nothing, with `why`) a torn, altered or malformed entry.
std::optional<CachedResult> cache_entry_from_text(std::string_view text, std::string& why);

// Everything besides the content a result depends on: every setting whose change reconverts (the
// registry's kReconvert column, daemon/config_keys.cc), rdtf's version and git commit, the cache's
// format, and for a build from a modified tree ("-dirty" commit) the daemon executable's size and
// time, since its commit does not name its code. As a hex SHA-256.
std::string settings_key(const DaemonConfig& config);

class ResultCache {
 public:
  // `folder` is made when the first entry is written. max_entries >= 1.
  ResultCache(std::filesystem::path folder, std::size_t max_entries);

  static std::filesystem::path folder_for(const std::filesystem::path& output_root);
  std::filesystem::path file_for(const std::string& source) const;

  // Counts the entries there and removes the least recently used beyond the bound. Returns how
  // many were removed.
  std::size_t open();

  enum class Lookup {
    kMiss,     // No entry, or one for other content or settings.
    kHit,      // `out` holds it (and it is marked used).
    kRefused,  // An entry that is torn, altered or malformed (`why` says how): convert again.
  };
  Lookup find(const std::string& source, const std::string& key, const std::string& content_hash,
              CachedResult& out, std::string& why);
  // Writes (or replaces) the entry of result.source; evicts beyond the bound. False with `why`.
  bool store(const CachedResult& result, std::string& why);

  std::size_t entries() const { return entries_.load(); }
  std::size_t evicted() const { return evicted_.load(); }
  std::size_t max_entries() const { return max_entries_; }

 private:
  std::size_t evict_locked();

  std::filesystem::path folder_;
  std::size_t max_entries_;
  std::mutex eviction_;
  std::atomic<std::size_t> entries_{0};
  std::atomic<std::size_t> evicted_{0};
};

}  // namespace rdtf::daemon
