// Loading a glTF 2.0 asset (.gltf or .glb) from disk or memory, confined to one folder.
//
// The asset keeps the document as ordered JSON (so that the RDTF we write is the input plus our
// additions, keys in their original order) and the bytes of every buffer, which tinygltf loads
// through filesystem callbacks that refuse anything outside the model's folder.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rdtf/diagnostics.h"

namespace rdtf {

using Json = nlohmann::ordered_json;

// Caps on untrusted input, each checked before the memory it guards is allocated.
struct LoadLimits {
  std::uint64_t max_file_bytes = 512ull << 20;    // The .gltf/.glb and each external file.
  std::uint64_t max_buffer_bytes = 1ull << 30;    // Sum of every buffer's byteLength.
  std::uint64_t max_accessor_count = 1ull << 26;  // Elements in one accessor.
  std::uint64_t max_triangles = 1ull << 26;       // Triangles in the whole scene.
};

struct GltfAsset {
  std::filesystem::path path;    // As given by the caller; used in diagnostics.
  std::filesystem::path folder;  // Canonical folder that confines every external URI.
  bool binary = false;           // Loaded from a GLB container.
  Json document;
  std::vector<std::vector<std::uint8_t>> buffers;  // One per document["buffers"] entry.
  LoadLimits limits;  // The caps it was loaded with.
  // The bytes of each external image (by its path in `folder`), read with the buffers at load time:
  // a writer copies these, never the file again.
  std::map<std::filesystem::path, std::vector<std::uint8_t>> images;
  // For each buffer view decoded through an EXT_meshopt_compression QUATERNION or EXPONENTIAL
  // filter, the quantization step of each of its elements (decode_meshopt), `stride` bytes apart:
  // a key a filter rounded differs from the value it stands for by up to half of it, which a
  // comparison must allow. Per element, since one view holds every channel's keys.
  struct FilterSteps {
    std::size_t stride = 0;
    std::vector<double> steps;
  };
  std::map<std::size_t, FilterSteps> filter_steps;
};

// One file a model names, as read once for a load (read_source_files).
struct SourceFile {
  std::optional<std::uint64_t> size;  // Nothing: refused or unreadable (`why` says why).
  std::vector<std::uint8_t> bytes;    // The file, when its size is within max_file_bytes.
  std::string why;
  // Not read for want of the system's (descriptors, memory: rdtf/shortage.h), not for anything of
  // the file's: a later read may succeed, so rdtfd tries the same content again instead of
  // rejecting it until the next save.
  bool unavailable = false;
};

// Every file a model names (referenced_files), each read once, by its path in the model's folder:
// what is hashed is what is converted, whatever happens to the files afterwards.
using SourceFiles = std::map<std::filesystem::path, SourceFile>;

// Reads one confined file (the checks of the loader: no symlink out of the folder, one hard link,
// a regular file) into `file`: its size, and its bytes when the size is within `max_bytes`; or
// nothing, with `why` (and `unavailable` when the system, not the file, was the reason).
using ConfinedReader = std::function<void(const std::filesystem::path& folder, const std::filesystem::path& path,
                                          std::uint64_t max_bytes, SourceFile& file)>;

// The loader's own ConfinedReader.
void read_confined(const std::filesystem::path& folder, const std::filesystem::path& path, std::uint64_t max_bytes,
                   SourceFile& file);

// Reads each of `files` once (a file named twice is read once) under limits.max_file_bytes, through
// `reader` when given (tests count reads with it), else the loader's own.
SourceFiles read_source_files(const std::vector<std::filesystem::path>& files,
                              const std::filesystem::path& folder, const LoadLimits& limits,
                              const ConfinedReader& reader = {});

// Reads and validates a model file. Returns nothing (and errors in `diagnostics`) when the file
// cannot be used: every error names the file and the place in it.
std::optional<GltfAsset> load_gltf(const std::filesystem::path& path, const LoadLimits& limits,
                                   Diagnostics& diagnostics);

// The same from bytes already in memory; `folder` confines external URIs (empty: none allowed).
// The files the model names are read once here (read_source_files).
std::optional<GltfAsset> load_gltf_from_memory(const std::vector<std::uint8_t>& bytes,
                                               const std::filesystem::path& display_path,
                                               const std::filesystem::path& folder,
                                               const LoadLimits& limits,
                                               Diagnostics& diagnostics);

// The same with the files the model names already read (read_source_files over referenced_files
// of `bytes`): nothing is read from disk, and the buffers are these bytes (moved, not copied).
std::optional<GltfAsset> load_gltf_from_memory(const std::vector<std::uint8_t>& bytes,
                                               const std::filesystem::path& display_path,
                                               const std::filesystem::path& folder,
                                               const LoadLimits& limits, SourceFiles files,
                                               Diagnostics& diagnostics);

bool looks_like_glb(const std::vector<std::uint8_t>& bytes);

// The files a model refers to (external buffers and images) inside `folder`, read from its JSON
// without validating anything else: a watcher uses it to re-convert a model when one of them
// changes, even after a failed load (a .bin that is still missing). Unusable URIs are left out.
std::vector<std::filesystem::path> referenced_files(const std::vector<std::uint8_t>& model_bytes,
                                                    const std::filesystem::path& folder);

}  // namespace rdtf
