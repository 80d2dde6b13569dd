// The files a revision's output folder holds (the manifest, <prefix>/<model_id>/MANIFEST), each
// named by the SHA-256 of its bytes: what a subscriber fetches as blobs (docs/lcm.md, "Files and
// blobs"). The hashes come from the bytes as the conversion writes them, never from reading the
// files back.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include <rdtf/manifest_t.hpp>

#include "rdtf/atomic_file.h"

namespace rdtf::daemon {

// One file of an output folder.
struct OutputFile {
  std::string path;    // Relative to <output>/<model_id>/, '/'-separated.
  std::string sha256;  // Lowercase hex of the whole file.
  std::int64_t size = 0;
  std::string role;    // "rdtf", "buffer", "image", "urdf", "urdf_mesh".
  bool operator==(const OutputFile&) const = default;
};

// Records the full SHA-256 and size of every byte string the writer names a file after: the
// writer (write_rdtf, write_urdf) calls the content digest on exactly the bytes it writes, so the
// recorder sees each content-addressed file's bytes once, as they are written.
class DigestLog {
 public:
  // The digest to hand the writer (WriteOptions::content_digest, UrdfOptions::mesh_digest).
  ContentDigest digest();
  struct Entry {
    std::string sha256;
    std::int64_t size;
  };
  // The entries whose hash starts with `prefix` (the 16 digits in a content-addressed name).
  std::vector<Entry> matching(const std::string& prefix) const;

 private:
  // Shared with the digest functions handed out (they may outlive a copy of the log's owner).
  struct State {
    std::mutex mutex;
    std::multimap<std::string, Entry> by_prefix;
  };
  std::shared_ptr<State> state_ = std::make_shared<State>();
};

// The manifest of one written revision: `gltf_name` (the .rdtf.gltf, its text `rdtf_json`), the
// buffers and images its JSON names, and when `urdf` is not empty urdf/robot.urdf and the meshes
// it names. A content-addressed file missing from `log` (not written by this conversion) makes
// `why` non-empty and the result empty: a manifest with a wrong hash would be worse than none. An
// image under a name that is not content-addressed is one the conversion could not copy
// (IMAGE_NOT_COPIED): it is not in the output, and not listed.
std::vector<OutputFile> output_files(const std::string& gltf_name, const std::string& rdtf_json,
                                     const std::string& urdf, const DigestLog& log, std::string& why);

// The manifest as messages that each encode to at most max_message_bytes: one, or several parts
// with consecutive files (together every file once, in order).
std::vector<rdtf::manifest_t> make_manifests(const std::string& model_id, std::int64_t revision,
                                             const std::string& content_hash,
                                             const std::vector<OutputFile>& files, std::size_t max_message_bytes);

}  // namespace rdtf::daemon
