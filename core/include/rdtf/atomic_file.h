// Writing a file so that readers see either the old content or the whole new one, never a part:
// write a temporary file in the same folder, fsync it, rename it over the target, fsync the folder.
//
// An output made of several files (a .rdtf.gltf and its .bin, a robot.urdf and its meshes) needs
// more: a reader must never find a new .bin beside an old JSON. With content-addressed names each
// file the primary file refers to is named after its bytes, so a new revision never overwrites a
// file that an older primary file refers to; the files are written first and the rename of the
// primary file commits the whole set at once (docs/daemon.md, "Outputs").
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rdtf {

// False, with `why`, when any step fails; the temporary file is then removed.
bool write_file_atomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes,
                           std::string& why);
bool write_file_atomically(const std::filesystem::path& path, std::string_view text,
                           std::string& why);

// A digest of bytes in lowercase hex, at least 16 digits (the daemon passes SHA-256). librdtf
// links no cryptography library, so whoever wants content-addressed names brings the digest.
using ContentDigest = std::function<std::string(std::span<const std::uint8_t>)>;

// "<stem>.<first 16 hex digits of digest(bytes)><extension>" (extension with its dot, or empty).
// A stem that already ends in ".<16 hex digits>" (an output converted again) loses that part, so
// names do not grow. Throws std::invalid_argument when the digest is not 16 hex digits or more.
std::string content_addressed_name(std::string_view stem, std::string_view extension,
                                   std::span<const std::uint8_t> bytes, const ContentDigest& digest);

// Whether a file name has the form content_addressed_name gives: "<stem>.<16 hex>[.<ext>]".
bool is_content_addressed_name(std::string_view file_name);

// Removes each regular file (not a symlink) directly in `folder` whose name is content-addressed
// and not in `keep`.
// Returns how many were removed. A file that cannot be removed is left: an unreferenced leftover
// harms no reader, and the next write or start tries again.
int remove_unreferenced(const std::filesystem::path& folder, const std::set<std::string>& keep);

// Removes the files a failed write created (no committed document refers to them); what cannot
// be removed is left, as above.
void remove_created(const std::vector<std::filesystem::path>& created);

}  // namespace rdtf
