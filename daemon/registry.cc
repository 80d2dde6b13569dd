#include "registry.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "rdtf/shortage.h"

namespace rdtf::daemon {

bool is_model_file(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".gltf" || extension == ".glb";
}

std::string model_id_for(const std::filesystem::path& source,
                         const std::vector<std::filesystem::path>& roots, std::size_t max_length) {
  std::string id = source.filename().string();
  for (std::size_t r = 0; r < roots.size(); ++r) {
    const auto relative = source.lexically_relative(roots[r]);
    if (relative.empty() || *relative.begin() == "..") continue;
    id = relative.generic_string();
    if (roots.size() > 1) {
      // The watched folder's name, made unique by its position when two share a name.
      std::string prefix = roots[r].filename().string();
      for (std::size_t other = 0; other < roots.size(); ++other) {
        if (other != r && roots[other].filename() == roots[r].filename()) {
          prefix += "_" + std::to_string(r + 1);
          break;
        }
      }
      id = prefix + "/" + id;
    }
    break;
  }
  for (char& c : id) {
    const bool allowed = std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' ||
                         c == '-' || c == '/';
    if (!allowed) c = '_';
  }
  if (id.size() > max_length) {
    // Keep the end (the file name) and make it unique with a short hash of the whole id.
    const std::size_t hash = std::hash<std::string>{}(id);
    char suffix[10];
    std::snprintf(suffix, sizeof(suffix), "%08zx", hash & 0xffffffffu);
    id = std::string(suffix) + "-" + id.substr(id.size() - (max_length - 9));
  }
  return id;
}

ModelRecord& Registry::ensure(const std::filesystem::path& source, const std::string& id) {
  auto [it, inserted] = models_.try_emplace(source);
  if (inserted) {
    it->second.source = source;
    it->second.id = id;
    ids_[id] = source;
  }
  return it->second;
}

ModelRecord* Registry::find(const std::filesystem::path& source) {
  const auto it = models_.find(source);
  return it == models_.end() ? nullptr : &it->second;
}

ModelRecord* Registry::find_id(const std::string& id) {
  const auto it = ids_.find(id);
  return it == ids_.end() ? nullptr : find(it->second);
}

const ModelRecord* Registry::find_id(const std::string& id) const {
  const auto it = ids_.find(id);
  if (it == ids_.end()) return nullptr;
  const auto model = models_.find(it->second);
  return model == models_.end() ? nullptr : &model->second;
}

void Registry::erase(const std::filesystem::path& source) {
  const auto it = models_.find(source);
  if (it == models_.end()) return;
  ids_.erase(it->second.id);
  models_.erase(it);
}

std::vector<std::filesystem::path> Registry::dependents(const std::filesystem::path& file) const {
  std::vector<std::filesystem::path> result;
  for (const auto& [source, record] : models_) {
    if (std::find(record.dependencies.begin(), record.dependencies.end(), file) !=
        record.dependencies.end()) {
      result.push_back(source);
    }
  }
  return result;
}

namespace {

// The manifest's entry of the file that has `role` ("rdtf", "urdf"); none when not written.
const OutputFile* file_of_role(const ConvertedModel& model, const char* role) {
  for (const OutputFile& file : model.files) {
    if (file.role == role) return &file;
  }
  return nullptr;
}

bool read_checked(const std::filesystem::path& path, const OutputFile& expected, std::string& text, std::string& why) {
  // With the reason: at the open-file limit every model's republication failed here, and the log
  // said only "cannot read" (s106fd D5).
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    why = "cannot read " + path.string() + ": " + std::strerror(errno);
    return false;
  }
  text.clear();
  char block[65536];
  for (;;) {
    const ssize_t n = ::read(fd, block, sizeof block);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      why = "cannot read " + path.string() + ": " + std::strerror(errno);
      ::close(fd);
      return false;
    }
    if (n == 0) break;
    text.append(block, static_cast<std::size_t>(n));
  }
  ::close(fd);
  if (static_cast<std::int64_t>(text.size()) != expected.size || sha256_hex(text) != expected.sha256) {
    why = path.string() + " is no longer the file rdtfd wrote (" + std::to_string(text.size()) + " bytes, " +
          std::to_string(expected.size) + " written)";
    return false;
  }
  return true;
}

}  // namespace

void release_live_texts(ModelRecord& record) {
  if (!record.live || record.texts_on_disk) return;
  ConvertedModel& model = *record.live;
  // Only what the manifest describes can be checked when read back; anything else stays.
  const bool json_on_disk = model.rdtf_json.empty() || file_of_role(model, "rdtf") != nullptr;
  const bool urdf_on_disk = model.urdf.empty() || file_of_role(model, "urdf") != nullptr;
  if (!model.written || !json_on_disk || !urdf_on_disk) return;
  std::string().swap(model.rdtf_json);
  std::string().swap(model.urdf);
  record.texts_on_disk = true;
}

bool same_live_texts(const ModelRecord& record, const ConvertedModel& candidate) {
  const ConvertedModel& live = *record.live;
  if (!record.texts_on_disk) return live.rdtf_json == candidate.rdtf_json && live.urdf == candidate.urdf;
  // Released: each text was empty or has its entry in the manifest, which equals the candidate's.
  return (file_of_role(live, "rdtf") != nullptr || candidate.rdtf_json.empty()) &&
         (file_of_role(live, "urdf") != nullptr || candidate.urdf.empty());
}

bool live_texts(const ModelRecord& record, LiveTexts& texts, std::string& why) {
  texts = LiveTexts{};
  if (!record.live) {
    why = "no live revision";
    return false;
  }
  const ConvertedModel& model = *record.live;
  if (!record.texts_on_disk) {
    texts.rdtf_json = model.rdtf_json;
    texts.urdf = model.urdf;
    return true;
  }
  if (const OutputFile* file = file_of_role(model, "rdtf")) {
    if (!read_checked(model.output_path, *file, texts.rdtf_json, why)) return false;
  }
  if (const OutputFile* file = file_of_role(model, "urdf")) {
    if (!read_checked(model.urdf_path, *file, texts.urdf, why)) return false;
  }
  return true;
}

}  // namespace rdtf::daemon

namespace rdtf::daemon {

std::string restore_revisions(const std::filesystem::path& output_root, ModelRecord& record) {
  ModelState state;
  std::string why;
  record.state_unread = false;
  switch (RevisionStore::load(output_root, record.id, state, why)) {
    case RevisionStore::LoadResult::kUnavailable:
      record.state_unread = true;
      return "revision state of " + record.id + " cannot be read now: " + why +
             "; it is read again before a revision of it is numbered";
    case RevisionStore::LoadResult::kAbsent: {
      // No state, but the outputs of an earlier run under this id (`.rdtfd-state` deleted, or the
      // outputs copied without it): that run handed out numbers nothing here remembers, and
      // counting from 1 again gave other contents the numbers subscribers had seen (stop 42's
      // leftover). Numbered from the clock, as for a state file refused.
      // Only a folder of rdtfd's own: never a symbolic link, which rdtfd does not make there (and
      // refuses to write through).
      std::error_code ec;
      const std::filesystem::path earlier = output_root / record.id;
      if (!std::filesystem::is_directory(std::filesystem::symlink_status(earlier, ec)) || ec) return "";
      const bool empty = std::filesystem::is_empty(earlier, ec);
      if (ec && is_shortage(ec.value())) {
        record.state_unread = true;  // Whether an earlier run numbered it is not known yet.
        return "revision state of " + record.id + " cannot be read now: cannot list " + earlier.string() + ": " +
               std::strerror(ec.value()) + "; it is read again before a revision of it is numbered";
      }
      if (empty || ec) return "";
      record.numbered = std::max(record.numbered, revision_floor_now());
      return "revision state of " + record.id + " missing while " + earlier.string() +
             " holds an earlier run's outputs; its revisions are numbered from " + std::to_string(record.numbered + 1) +
             ", above any number an earlier run can have handed out";
    }
    case RevisionStore::LoadResult::kRefused:
      record.numbered = std::max(record.numbered, revision_floor_now());
      return "revision state of " + record.id + " ignored: " + why + "; its revisions are numbered from " +
             std::to_string(record.numbered + 1) + ", above any number an earlier run can have handed out";
    case RevisionStore::LoadResult::kLoaded:
      break;
  }
  record.reserved = std::max(record.reserved, state.reserved);
  record.numbered = std::max(record.numbered, state.numbered);
  // Another file under the same id (ids that sanitise alike are numbered in the order they are
  // found) keeps the id's numbers but not the other file's revision.
  if (state.live && state.source == record.source.string()) record.restored = std::move(state.live);
  return "";
}

std::optional<StoredRevision> stored_live(const ModelRecord& record) {
  if (!record.live) return record.restored;
  StoredRevision stored;
  stored.revision = record.revisions;
  stored.content_hash = record.live->content_hash;
  stored.result_digest = record.live_result.empty() ? result_digest(*record.live) : record.live_result;
  stored.facts = record.live->facts;
  return stored;
}

std::string save_revisions(const std::filesystem::path& output_root, ModelRecord& record,
                           const std::optional<StoredRevision>& live) {
  ModelState state;
  state.model_id = record.id;
  state.source = record.source.string();
  state.numbered = record.numbered;
  const bool durable = record.numbered > record.reserved;
  state.reserved = durable ? record.numbered + kReservedRevisions - 1 : record.reserved;
  state.live = live;
  std::string why;
  if (!RevisionStore::save(output_root, state, durable, why)) return why;
  record.reserved = state.reserved;
  return "";
}

}  // namespace rdtf::daemon
