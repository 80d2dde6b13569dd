// Reading files that a model refers to, without ever leaving the model's folder.
//
// tinygltf 2.7 resolves "../", absolute paths and the current directory on its own, and reads
// whatever it finds with no size cap (facts.md). We resolve every URI here instead and hand tinygltf
// only files that passed these checks.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rdtf/percent_decode.h"

namespace rdtf::internal {

using rdtf::percent_decode;  // rdtf/percent_decode.h, the one decoder of URI paths

bool is_data_uri(std::string_view uri);

// Maps a relative URI reference to a path inside `folder` (canonical). Refuses URIs with a
// scheme (file:, http:, ...), absolute paths, a query or fragment, NUL bytes, and "../" that
// climbs out of the folder; `why` says which. The file need not exist yet.
std::optional<std::filesystem::path> resolve_uri(const std::filesystem::path& folder,
                                                 std::string_view uri, std::string& why);

// Reads a regular file whose real location (after following symlinks) lies inside `folder`.
// Refuses directories, devices, FIFOs and sockets (without blocking on a FIFO), files with more
// than one hard link, and files over `max_bytes`, checked before reading. `why` says what went
// wrong; it never names where a symlink points.
bool read_confined_file(const std::filesystem::path& folder, const std::filesystem::path& path,
                        std::uint64_t max_bytes, std::vector<std::uint8_t>& out, std::string& why);

// The same checks without reading: the size of the file, or nothing and `why`.
std::optional<std::uint64_t> confined_file_size(const std::filesystem::path& folder,
                                                const std::filesystem::path& path,
                                                std::string& why);

// One open of a confined file, with the checks of read_confined_file: its size (nothing and `why`
// when refused), and its bytes in `out` when that size is at most `max_bytes` (a larger file is
// sized, not read). A read that fails after the checks gives nothing and `why` too, and the
// failing call's errno in `*error` when given (0 when a check refused the file).
std::optional<std::uint64_t> read_confined_file_within(const std::filesystem::path& folder,
                                                       const std::filesystem::path& path,
                                                       std::uint64_t max_bytes,
                                                       std::vector<std::uint8_t>& out, std::string& why,
                                                       int* error = nullptr);

// Reads any regular file (the model itself), refusing non-regular files and files over max_bytes.
bool read_regular_file(const std::filesystem::path& path, std::uint64_t max_bytes,
                       std::vector<std::uint8_t>& out, std::string& why);

// Reading a model file below a watched folder: every folder from `root` down and the file itself
// are opened without following symlinks (a symlink is refused even when it points inside), and
// the file must be a regular file with one link and at most `max_bytes`.
enum class ReadBeneath {
  kRead,     // `out` holds the file.
  kGone,     // Not there (any more): missing, a directory, or a folder on the way is no folder.
  kRefused,  // There, but not readable as a model (or behind a folder that cannot be searched): `why`
             // says why (never the file's content).
  kUnavailable,  // Not read for want of the system's (descriptors, memory): there or not, a later
                 // attempt may read it. `why` says which.
};
ReadBeneath read_beneath(const std::filesystem::path& root, const std::filesystem::path& path,
                         std::uint64_t max_bytes, std::vector<std::uint8_t>& out, std::string& why);

}  // namespace rdtf::internal
