// The parts of one revision of one model, (model_id, revision, content_hash), as they arrive in
// any order and with losses: the DESCRIPTION, the chunks of its RDTF JSON and URDF, the INERTIA
// parts, the MANIFEST parts and the VALIDATION. Every add_* checks its message against the limits
// and what is already known, and returns "" or why it was dropped; assemble() joins and checks
// the whole (sizes, SHA-256s, counts) and yields a Snapshot without blobs. No I/O, no clock.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <rdtf/description_chunk_t.hpp>
#include <rdtf/manifest_t.hpp>

#include "rdtf/client.h"

namespace rdtf::client::detail {

// An RDTF JSON or URDF text sent as description_chunk_t messages.
struct ChunkedDocument {
  std::int32_t count = -1;  // announced by the chunks (-1: none yet)
  std::map<std::int32_t, std::string> chunks;
  std::int64_t bytes = 0;

  std::string add(const rdtf::description_chunk_t& chunk, const Limits& limits);
  bool complete() const { return count >= 0 && chunks.size() == static_cast<std::size_t>(count); }
  void clear() { *this = ChunkedDocument(); }
};

// Checks a description's own fields against the limits (sizes, counts, hash formats).
std::string check_description(const rdtf::description_t& description, const Limits& limits);
// Checks one manifest part's fields and files (paths, hashes, sizes).
std::string check_manifest_part(const rdtf::manifest_t& part, const Limits& limits);
// Whether `text` is 64 lower-case hex digits.
bool is_sha256_hex(const std::string& text);

class RevisionParts {
 public:
  RevisionParts(std::string model_id, std::int64_t revision, std::string content_hash)
      : model_id_(std::move(model_id)), revision_(revision), content_hash_(std::move(content_hash)) {}

  std::string add_description(const rdtf::description_t& description, const Limits& limits);
  std::string add_json_chunk(const rdtf::description_chunk_t& chunk, const Limits& limits);
  std::string add_urdf_chunk(const rdtf::description_chunk_t& chunk, const Limits& limits);
  std::string add_inertia(const rdtf::inertia_table_t& table, const Limits& limits);
  std::string add_manifest(const rdtf::manifest_t& part, const Limits& limits);
  std::string add_validation(const rdtf::validation_report_t& report);

  bool has_description() const { return description_.has_value(); }
  // Only a failed VALIDATION came: a revision the gate refused, of which rdtfd publishes nothing
  // more (unless publish_failed); asked again, it only republishes the refusal.
  bool refused_only() const {
    return validation_ && !validation_->passed && !description_ && json_.bytes == 0 && urdf_.bytes == 0 &&
           !inertia_ && manifest_parts_.empty();
  }
  // The snapshot (blobs not filled in) once every part needed is here and checks out. A part
  // that fails its check (a hash, a size) is cleared so that the next publication refills it;
  // `why` then says what failed.
  std::optional<Snapshot> assemble(bool need_manifest, std::string& why);

  // What assemble() still waits for, for a message ("INERTIA (2 of 5 links), VALIDATION"); ""
  // when every part is here.
  std::string missing(bool need_manifest) const;

  std::int64_t revision() const { return revision_; }
  const std::string& content_hash() const { return content_hash_; }
  // Bytes held, for the bound on incomplete revisions.
  std::int64_t bytes() const { return json_.bytes + urdf_.bytes; }

 private:
  std::optional<std::string> document(const ChunkedDocument& chunks, std::int32_t announced, std::int64_t size,
                                      const std::string& sha256, const char* what, std::string& why);

  std::string model_id_;
  std::int64_t revision_;
  std::string content_hash_;
  std::optional<rdtf::description_t> description_;
  ChunkedDocument json_;
  ChunkedDocument urdf_;
  std::optional<rdtf::inertia_table_t> inertia_;  // links of the parts so far, in order
  std::map<std::int32_t, std::vector<rdtf::file_t>> manifest_parts_;
  std::int32_t manifest_num_parts_ = -1;
  std::int32_t manifest_total_files_ = -1;
  std::optional<rdtf::validation_report_t> validation_;
};

}  // namespace rdtf::client::detail
