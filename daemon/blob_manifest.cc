#include "blob_manifest.h"

#include <filesystem>
#include <set>

#include <nlohmann/json.hpp>

#include "../core/gltf/confined_files.h"
#include "conversion.h"
#include "message_parts.h"
#include "messages.h"
#include "rdtf/urdf.h"

namespace rdtf::daemon {
namespace {

constexpr std::size_t kNameDigits = 16;

// The 16 hex digits of a content-addressed name ("<stem>.<16 hex>[.<ext>]"), or "".
std::string name_digits(const std::string& name) {
  if (!is_content_addressed_name(name)) return {};
  const auto digits_at = [&](std::size_t end) -> std::string {
    return end >= kNameDigits ? name.substr(end - kNameDigits, kNameDigits) : std::string();
  };
  const std::string last = digits_at(name.size());
  if (name.size() > kNameDigits && name[name.size() - kNameDigits - 1] == '.' &&
      last.find_first_not_of("0123456789abcdef") == std::string::npos) {
    return last;
  }
  const auto dot = name.rfind('.');
  return dot == std::string::npos ? std::string() : digits_at(dot);
}

// The files (names directly in the folder) that the JSON's buffers and images name, with their role.
std::vector<std::pair<std::string, std::string>> gltf_files(const std::string& rdtf_json) {
  std::vector<std::pair<std::string, std::string>> files;
  const auto document = nlohmann::json::parse(rdtf_json, nullptr, false);
  if (!document.is_object()) return files;
  for (const auto& [array, role] : {std::pair{"buffers", "buffer"}, std::pair{"images", "image"}}) {
    if (!document.contains(array) || !document[array].is_array()) continue;
    for (const auto& item : document[array]) {
      if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
      const std::string uri = item["uri"].get<std::string>();
      if (internal::is_data_uri(uri)) continue;
      if (auto name = internal::percent_decode(uri)) files.emplace_back(*name, role);
    }
  }
  return files;
}

}  // namespace

ContentDigest DigestLog::digest() {
  return [state = state_](std::span<const std::uint8_t> bytes) {
    std::string hex = output_digest(bytes);
    std::lock_guard lock(state->mutex);
    state->by_prefix.emplace(hex.substr(0, kNameDigits), Entry{hex, static_cast<std::int64_t>(bytes.size())});
    return hex;
  };
}

std::vector<DigestLog::Entry> DigestLog::matching(const std::string& prefix) const {
  std::lock_guard lock(state_->mutex);
  std::vector<Entry> entries;
  auto [begin, end] = state_->by_prefix.equal_range(prefix);
  for (auto it = begin; it != end; ++it) {
    const bool seen = std::any_of(entries.begin(), entries.end(), [&](const Entry& e) { return e.sha256 == it->second.sha256; });
    if (!seen) entries.push_back(it->second);
  }
  return entries;
}

std::vector<OutputFile> output_files(const std::string& gltf_name, const std::string& rdtf_json,
                                     const std::string& urdf, const DigestLog& log, std::string& why) {
  std::vector<OutputFile> files;
  std::set<std::string> listed;
  auto addressed = [&](const std::string& path, const std::string& name, const std::string& role) {
    if (listed.count(path) > 0) return true;  // Two buffers with the same bytes: one file.
    // An image the conversion could not copy (missing or unreadable: IMAGE_NOT_COPIED) keeps its
    // own URI in the output, and no such file is there to list: the model's other files are
    // still had from the bus. It made the whole manifest empty (s80client D2).
    if (role == "image" && !is_content_addressed_name(std::filesystem::path(name).filename().string())) return true;
    const auto entries = log.matching(name_digits(name));
    if (name.find('/') != std::string::npos || entries.size() != 1) {
      why = "no single hash was recorded for " + path + " when it was written (" +
            std::to_string(entries.size()) + " match its name)";
      return false;
    }
    listed.insert(path);
    files.push_back({path, entries.front().sha256, entries.front().size, role});
    return true;
  };
  files.push_back({gltf_name, sha256_hex(rdtf_json), static_cast<std::int64_t>(rdtf_json.size()), "rdtf"});
  listed.insert(gltf_name);
  for (const auto& [name, role] : gltf_files(rdtf_json)) {
    if (!addressed(name, name, role)) return {};
  }
  if (!urdf.empty()) {
    files.push_back({"urdf/robot.urdf", sha256_hex(urdf), static_cast<std::int64_t>(urdf.size()), "urdf"});
    for (const auto& filename : urdf_mesh_filenames(urdf)) {
      const std::string name = std::filesystem::path(filename).filename().string();
      if (!addressed("urdf/meshes/" + name, name, "urdf_mesh")) return {};
    }
  }
  return files;
}

std::vector<rdtf::manifest_t> make_manifests(const std::string& model_id, std::int64_t revision,
                                             const std::string& content_hash,
                                             const std::vector<OutputFile>& files, std::size_t max_message_bytes) {
  rdtf::manifest_t part;
  part.utime = now_utime();
  part.model_id = model_id;
  part.revision = revision;
  part.content_hash = content_hash;
  part.part = 0;
  part.num_parts = 0;
  part.total_files = static_cast<std::int32_t>(files.size());
  part.num_files = 0;
  std::vector<rdtf::file_t> rows;
  rows.reserve(files.size());
  for (const OutputFile& file : files) {
    rdtf::file_t& row = rows.emplace_back();
    row.path = file.path;
    row.sha256 = file.sha256;
    row.size = file.size;
    row.role = file.role;
  }
  return split_into_parts(part, std::move(rows), &rdtf::manifest_t::files, &rdtf::manifest_t::num_files,
                          max_message_bytes);
}

}  // namespace rdtf::daemon
