#include "assembly.h"

#include <set>

namespace rdtf::client::detail {
namespace {

std::string str(std::int64_t value) { return std::to_string(value); }

}  // namespace

bool is_sha256_hex(const std::string& text) {
  if (text.size() != 64) return false;
  for (const char c : text) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

std::string ChunkedDocument::add(const rdtf::description_chunk_t& chunk, const Limits& limits) {
  if (chunk.count <= 0 || chunk.count > limits.max_chunks) {
    return "chunk count " + str(chunk.count) + " outside 1.." + str(limits.max_chunks);
  }
  if (chunk.index < 0 || chunk.index >= chunk.count) {
    return "chunk index " + str(chunk.index) + " outside 0.." + str(chunk.count - 1);
  }
  if (count >= 0 && chunk.count != count) {
    return "chunk count " + str(chunk.count) + " differs from the " + str(count) + " of earlier chunks";
  }
  const std::string data(chunk.data.begin(), chunk.data.end());
  if (const auto held = chunks.find(chunk.index); held != chunks.end()) {
    // A republication repeats the same bytes; different ones are not the same revision's.
    return held->second == data ? "" : "chunk " + str(chunk.index) + " differs from the one already held";
  }
  if (bytes + static_cast<std::int64_t>(data.size()) > limits.max_document_bytes) {
    return "chunks beyond max_document_bytes (" + str(limits.max_document_bytes) + ")";
  }
  count = chunk.count;
  bytes += static_cast<std::int64_t>(data.size());
  chunks.emplace(chunk.index, data);
  return "";
}

std::string check_description(const rdtf::description_t& d, const Limits& limits) {
  if (d.revision <= 0) return "revision " + str(d.revision) + " is not positive";
  if (d.rdtf_json_size < 0 || d.rdtf_json_size > limits.max_document_bytes) {
    return "rdtf_json_size " + str(d.rdtf_json_size) + " outside 0.." + str(limits.max_document_bytes);
  }
  if (d.num_chunks < 0 || d.num_chunks > limits.max_chunks) return "num_chunks " + str(d.num_chunks) + " out of range";
  if (d.num_chunks == 0 && static_cast<std::int64_t>(d.rdtf_json.size()) != d.rdtf_json_size) {
    return "rdtf_json of " + str(static_cast<std::int64_t>(d.rdtf_json.size())) + " bytes but rdtf_json_size " +
           str(d.rdtf_json_size);
  }
  if (d.num_chunks > 0 && !d.rdtf_json.empty()) return "rdtf_json inline and in chunks";
  if (!is_sha256_hex(d.rdtf_json_sha256)) return "rdtf_json_sha256 is not 64 hex digits";
  if (d.urdf_size < 0 || d.urdf_size > limits.max_document_bytes) return "urdf_size " + str(d.urdf_size) + " out of range";
  if (d.num_urdf_chunks < 0 || d.num_urdf_chunks > limits.max_chunks) {
    return "num_urdf_chunks " + str(d.num_urdf_chunks) + " out of range";
  }
  if (d.urdf_sha256.empty()) {
    if (d.urdf_size != 0 || d.num_urdf_chunks != 0 || !d.urdf.empty()) return "a URDF without urdf_sha256";
  } else {
    if (!is_sha256_hex(d.urdf_sha256)) return "urdf_sha256 is not 64 hex digits";
    if (d.num_urdf_chunks == 0 && static_cast<std::int64_t>(d.urdf.size()) != d.urdf_size) {
      return "urdf of " + str(static_cast<std::int64_t>(d.urdf.size())) + " bytes but urdf_size " + str(d.urdf_size);
    }
    if (d.num_urdf_chunks > 0 && !d.urdf.empty()) return "urdf inline and in chunks";
  }
  if (d.num_links < 0 || d.num_links > limits.max_links) return "num_links " + str(d.num_links) + " out of range";
  if (d.num_joints < 0) return "num_joints " + str(d.num_joints) + " is negative";
  return "";
}

std::string check_manifest_part(const rdtf::manifest_t& m, const Limits& limits) {
  if (m.num_parts <= 0 || m.num_parts > limits.max_parts) return "num_parts " + str(m.num_parts) + " out of range";
  if (m.part < 0 || m.part >= m.num_parts) return "part " + str(m.part) + " outside 0.." + str(m.num_parts - 1);
  if (m.total_files < 0 || m.total_files > limits.max_files) {
    return "total_files " + str(m.total_files) + " outside 0.." + str(limits.max_files);
  }
  if (m.num_files > m.total_files) return "num_files " + str(m.num_files) + " above total_files";
  for (const auto& file : m.files) {
    if (const std::string why = check_relative_path(file.path); !why.empty()) return "file path: " + why;
    if (!is_sha256_hex(file.sha256)) return "file " + file.path + ": sha256 is not 64 lower-case hex digits";
    if (file.size < 0 || file.size > limits.max_blob_bytes) {
      return "file " + file.path + ": size " + str(file.size) + " outside 0.." + str(limits.max_blob_bytes);
    }
  }
  return "";
}

std::string RevisionParts::add_description(const rdtf::description_t& description, const Limits& limits) {
  if (std::string why = check_description(description, limits); !why.empty()) return why;
  if (description_ && (description_->num_chunks != description.num_chunks ||
                       description_->rdtf_json_sha256 != description.rdtf_json_sha256 ||
                       description_->urdf_sha256 != description.urdf_sha256 ||
                       description_->num_links != description.num_links)) {
    return "differs from the description already held for the same revision and content hash";
  }
  description_ = description;
  return "";
}

std::string RevisionParts::add_json_chunk(const rdtf::description_chunk_t& chunk, const Limits& limits) {
  if (description_ && chunk.count != description_->num_chunks) {
    return "chunk count " + str(chunk.count) + " but the description announces " + str(description_->num_chunks);
  }
  return json_.add(chunk, limits);
}

std::string RevisionParts::add_urdf_chunk(const rdtf::description_chunk_t& chunk, const Limits& limits) {
  if (description_ && chunk.count != description_->num_urdf_chunks) {
    return "URDF chunk count " + str(chunk.count) + " but the description announces " +
           str(description_->num_urdf_chunks);
  }
  return urdf_.add(chunk, limits);
}

std::string RevisionParts::add_inertia(const rdtf::inertia_table_t& table, const Limits& limits) {
  const std::int32_t expected = description_ ? description_->num_links : limits.max_links;
  // The parts of one publication share its utime and come in order (one sender, one socket);
  // a part of another publication starts the table again, so that parts lost from one
  // publication are never filled in by another's in the wrong order.
  if (!inertia_ || inertia_->utime != table.utime) {
    inertia_ = table;
    inertia_->links.clear();
    inertia_->num_links = 0;
  } else if (table.total_mass != inertia_->total_mass) {
    inertia_.reset();
    return "an INERTIA part whose total_mass differs from the earlier parts'";
  } else if (!table.links.empty()) {
    // A part of this publication already here (a datagram the network duplicated): each link
    // comes in one part, so its first link's node is among those held.
    for (const rdtf::link_inertia_t& held : inertia_->links) {
      if (held.node == table.links.front().node) return "";
    }
  }
  if (inertia_->num_links + table.num_links > expected) {
    inertia_.reset();
    return "INERTIA parts with more than the " + str(expected) + " links announced";
  }
  inertia_->links.insert(inertia_->links.end(), table.links.begin(), table.links.end());
  inertia_->num_links = static_cast<std::int32_t>(inertia_->links.size());
  return "";
}

std::string RevisionParts::add_manifest(const rdtf::manifest_t& part, const Limits& limits) {
  if (std::string why = check_manifest_part(part, limits); !why.empty()) return why;
  if (manifest_num_parts_ >= 0 && (part.num_parts != manifest_num_parts_ || part.total_files != manifest_total_files_)) {
    return "num_parts/total_files differ from the earlier parts'";
  }
  manifest_num_parts_ = part.num_parts;
  manifest_total_files_ = part.total_files;
  manifest_parts_[part.part] = part.files;
  return "";
}

std::string RevisionParts::add_validation(const rdtf::validation_report_t& report) {
  validation_ = report;
  return "";
}

std::optional<std::string> RevisionParts::document(const ChunkedDocument& chunks, std::int32_t announced,
                                                   std::int64_t size, const std::string& sha256,
                                                   const char* what, std::string& why) {
  if (!chunks.complete() || chunks.count != announced) return std::nullopt;
  std::string text;
  text.reserve(static_cast<std::size_t>(chunks.bytes));
  for (const auto& [index, data] : chunks.chunks) text += data;
  if (static_cast<std::int64_t>(text.size()) != size) {
    why = std::string(what) + " chunks join to " + str(static_cast<std::int64_t>(text.size())) +
          " bytes, announced " + str(size);
    return std::nullopt;
  }
  if (sha256_hex(text.data(), text.size()) != sha256) {
    why = std::string(what) + " chunks do not match the announced SHA-256";
    return std::nullopt;
  }
  return text;
}

std::string RevisionParts::missing(bool need_manifest) const {
  std::vector<std::string> out;
  const auto of = [](std::size_t have, std::int64_t all, const char* what) {
    return " (" + str(static_cast<std::int64_t>(have)) + " of " + str(all) + " " + what + ")";
  };
  if (!description_) {
    out.push_back("DESCRIPTION");
  } else {
    const auto& d = *description_;
    if (d.num_chunks > 0 && !(json_.complete() && json_.count == d.num_chunks)) {
      out.push_back("DESCRIPTION_CHUNK" + of(json_.chunks.size(), d.num_chunks, "chunks of the RDTF JSON"));
    }
    if (!d.urdf_sha256.empty() && d.num_urdf_chunks > 0 && !(urdf_.complete() && urdf_.count == d.num_urdf_chunks)) {
      out.push_back("URDF_CHUNK" + of(urdf_.chunks.size(), d.num_urdf_chunks, "chunks"));
    }
    if (!inertia_ || inertia_->num_links != d.num_links) {
      out.push_back("INERTIA" + of(inertia_ ? inertia_->links.size() : 0, d.num_links, "links"));
    }
    if (d.validated && !validation_) out.push_back("VALIDATION");
  }
  if (need_manifest && !(manifest_num_parts_ >= 0 &&
                         manifest_parts_.size() == static_cast<std::size_t>(manifest_num_parts_))) {
    out.push_back(manifest_num_parts_ < 0 ? std::string("MANIFEST")
                                          : "MANIFEST" + of(manifest_parts_.size(), manifest_num_parts_, "parts"));
  }
  std::string text;
  for (const std::string& part : out) text += (text.empty() ? "" : ", ") + part;
  return text;
}

std::optional<Snapshot> RevisionParts::assemble(bool need_manifest, std::string& why) {
  why.clear();
  if (!description_) return std::nullopt;
  const auto& d = *description_;
  Snapshot snapshot;
  snapshot.description = d;
  if (d.num_chunks == 0) {
    if (sha256_hex(d.rdtf_json.data(), d.rdtf_json.size()) != d.rdtf_json_sha256) {
      why = "rdtf_json does not match rdtf_json_sha256";
      description_.reset();
      return std::nullopt;
    }
  } else {
    auto text = document(json_, d.num_chunks, d.rdtf_json_size, d.rdtf_json_sha256, "RDTF JSON", why);
    if (!why.empty()) json_.clear();
    if (!text) return std::nullopt;
    snapshot.description.rdtf_json = std::move(*text);
  }
  if (!d.urdf_sha256.empty()) {
    if (d.num_urdf_chunks == 0) {
      if (sha256_hex(d.urdf.data(), d.urdf.size()) != d.urdf_sha256) {
        why = "urdf does not match urdf_sha256";
        description_.reset();
        return std::nullopt;
      }
    } else {
      auto text = document(urdf_, d.num_urdf_chunks, d.urdf_size, d.urdf_sha256, "URDF", why);
      if (!why.empty()) urdf_.clear();
      if (!text) return std::nullopt;
      snapshot.description.urdf = std::move(*text);
    }
  }
  if (!inertia_ || inertia_->num_links != d.num_links) return std::nullopt;
  snapshot.inertia = *inertia_;
  if (d.validated) {
    if (!validation_) return std::nullopt;
    snapshot.validation = validation_;
  }
  const bool manifest_complete = manifest_num_parts_ >= 0 &&
                                 manifest_parts_.size() == static_cast<std::size_t>(manifest_num_parts_);
  if (manifest_complete) {
    std::set<std::string> paths;
    std::map<std::string, std::int64_t> sizes;
    for (const auto& [index, files] : manifest_parts_) {
      for (const auto& file : files) {
        const auto size = sizes.emplace(file.sha256, file.size).first->second;
        if (!paths.insert(file.path).second || size != file.size) {
          why = "manifest names " + file.path + " twice, or one SHA-256 with two sizes";
          break;
        }
        snapshot.manifest.push_back(file);
      }
      if (!why.empty()) break;
    }
    // "a" and "a/b" cannot both be files.
    for (const auto& path : paths) {
      if (!why.empty()) break;
      if (const auto next = paths.lower_bound(path + "/"); next != paths.end() && next->rfind(path + "/", 0) == 0) {
        why = "manifest has both " + path + " and " + *next;
      }
    }
    if (why.empty() && static_cast<std::int32_t>(snapshot.manifest.size()) != manifest_total_files_) {
      why = "manifest parts hold " + str(static_cast<std::int64_t>(snapshot.manifest.size())) + " files, announced " +
            str(manifest_total_files_);
    }
    if (!why.empty()) {
      manifest_parts_.clear();
      manifest_num_parts_ = manifest_total_files_ = -1;
      return std::nullopt;
    }
    snapshot.has_manifest = true;
  } else {
    snapshot.manifest.clear();
    if (need_manifest) return std::nullopt;
  }
  return snapshot;
}

}  // namespace rdtf::client::detail
