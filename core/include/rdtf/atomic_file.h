// Writing a file so that readers see either the old content or the whole new one, never a part:
// write a temporary file in the same folder, fsync it (unless Durability::kAtomic), rename it over
// the target, fsync the folder (likewise).
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
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rdtf {

// How far a write goes before it returns. Either way readers, and a writer that crashes or is
// killed, find the old file or the whole new one, never a part (the temporary, then a rename).
// - kDurable: the file and then its folder are fsynced, so the new file also survives a power loss
//   or a kernel crash. rdtfd writes so: it publishes a revision only once its files are durable.
// - kAtomic: no fsync. A power loss soon after may take back the new file (the old one, or none,
//   or on some file systems an empty one, can be found after it), as with the outputs of most
//   tools (cp, compilers, Blender); `rdtf convert` writes so unless given --sync.
enum class Durability { kDurable, kAtomic };

// False, with `why`, when any step fails; the temporary file is then removed.
bool write_file_atomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes,
                           std::string& why, Durability durability = Durability::kDurable);
bool write_file_atomically(const std::filesystem::path& path, std::string_view text,
                           std::string& why, Durability durability = Durability::kDurable);
// The file's bytes are the pieces one after another: a large output is written from where its
// parts already lie, without assembling a copy of it first.
bool write_file_atomically(const std::filesystem::path& path,
                           std::span<const std::span<const std::uint8_t>> pieces, std::string& why,
                           Durability durability = Durability::kDurable);

// A file written into a StagedOutput's folder, to be moved into place by its commit: created or
// truncated and written whole, without a temporary and without an fsync. The stage is a temporary
// itself (no reader looks into it, and a start after a crash removes it), so a temporary inside it
// buys nothing, and commit makes durable what it moves (docs/daemon.md, "Outputs").
bool write_staged_file(const std::filesystem::path& path, std::span<const std::span<const std::uint8_t>> pieces,
                       std::string& why);
bool write_staged_file(const std::filesystem::path& path, std::string_view text, std::string& why);

// Whether `path` is a regular file (not a symlink) whose bytes are exactly the pieces one after
// another, compared in full (a size that matches says nothing about the bytes).
bool file_holds(const std::filesystem::path& path, std::span<const std::span<const std::uint8_t>> pieces);

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

// An output of several files written into a hidden folder first (".<name>.<pid>-<random>.tmp",
// beside the output, so on the same file system), then moved into place by rename: until every
// file of the new output is whole nothing of the previous output is touched, so a disk that fills
// up between two files costs nothing but the new output. The folder goes with the object.
class StagedOutput {
 public:
  // A fresh folder in `folder` (which must exist); nothing and `why` when it cannot be made.
  static std::optional<StagedOutput> create(const std::filesystem::path& folder, std::string_view name,
                                            std::string& why);
  StagedOutput(StagedOutput&& other) noexcept : folder_(std::move(other.folder_)), synced_(std::move(other.synced_)) {
    other.folder_.clear();
  }
  StagedOutput& operator=(StagedOutput&&) = delete;
  StagedOutput(const StagedOutput&) = delete;
  ~StagedOutput();

  const std::filesystem::path& folder() const { return folder_; }

  // Moves every file below the stage to the same place below `target` (folders made as needed),
  // each by one rename: first every file not in `last`, then the files of `last` (paths relative
  // to the stage) in that order, so that the primary files, renamed last, commit the rest. Every
  // file is fsynced before the first rename (write_staged_file does not sync), and the folders
  // written to after the last (with kAtomic, neither). False with `why` when a sync or a rename
  // fails (the files already moved stay: they are whole).
  // `keep_identical`: a file whose destination already holds the same bytes is not moved (the
  // destination, perhaps the model's own .bin, stays the very same file).
  bool commit(const std::filesystem::path& target, const std::vector<std::filesystem::path>& last,
              std::string& why, bool keep_identical = false, Durability durability = Durability::kDurable);
  // Makes every file staged so far durable now (fsync), so that commit() has only its renames and
  // their folders to sync: for a stage written well before it is committed (rdtfd converts while a
  // save settles and commits at the settle period's end). Files staged after this are not synced
  // by it (commit() syncs those). False with `why` when a sync fails.
  bool sync(std::string& why);

  // A stage the destructor could not remove (out of descriptors: removing a tree lists it) is kept
  // in a list for the process, not forgotten: this tries each again and returns the paths still
  // there. rdtfd calls it now and then and before it marks a stop clean (the next start looks for
  // leftovers when any remain); `rdtf` before it exits.
  static std::vector<std::filesystem::path> remove_left_behind();

 private:
  explicit StagedOutput(std::filesystem::path folder) : folder_(std::move(folder)) {}
  std::filesystem::path folder_;
  std::set<std::filesystem::path> synced_;  // made durable by sync(), relative: commit() skips them
};

// Whether a name has the form of write_file_atomically's and StagedOutput's temporaries
// (".<name>.<pid>-<random>.tmp"), and the pid in it.
std::optional<long> temporary_writer_pid(std::string_view file_name);

}  // namespace rdtf
