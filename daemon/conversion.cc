#include "conversion.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openssl/evp.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <memory>
#include <set>

#include "../core/gltf/confined_files.h"
#include "rdtf/atomic_file.h"
#include "rdtf/urdf_names.h"
#include "rdtf/write.h"
#include "rdtf/diagnostic_codes.h"
#include "result_cache.h"
#include "verdict_memo.h"

namespace rdtf::daemon {

void log_line(const std::string& text);  // daemon.cc: one line to stderr, whole.

namespace {

// The content-addressed files a primary output's text refers to (file names in its folder).
std::set<std::string> names_in_gltf(const std::string& json, const std::filesystem::path& folder) {
  std::set<std::string> names;
  if (json.empty()) return names;
  for (const auto& file : referenced_files(std::vector<std::uint8_t>(json.begin(), json.end()), folder)) {
    names.insert(file.filename().string());
  }
  return names;
}

std::set<std::string> names_in_urdf(const std::string& text) {
  std::set<std::string> names;
  for (const auto& filename : urdf_mesh_filenames(text)) names.insert(std::filesystem::path(filename).filename().string());
  return names;
}

std::string file_text(const std::filesystem::path& path) {
  std::vector<std::uint8_t> bytes;
  std::string why;
  if (!internal::read_regular_file(path, std::uint64_t{1} << 30, bytes, why)) return {};
  return std::string(bytes.begin(), bytes.end());
}

// The file names a revision's outputs keep: those directly in the model's output folder
// (`in_folder`) and in urdf/meshes (`meshes`).
struct KeptNames {
  std::set<std::string> in_folder;
  std::set<std::string> meshes;

  // Every file of a manifest: no text to parse again.
  void add(const std::vector<OutputFile>& files) {
    for (const OutputFile& file : files) {
      const auto slash = file.path.rfind('/');
      if (slash == std::string::npos) {
        in_folder.insert(file.path);
      } else if (file.path.compare(0, slash + 1, "urdf/meshes/") == 0) {
        meshes.insert(file.path.substr(slash + 1));
      }
    }
  }
  void add(const std::string& rdtf_json, const std::string& urdf, const std::filesystem::path& output_dir) {
    in_folder.merge(names_in_gltf(rdtf_json, output_dir));
    meshes.merge(names_in_urdf(urdf));
  }
  // The primary files on disk now (after a restart, or an earlier attempt committed halfway, they
  // may be newer than the live revision): what they refer to, unless they are the live revision's
  // own, byte for byte (its files are kept already).
  void add_on_disk(const std::filesystem::path& output_dir, const std::string& gltf_name,
                   const std::vector<OutputFile>& live_files, bool urdf_kept = true) {
    auto is_live = [&](const std::string& path, const std::string& text) {
      for (const OutputFile& file : live_files) {
        if (file.path == path) return file.size == static_cast<std::int64_t>(text.size()) && file.sha256 == sha256_hex(text);
      }
      return false;
    };
    const std::string json = file_text(output_dir / gltf_name);
    if (!is_live(gltf_name, json)) in_folder.merge(names_in_gltf(json, output_dir));
    if (!urdf_kept) return;
    const std::string urdf = file_text(output_dir / "urdf" / "robot.urdf");
    if (!is_live("urdf/robot.urdf", urdf)) meshes.merge(names_in_urdf(urdf));
  }
};

// Holds a share of the read budget for the life of a conversion.
class HeldBytes {
 public:
  HeldBytes(ReadBudget* budget, std::uint64_t bytes) : budget_(budget), bytes_(bytes) {
    if (budget_ != nullptr) budget_->acquire(bytes_);
  }
  ~HeldBytes() {
    if (budget_ != nullptr) budget_->release(bytes_);
  }
  HeldBytes(const HeldBytes&) = delete;
  HeldBytes& operator=(const HeldBytes&) = delete;

 private:
  ReadBudget* budget_;
  std::uint64_t bytes_;
};

bool has_code(const Diagnostics& diag, const char* code) {
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError && d.code == code) return true;
  }
  return false;
}

}  // namespace

std::string to_hex(std::span<const unsigned char> bytes) {
  static const char* const kHex = "0123456789abcdef";
  std::string out;
  out.reserve(2 * bytes.size());
  for (const unsigned char b : bytes) {
    out += kHex[b >> 4];
    out += kHex[b & 15];
  }
  return out;
}

std::string output_digest(std::span<const std::uint8_t> bytes) {
  return sha256_hex(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

std::string sha256_hex(const std::vector<const std::vector<std::uint8_t>*>& parts) {
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> context(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  EVP_DigestInit_ex(context.get(), EVP_sha256(), nullptr);
  for (const auto* part : parts) {
    // Length first, so that moving bytes between parts changes the hash. A part not read (nullptr)
    // has a length no file has: a missing or refused file never hashes as an empty one.
    const std::uint64_t size = part ? part->size() : ~std::uint64_t{0};
    EVP_DigestUpdate(context.get(), &size, sizeof(size));
    if (part) EVP_DigestUpdate(context.get(), part->data(), part->size());
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(context.get(), digest, &length);
  return to_hex({digest, length});
}

std::string content_hash(const std::vector<std::uint8_t>& model, const std::vector<std::filesystem::path>& named,
                         const SourceFiles& files) {
  std::vector<const std::vector<std::uint8_t>*> parts{&model};
  for (const auto& path : named) {
    const auto found = files.find(path);
    parts.push_back(found != files.end() && found->second.size ? &found->second.bytes : nullptr);
  }
  return sha256_hex(parts);
}

std::string sha256_hex(std::string_view text) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(text.data(), text.size(), digest, &length, EVP_sha256(), nullptr);
  return to_hex({digest, length});
}

// The key an entry is stored and found under: the settings, and the model's output folder, which
// its diagnostics and outputs name (the same file watched through another folder is another model
// id, with another output folder: it got the entry of the first, naming the first's outputs;
// helper sweep s70cache D4).
std::string cache_entry_key(const ConversionJob& job) { return job.cache_key + " " + job.output_dir.string(); }

namespace {

// WRITE_FAILED because a name is longer than the output's file system allows: no retry helps.
bool name_too_long(const Diagnostics& diag) {
  const std::string text = std::strerror(ENAMETOOLONG);
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError && d.code == codes::WRITE_FAILED && d.message.find(text) != std::string::npos) {
      return true;
    }
  }
  return false;
}

// `from` appended to `to`, naming the files where they will be (`final_folder`) rather than in the
// stage folder they were written to, whose random name is gone after the commit or the failure.
void append_unstaged(Diagnostics& to, const Diagnostics& from, const std::filesystem::path& stage_folder,
                     const std::filesystem::path& final_folder) {
  const std::string staged = stage_folder.string();
  const std::string final = final_folder.string();
  const auto unstaged = [&](std::string text) {
    for (std::size_t at = text.find(staged); at != std::string::npos; at = text.find(staged, at + final.size())) {
      text.replace(at, staged.size(), final);
    }
    return text;
  };
  const std::string file = to.file();
  for (const Diagnostic& d : from.all()) {
    to.set_file(unstaged(d.file));
    to.add(d.severity, d.code, d.pointer, unstaged(d.message));
  }
  to.set_file(file);
}

// A failed write: retried later when the environment may change (disk full, unwritable folder),
// refused for good when a name is too long.
void write_failed(const std::filesystem::path& output_dir, Diagnostics& diagnostics, bool& retry) {
  if (name_too_long(diagnostics)) {
    const long name_max = ::pathconf(output_dir.c_str(), _PC_NAME_MAX);
    diagnostics.error(codes::NAME_TOO_LONG, "",
                      "an output name made from this model (its file name, or a node's name in the "
                      "URDF's meshes) is longer than " + (name_max > 0 ? std::to_string(name_max) : std::string("allowed")) +
                      " bytes, the longest name the output file system takes; not retried: rename it");
    retry = false;
    return;
  }
  retry = true;
}

}  // namespace

// A revision's outputs in their stage folder: what the commit moves into place and what it keeps.
struct StagedOutputs {
  StagedOutput stage;
  std::filesystem::path output_dir;
  std::vector<std::filesystem::path> primaries;  // Relative to the stage: renamed last.
  KeptNames keep;
  bool urdf = false;
  // No URDF written, and none live: urdf/robot.urdf on disk is an earlier revision's, which no
  // revision served now refers to (a ROS user loading it would get another robot).
  bool urdf_stale = false;
};

namespace {

// Creates root / relative folder by folder (or only checks what exists, `create` false), refusing a
// component that is a symlink or no folder: a link planted in the output folder (<output>/<model>
// -> elsewhere) would have rdtfd write, and clean up, outside it. The root itself is the
// configuration's to choose.
bool make_output_folder(const std::filesystem::path& root, const std::filesystem::path& relative, bool create,
                        std::string& why) {
  std::filesystem::path at = root;
  for (const std::filesystem::path& part : relative) {
    if (part.empty() || part == ".") continue;
    at /= part;
    struct stat info {};
    if (::lstat(at.c_str(), &info) != 0) {
      if (errno == ENOENT && !create) return true;
      if (errno != ENOENT || (::mkdir(at.c_str(), 0755) != 0 && errno != EEXIST) || ::lstat(at.c_str(), &info) != 0) {
        why = "cannot create " + at.string() + ": " + std::strerror(errno);
        return false;
      }
    }
    if (S_ISLNK(info.st_mode)) {
      why = at.string() + " is a symbolic link: rdtfd writes and removes files only inside its output folder " +
            root.string() + "; remove the link";
      return false;
    }
    if (!S_ISDIR(info.st_mode)) {
      why = at.string() + " is not a folder: remove it, rdtfd keeps this model's outputs there";
      return false;
    }
  }
  return true;
}

// Every file of the new revision is written into a stage folder first and moved into place only
// when all of them are whole (the primary files last, commit_outputs), and the previous
// generation's files go only after that: a disk that fills up between two files leaves the live
// revision untouched. Null when the stage could not be written (diagnostics say why).
std::unique_ptr<StagedOutputs> stage_outputs(const ConversionJob& job, const Conversion& conversion,
                                             ConvertedModel& converted, Diagnostics& diagnostics, bool& retry) {
  std::string why;
  if (!job.output_root.empty()) {
    const std::filesystem::path relative = job.output_dir.lexically_relative(job.output_root);
    if (relative.empty() || *relative.begin() == ".." || !make_output_folder(job.output_root, relative, true, why) ||
        (job.urdf && !make_output_folder(job.output_dir, std::filesystem::path("urdf") / "meshes", false, why))) {
      if (why.empty()) why = job.output_dir.string() + " is not inside the output folder " + job.output_root.string();
      diagnostics.error(codes::WRITE_FAILED, "", why);
      write_failed(job.output_dir, diagnostics, retry);
      return nullptr;
    }
  } else {
    std::error_code ec;
    std::filesystem::create_directories(job.output_dir, ec);
    if (ec) {
      diagnostics.error(codes::WRITE_FAILED, "", "cannot create " + job.output_dir.string() + ": " + ec.message());
      write_failed(job.output_dir, diagnostics, retry);
      return nullptr;
    }
  }
  auto stage = StagedOutput::create(job.output_dir, "stage", why);
  if (!stage) {
    diagnostics.error(codes::WRITE_FAILED, "", "cannot write: " + why);
    write_failed(job.output_dir, diagnostics, retry);
    return nullptr;
  }
  const std::filesystem::path name = job.source.stem().string() + ".rdtf.gltf";
  converted.output_path = (job.output_dir / name).native();
  Diagnostics write_diag(converted.output_path);
  // Every content-addressed file's hash, taken from the bytes as they are written (the manifest).
  DigestLog written;
  WriteOptions write_options;
  write_options.content_digest = written.digest();
  write_options.staged_for = job.output_dir;
  if (!write_rdtf(conversion.asset, stage->folder() / name, write_options, write_diag, &converted.rdtf_json)) {
    append_unstaged(diagnostics, write_diag, stage->folder(), job.output_dir);
    if (has_code(write_diag, codes::WRITE_FAILED)) write_failed(job.output_dir, diagnostics, retry);
    return nullptr;
  }
  append_unstaged(diagnostics, write_diag, stage->folder(), job.output_dir);
  std::vector<std::filesystem::path> primaries{name};
  if (job.urdf) {
    // URDF is a second output: a model URDF cannot express (a ball joint) still converts.
    Diagnostics urdf_diag(converted.output_path);
    UrdfOptions urdf_options = *job.urdf;
    urdf_options.mesh_digest = written.digest();
    urdf_options.staged_for = job.output_dir / "urdf";
    if (write_urdf(conversion, stage->folder() / "urdf", urdf_options, urdf_diag, &converted.urdf)) {
      converted.urdf_path = (job.output_dir / "urdf" / "robot.urdf").native();
      primaries.emplace_back("urdf/robot.urdf");
      append_unstaged(diagnostics, urdf_diag, stage->folder(), job.output_dir);  // Its warnings (URDF_NAME_CHANGED, ...).
    } else if (has_code(urdf_diag, codes::WRITE_FAILED)) {
      // The disk, not the model: fail the revision and try again; nothing was moved into place.
      append_unstaged(diagnostics, urdf_diag, stage->folder(), job.output_dir);
      write_failed(job.output_dir, diagnostics, retry);
      return nullptr;
    } else {
      for (const Diagnostic& d : urdf_diag.all()) diagnostics.warning(codes::URDF_NOT_WRITTEN, d.pointer, d.message);
    }
  }
  std::string manifest_why;
  converted.files = output_files(name.string(), converted.rdtf_json, converted.urdf, written, manifest_why);
  // Kept: the files of the new revision, of the outputs it replaces on disk, and of the live
  // revision (the disk's may be newer after a restart or a half-committed earlier attempt). Taken
  // from the manifests where there are any: parsing the texts again cost 2.2 ms of a 13 ms save.
  KeptNames keep;
  if (manifest_why.empty()) {
    keep.add(converted.files);
  } else {
    keep.add(converted.rdtf_json, converted.urdf, job.output_dir);
  }
  const bool live_urdf =
      !job.live_urdf.empty() || std::any_of(job.live_files.begin(), job.live_files.end(),
                                            [](const OutputFile& file) { return file.path == "urdf/robot.urdf"; });
  const bool urdf_stale = !job.urdf && !live_urdf;
  keep.add_on_disk(job.output_dir, name.string(), job.live_files, !urdf_stale);
  keep.add(job.live_files);
  keep.add(job.live_rdtf_json, job.live_urdf, job.output_dir);
  if (!manifest_why.empty()) {
    diagnostics.warning(codes::MANIFEST_INCOMPLETE, "", "no manifest for this revision, so its files are not served "
                        "as blobs: " + manifest_why);
  }
  // A prepared revision is committed at the settle period's end: its files are made durable now,
  // and the commit has only its renames and their folders to sync.
  if (job.prepare && !stage->sync(why)) {
    diagnostics.error(codes::WRITE_FAILED, "", "cannot write: " + why);
    write_failed(job.output_dir, diagnostics, retry);
    return nullptr;
  }
  return std::make_unique<StagedOutputs>(
      StagedOutputs{std::move(*stage), job.output_dir, std::move(primaries), std::move(keep), job.urdf.has_value(), urdf_stale});
}

// Moves a staged revision into place (made durable before it returns), then removes the files
// that neither it nor the live revision refers to.
bool commit_outputs(StagedOutputs& staged, Diagnostics& diagnostics, bool& retry) {
  std::string why;
  if (!staged.stage.commit(staged.output_dir, staged.primaries, why)) {
    diagnostics.error(codes::WRITE_FAILED, "", "cannot move the outputs into place: " + why);
    write_failed(staged.output_dir, diagnostics, retry);
    return false;
  }
  remove_unreferenced(staged.output_dir, staged.keep.in_folder);
  if (staged.urdf) remove_unreferenced(staged.output_dir / "urdf" / "meshes", staged.keep.meshes);
  if (staged.urdf_stale) {
    // The folders were made by rdtfd and checked for links when the stage was written.
    const auto folder = staged.output_dir / "urdf";
    struct stat info {};
    if (::lstat(folder.c_str(), &info) == 0 && S_ISDIR(info.st_mode)) {
      ::unlink((folder / "robot.urdf").c_str());
      if (::lstat((folder / "meshes").c_str(), &info) == 0 && S_ISDIR(info.st_mode)) {
        remove_unreferenced(folder / "meshes", {});
        ::rmdir((folder / "meshes").c_str());
      }
      ::rmdir(folder.c_str());  // only if empty: anything of the user's stays
    }
  }
  return true;
}

// The outputs a cached result names, as they are on disk now: the primary files (read and
// hashed: their text goes into the description) and every other file of the manifest (by type and
// size: content-addressed names carry their hash, and reading an 18 MB buffer back would cost
// what the cache saves). Empty when they match; else what does not.
std::string outputs_differ(const ConversionJob& job, const CachedResult& cached, std::string& rdtf_json,
                           std::string& urdf) {
  if (!cached.written) return {};
  if (cached.output_name != job.source.stem().string() + ".rdtf.gltf") return "another output name";
  // Nothing between the output root and a file may be a link, as for a conversion's writes (a
  // model's output folder replaced by a link out of the output was read through, and served; helper
  // sweep s70cache D3): such an entry is not used, and the conversion that follows says why.
  const auto inside = job.output_dir.lexically_relative(job.output_root);
  if (!job.output_root.empty() && !inside.empty() && *inside.begin() != "..") {
    for (const std::filesystem::path& folder : {job.output_dir, job.output_dir / "urdf", job.output_dir / "urdf" / "meshes"}) {
      for (auto at = folder; at != job.output_root && at.has_relative_path() && at != at.parent_path(); at = at.parent_path()) {
        struct stat info {};
        if (::lstat(at.c_str(), &info) == 0 && S_ISLNK(info.st_mode)) return at.string() + " is a symbolic link";
      }
    }
  }
  std::string why;
  auto read_text = [&](const std::filesystem::path& path, const std::string& sha256, std::string& out) {
    std::vector<std::uint8_t> bytes;
    if (!internal::read_regular_file(path, std::uint64_t{1} << 30, bytes, why)) {
      why = path.string() + ": " + why;
      return false;
    }
    out.assign(bytes.begin(), bytes.end());
    if (sha256_hex(out) != sha256) {
      why = path.string() + " was changed";
      return false;
    }
    return true;
  };
  if (!read_text(job.output_dir / cached.output_name, cached.rdtf_sha256, rdtf_json)) return why;
  if (cached.has_urdf && !read_text(job.output_dir / "urdf" / "robot.urdf", cached.urdf_sha256, urdf)) return why;
  for (const OutputFile& file : cached.files) {
    struct stat info {};
    const auto path = job.output_dir / file.path;
    if (::lstat(path.c_str(), &info) != 0) return path.string() + ": " + std::strerror(errno);
    if (!S_ISREG(info.st_mode) || info.st_size != file.size) return path.string() + " was changed";
  }
  return {};
}

// The outcome from the cache when it holds this content's result and its outputs are on disk.
bool from_cache(const ConversionJob& job, ConversionOutcome& outcome) {
  CachedResult cached;
  std::string why;
  switch (job.cache->find(job.source.string(), cache_entry_key(job), outcome.content_hash, cached, why)) {
    case ResultCache::Lookup::kMiss:
      return false;
    case ResultCache::Lookup::kRefused:
      outcome.cache_note = "result cache entry refused (" + why + "): converting again";
      return false;
    case ResultCache::Lookup::kHit:
      break;
  }
  ConvertedModel converted;
  const std::string differ = outputs_differ(job, cached, converted.rdtf_json, converted.urdf);
  if (!differ.empty()) {
    outcome.cache_note = "result cache entry not used, the outputs changed on disk (" + differ + "): converting again";
    return false;
  }
  converted.content_hash = outcome.content_hash;
  converted.written = cached.written;
  if (cached.written) converted.output_path = (job.output_dir / cached.output_name).native();
  if (cached.has_urdf) converted.urdf_path = (job.output_dir / "urdf" / "robot.urdf").native();
  converted.validation = std::move(cached.validation);
  converted.facts = std::move(cached.facts);
  converted.files = std::move(cached.files);
  converted.totals = robot_totals(cached.robot);
  converted.robot = std::move(cached.robot);
  outcome.diagnostics.append(cached.diagnostics);
  outcome.converted = std::move(converted);
  outcome.kind = ConversionOutcome::Kind::kConverted;
  outcome.from_cache = true;
  return true;
}

// Storing this outcome in the cache, as work for after the hand-over: the entry is a copy taken
// now, the SHA-256 of the texts and the write happen then. Two saves of one model are at least
// a settle period apart, so a later revision's entry is not overwritten by this one in practice;
// if it were, the entry would name the older content and only miss (it is keyed by content hash).
std::function<void()> cache_after_handover(const ConversionJob& job, const ConversionOutcome& outcome) {
  const ConvertedModel& m = *outcome.converted;
  CachedResult entry;
  entry.key = cache_entry_key(job);
  entry.source = job.source.string();
  entry.content_hash = outcome.content_hash;
  entry.written = m.written;
  if (m.written) entry.output_name = std::filesystem::path(m.output_path).filename().string();
  const bool has_urdf = !m.urdf_path.empty();
  entry.has_urdf = has_urdf;
  entry.files = m.files;
  entry.validation = m.validation;
  entry.diagnostics = outcome.diagnostics;
  entry.robot = m.robot;
  entry.facts = m.facts;
  return [cache = job.cache, entry = std::move(entry), rdtf_json = m.written ? m.rdtf_json : std::string(),
          urdf = has_urdf ? m.urdf : std::string(), model_id = outcome.model_id]() mutable {
    if (entry.written) entry.rdtf_sha256 = sha256_hex(rdtf_json);
    if (entry.has_urdf) entry.urdf_sha256 = sha256_hex(urdf);
    std::string why;
    if (!cache->store(entry, why)) log_line(model_id + ": result not cached: " + why);
  };
}

}  // namespace

void ReadBudget::set_capacity(std::uint64_t capacity) {
  {
    std::lock_guard lock(mutex_);
    capacity_ = capacity;
  }
  freed_.notify_all();
}

void ReadBudget::acquire(std::uint64_t bytes) {
  std::unique_lock lock(mutex_);
  freed_.wait(lock, [&] { return held_ == 0 || held_ + bytes <= capacity_; });
  held_ += bytes;
}

void ReadBudget::release(std::uint64_t bytes) {
  {
    std::lock_guard lock(mutex_);
    held_ -= std::min(held_, bytes);
  }
  freed_.notify_all();
}

std::uint64_t ReadBudget::held() const {
  std::lock_guard lock(mutex_);
  return held_;
}

namespace {

// Not cached: a written result whose manifest is incomplete (a hit could not check its files),
// and a verdict the machine's load decided (the check ran out of its CPU budget).
bool cacheable(const ConversionJob& job, const ConversionOutcome& outcome) {
  const bool manifest_whole = !outcome.converted->written || !outcome.converted->files.empty();
  const bool load_decided = outcome.converted->validation &&
                            outcome.converted->validation->diagnostics.contains(codes::SIM_BUDGET_EXCEEDED);
  return job.cache && manifest_whole && !load_decided;
}

// The second half of a prepared conversion, at the deadline: its staged outputs moved into place.
ConversionOutcome commit_prepared(const ConversionJob& job) {
  const auto start = std::chrono::steady_clock::now();
  ConversionOutcome outcome = std::move(*job.commit);
  outcome.prepared = false;
  outcome.while_settling = true;
  const std::shared_ptr<StagedOutputs> staged = std::move(outcome.staged);
  outcome.staged.reset();
  if (staged && outcome.converted) {
    if (commit_outputs(*staged, outcome.diagnostics, outcome.retry)) {
      outcome.converted->written = true;
    } else {
      outcome.kind = ConversionOutcome::Kind::kRejected;
      outcome.converted.reset();
    }
  }
  outcome.finished = std::chrono::steady_clock::now();
  const auto took = std::chrono::duration_cast<std::chrono::microseconds>(outcome.finished - start);
  outcome.stages.write += took;
  outcome.duration += took;
  if (outcome.kind == ConversionOutcome::Kind::kConverted && !outcome.from_cache && cacheable(job, outcome)) {
    outcome.after_handover = cache_after_handover(job, outcome);
  }
  return outcome;
}

}  // namespace

ConversionOutcome run_conversion(const ConversionJob& job) {
  if (job.commit) return commit_prepared(job);
  const auto start = std::chrono::steady_clock::now();
  ConversionOutcome outcome;
  outcome.model_id = job.model_id;
  outcome.source = job.source;
  outcome.cache_key = job.cache_key;
  outcome.prepared = job.prepare;
  outcome.diagnostics.set_file(job.source.string());
  // Each stage's time: from the end of the one before to now.
  auto lap_start = start;
  auto lap = [&](std::chrono::microseconds& stage) {
    const auto now = std::chrono::steady_clock::now();
    stage += std::chrono::duration_cast<std::chrono::microseconds>(now - lap_start);
    lap_start = now;
  };
  auto finish = [&]() -> ConversionOutcome {
    outcome.finished = std::chrono::steady_clock::now();
    outcome.duration = std::chrono::duration_cast<std::chrono::microseconds>(outcome.finished - start);
    return std::move(outcome);
  };

  if (!job.not_now.empty()) {
    outcome.diagnostics.error(codes::IO_ERROR, "", job.not_now);
    outcome.retry = true;
    return finish();
  }
  std::error_code ec;
  // The model is read without following any symlink from the watched folder down: a link named
  // like a model, or a folder swapped for a link to another folder, leads nowhere.
  std::vector<std::uint8_t> model_bytes;
  std::string why;
  switch (internal::read_beneath(job.root, job.source, job.options.limits.max_file_bytes, model_bytes, why)) {
    case internal::ReadBeneath::kRead:
      break;
    case internal::ReadBeneath::kGone:
      outcome.kind = ConversionOutcome::Kind::kVanished;
      return finish();
    case internal::ReadBeneath::kRefused:
      outcome.diagnostics.error(codes::IO_ERROR, "", "cannot read the model: it " + why);
      return finish();
    case internal::ReadBeneath::kUnavailable:
      // The environment's failure, as a full disk is for a write: the same content is tried again
      // after a back-off, and the live revision is served meanwhile.
      outcome.diagnostics.error(codes::IO_ERROR, "", "cannot read the model now: it " + why);
      outcome.retry = true;
      return finish();
  }
  // Lexically, not canonically: no folder on the way is a symlink (read_beneath checked), and a
  // file the model names must really lie below this path (confined_files.h).
  const auto folder = job.source.parent_path();
  outcome.dependencies = referenced_files(model_bytes, folder);

  // Everything this conversion will read, each file as often as it is named, before any of it is
  // read: a small file naming one huge (sparse) file many times is refused up front.
  std::uint64_t to_read = model_bytes.size();
  for (const auto& file : outcome.dependencies) {
    std::string size_why;
    to_read += internal::confined_file_size(folder, file, size_why).value_or(0);
  }
  if (to_read > job.max_read_bytes) {
    outcome.diagnostics.error(codes::LIMIT_EXCEEDED, "",
                              "the model and the " + std::to_string(outcome.dependencies.size()) +
                                  " files it names (each counted as often as it is named) add up to " +
                                  std::to_string(to_read) + " bytes to read, over the limit of " +
                                  std::to_string(job.max_read_bytes) + " bytes (max_read_bytes)");
    return finish();
  }
  HeldBytes held(job.budget.get(), to_read);

  // Every file the model names is read once, here: the content hash covers these bytes (so a new
  // .bin alone counts), and the loader converts the same bytes, whatever is written meanwhile.
  SourceFiles files = read_source_files(outcome.dependencies, folder, job.options.limits, job.read_file);
  for (const auto& [path, file] : files) {
    if (!file.unavailable) continue;
    // As for the model file above: the same content is tried again after a back-off, not rejected
    // until the next save (s106fd: a .bin not opened for want of descriptors kept its model
    // unpublished after the limit was raised).
    outcome.diagnostics.error(codes::IO_ERROR, "",
                              "cannot read " + path.lexically_relative(folder).string() + " now: " + file.why);
    outcome.retry = true;
    return finish();
  }
  outcome.content_hash = content_hash(model_bytes, outcome.dependencies, files);
  // A file named through a symlink in the watched folder (current.bin -> meshes/arm3.bin, or a
  // linked folder) is saved at its target, which is what inotify reports: that path is a
  // dependency too, or an edit there would leave the model stale.
  const std::size_t named = outcome.dependencies.size();
  for (std::size_t i = 0; i < named; ++i) {
    std::error_code resolve_error;
    std::filesystem::path target = std::filesystem::canonical(outcome.dependencies[i], resolve_error);
    if (resolve_error || target == outcome.dependencies[i]) continue;
    const auto relative = target.lexically_relative(job.root);
    if (relative.empty() || *relative.begin() == "..") continue;
    if (std::find(outcome.dependencies.begin(), outcome.dependencies.end(), target) == outcome.dependencies.end()) {
      outcome.dependencies.push_back(std::move(target));
    }
  }
  lap(outcome.stages.read);
  // A state not read whole is never "unchanged" (a .bin linked out of the folder, then
  // hard-linked, hashed alike, and the second refusal went unreported).
  const bool read_whole =
      std::all_of(files.begin(), files.end(), [](const auto& file) { return file.second.size.has_value(); });
  if (read_whole && outcome.content_hash == job.previous_hash) {
    outcome.kind = ConversionOutcome::Kind::kUnchanged;
    return finish();
  }
  // Nor is a result cached for it served: what a conversion says of the file it could not read
  // (an error for a refused image, a warning for a missing one) is not in the entry (an empty
  // texture converted, then deleted while rdtfd was stopped, came back from the cache unreported).
  const bool cached = read_whole && job.cache && from_cache(job, outcome);
  lap(outcome.stages.cache);
  if (cached) return finish();

  auto asset = load_gltf_from_memory(model_bytes, job.source, folder, job.options.limits, std::move(files),
                                     outcome.diagnostics);
  if (!asset) return finish();
  auto conversion = convert(std::move(*asset), job.options, outcome.diagnostics);
  if (!conversion) return finish();
  lap(outcome.stages.convert);

  // The check runs before anything is written: a revision it rejects must never replace the live
  // revision's files (docs/daemon.md, "Outputs").
  std::optional<ValidationSummary> validation;
  if (job.validation) {
    LinkBounds bounds = link_geometry_bounds(conversion->asset, conversion->robot);
    const std::string file = job.source.string();
    // No settings key, nothing says what a verdict was computed under: none is kept or reused.
    const bool memo = !job.cache_key.empty();
    const CheckDigest digest = memo ? check_digest(file, job.cache_key, conversion->robot, bounds) : CheckDigest{};
    if (memo && job.verdict && job.verdict->digest == digest) {
      // Exactly the check that gave this verdict (verdict_memo.h): running it again would too.
      validation = job.verdict->verdict;
      outcome.verdict_reused = true;
    } else {
      ValidationReport report = validate_dynamics(conversion->robot, *job.validation, &bounds, file);
      if (report.cancelled) {
        outcome.cancelled = true;
        outcome.diagnostics.append(report.diagnostics);
        return finish();
      }
      ValidationSummary summary;
      summary.passed = report.passed;
      summary.simulated_time = report.simulated_time;
      summary.steps = report.steps;
      summary.energy_drift = report.energy_drift;
      summary.worst_joint_error = report.worst_joint_error;
      summary.wall_time = report.wall_time;
      summary.summary_line = validation_summary_line(report);
      summary.live_stepper = report.verdict_stepper;
      summary.after_quickstep_failed = report.judged_again_exactly;
      summary.diagnostics = std::move(report.diagnostics);
      // A verdict the machine's load decided (the check ran out of its CPU budget) is not kept.
      if (memo && !summary.diagnostics.contains(codes::SIM_BUDGET_EXCEEDED)) {
        outcome.verdict = std::make_shared<const VerdictMemo>(VerdictMemo{digest, summary});
      }
      validation = std::move(summary);
    }
  }
  lap(outcome.stages.check);
  const bool write = !(validation && !validation->passed) || job.write_failed;
  ConvertedModel converted;
  converted.content_hash = outcome.content_hash;
  converted.validation = std::move(validation);
  if (write) {
    auto staged = stage_outputs(job, *conversion, converted, outcome.diagnostics, outcome.retry);
    if (!staged) return finish();
    if (job.prepare) {
      outcome.staged = std::move(staged);  // Committed at the deadline (commit_prepared), or dropped.
    } else {
      if (!commit_outputs(*staged, outcome.diagnostics, outcome.retry)) return finish();
      converted.written = true;
    }
  }
  lap(outcome.stages.write);
  const UrdfNames names = urdf_names(conversion->robot);
  converted.facts = robot_facts(conversion->robot, names.links, names.joints,
                                link_geometry_digests(conversion->asset, conversion->robot, output_digest));
  converted.totals = robot_totals(conversion->robot);
  converted.robot = std::move(conversion->robot);
  lap(outcome.stages.convert);
  outcome.converted = std::move(converted);
  outcome.kind = ConversionOutcome::Kind::kConverted;
  // Staged outputs are cached once committed: an entry names outputs on disk.
  if (!outcome.staged && cacheable(job, outcome)) outcome.after_handover = cache_after_handover(job, outcome);
  lap(outcome.stages.cache);
  return finish();
}

}  // namespace rdtf::daemon
