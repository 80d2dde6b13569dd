// What rdtfd publishes for one revision of one model, and its answers to blob requests, as
// encoded datagrams (channel, bytes), for the unit tests of rdtf_client (client_test.cc). The
// order is rdtfd's (docs/lcm.md): VALIDATION, MANIFEST parts, DESCRIPTION_CHUNKs, URDF_CHUNKs,
// DESCRIPTION, INERTIA parts. Sizes are small so that a test splits into many chunks and parts.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <rdtf/blob_chunk_t.hpp>
#include <rdtf/blob_request_t.hpp>
#include <rdtf/blob_unavailable_t.hpp>
#include <rdtf/description_chunk_t.hpp>
#include <rdtf/description_t.hpp>
#include <rdtf/inertia_table_t.hpp>
#include <rdtf/manifest_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "rdtf/client.h"

namespace rdtf::testing {

using Datagram = std::pair<std::string, std::vector<std::uint8_t>>;

template <typename Message>
Datagram datagram(const std::string& channel, const Message& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return {channel, bytes};
}

struct FakeFile {
  std::string path;
  std::string role;
  std::string bytes;
};

struct FakeRevision {
  std::string model_id = "arm.gltf";
  std::int64_t revision = 1;
  std::string content_hash = std::string(64, 'a');
  std::string rdtf_json;
  std::string urdf;
  int links = 5;
  bool validated = false;
  std::vector<FakeFile> files;
  // Splitting: bytes per description chunk (0: inline), links per INERTIA part, files per MANIFEST part.
  std::size_t json_chunk = 0;
  std::size_t urdf_chunk = 0;
  int links_per_part = 2;
  int files_per_part = 2;
};

inline std::string prefixed(const FakeRevision& r, const std::string& kind) { return "RDTF/" + r.model_id + "/" + kind; }

inline std::vector<rdtf::description_chunk_t> chunks_of(const FakeRevision& r, const std::string& text, std::size_t size) {
  std::vector<rdtf::description_chunk_t> out;
  const int count = static_cast<int>((text.size() + size - 1) / size);
  for (int i = 0; i < count; ++i) {
    rdtf::description_chunk_t c;
    c.utime = 1;
    c.model_id = r.model_id;
    c.revision = r.revision;
    c.content_hash = r.content_hash;
    c.index = i;
    c.count = count;
    const std::string part = text.substr(static_cast<std::size_t>(i) * size, size);
    c.data.assign(part.begin(), part.end());
    c.size = static_cast<std::int32_t>(part.size());
    out.push_back(c);
  }
  return out;
}

inline rdtf::description_t description_of(const FakeRevision& r) {
  rdtf::description_t d;
  d.utime = 1;
  d.model_id = r.model_id;
  d.source_path = "/models/" + r.model_id;
  d.revision = r.revision;
  d.content_hash = r.content_hash;
  d.output_path = "/out/" + r.model_id + "/x.rdtf.gltf";
  d.urdf_path = r.urdf.empty() ? "" : "/out/" + r.model_id + "/urdf/robot.urdf";
  d.num_links = r.links;
  d.num_joints = r.links - 1;
  d.validated = r.validated;
  d.validation_passed = r.validated;
  d.rdtf_json = r.json_chunk == 0 ? r.rdtf_json : "";
  d.num_chunks = r.json_chunk == 0 ? 0 : static_cast<std::int32_t>(chunks_of(r, r.rdtf_json, r.json_chunk).size());
  d.rdtf_json_size = static_cast<std::int64_t>(r.rdtf_json.size());
  d.rdtf_json_sha256 = rdtf::client::sha256_hex(r.rdtf_json.data(), r.rdtf_json.size());
  d.urdf = r.urdf_chunk == 0 ? r.urdf : "";
  d.num_urdf_chunks = r.urdf_chunk == 0 ? 0 : static_cast<std::int32_t>(chunks_of(r, r.urdf, r.urdf_chunk).size());
  d.urdf_size = static_cast<std::int64_t>(r.urdf.size());
  d.urdf_sha256 = r.urdf.empty() ? "" : rdtf::client::sha256_hex(r.urdf.data(), r.urdf.size());
  return d;
}

inline rdtf::link_inertia_t link_of(int i) {
  rdtf::link_inertia_t l;
  l.name = "link_" + std::to_string(i);
  l.node = i;
  l.mass = 1.5 + i;
  l.volume = 0.001 * (i + 1);
  l.center_of_mass[0] = 0.1 * i;
  l.center_of_mass[1] = 0;
  l.center_of_mass[2] = -0.2;
  l.ixx = l.iyy = l.izz = 0.01 * (i + 1);
  l.ixy = l.ixz = l.iyz = 0;
  l.authored = false;
  return l;
}

inline std::vector<rdtf::file_t> manifest_files(const FakeRevision& r) {
  std::vector<rdtf::file_t> out;
  for (const auto& f : r.files) {
    rdtf::file_t file;
    file.path = f.path;
    file.sha256 = rdtf::client::sha256_hex(f.bytes.data(), f.bytes.size());
    file.size = static_cast<std::int64_t>(f.bytes.size());
    file.role = f.role;
    out.push_back(file);
  }
  return out;
}

// Every datagram of one publication of `r`, in rdtfd's order. Like rdtfd, every INERTIA part of
// one publication carries the same utime, another than the last publication's.
inline std::vector<Datagram> publication(const FakeRevision& r) {
  static std::int64_t publications = 0;
  const std::int64_t utime = 1000 + ++publications;
  std::vector<Datagram> out;
  if (r.validated) {
    rdtf::validation_report_t v{};
    v.utime = 1;
    v.model_id = r.model_id;
    v.revision = r.revision;
    v.content_hash = r.content_hash;
    v.passed = true;
    v.num_diagnostics = 0;
    out.push_back(datagram(prefixed(r, "VALIDATION"), v));
  }
  const auto files = manifest_files(r);
  const int parts = std::max<int>(1, static_cast<int>((files.size() + r.files_per_part - 1) / r.files_per_part));
  for (int p = 0; p < parts; ++p) {
    rdtf::manifest_t m;
    m.utime = 1;
    m.model_id = r.model_id;
    m.revision = r.revision;
    m.content_hash = r.content_hash;
    m.part = p;
    m.num_parts = parts;
    m.total_files = static_cast<std::int32_t>(files.size());
    for (std::size_t i = static_cast<std::size_t>(p * r.files_per_part);
         i < files.size() && i < static_cast<std::size_t>((p + 1) * r.files_per_part); ++i) {
      m.files.push_back(files[i]);
    }
    m.num_files = static_cast<std::int32_t>(m.files.size());
    out.push_back(datagram(prefixed(r, "MANIFEST"), m));
  }
  if (r.json_chunk > 0) {
    for (const auto& c : chunks_of(r, r.rdtf_json, r.json_chunk)) out.push_back(datagram(prefixed(r, "DESCRIPTION_CHUNK"), c));
  }
  if (r.urdf_chunk > 0) {
    for (const auto& c : chunks_of(r, r.urdf, r.urdf_chunk)) out.push_back(datagram(prefixed(r, "URDF_CHUNK"), c));
  }
  out.push_back(datagram(prefixed(r, "DESCRIPTION"), description_of(r)));
  double total = 0;
  for (int i = 0; i < r.links; ++i) total += link_of(i).mass;
  for (int first = 0; first < r.links || first == 0; first += r.links_per_part) {
    rdtf::inertia_table_t t;
    t.utime = utime;
    t.model_id = r.model_id;
    t.revision = r.revision;
    t.content_hash = r.content_hash;
    t.total_mass = total;
    t.center_of_mass_scene[0] = t.center_of_mass_scene[1] = t.center_of_mass_scene[2] = 0;
    for (int i = first; i < r.links && i < first + r.links_per_part; ++i) t.links.push_back(link_of(i));
    t.num_links = static_cast<std::int32_t>(t.links.size());
    out.push_back(datagram(prefixed(r, "INERTIA"), t));
    if (r.links == 0) break;
  }
  return out;
}

// rdtfd's blob server in miniature: the chunks of the ranges asked for, or "not available".
class FakeBlobServer {
 public:
  explicit FakeBlobServer(std::int32_t chunk_size) : chunk_size_(chunk_size) {}
  void serve(const FakeRevision& r) {
    for (const auto& f : r.files) blobs_[rdtf::client::sha256_hex(f.bytes.data(), f.bytes.size())] = f.bytes;
  }
  std::vector<Datagram> answer(const rdtf::blob_request_t& request) const {
    std::vector<Datagram> out;
    rdtf::blob_unavailable_t unavailable;
    unavailable.utime = 1;
    unavailable.requester = request.requester;
    unavailable.num_blobs = 0;
    for (int i = 0; i < request.num_ranges; ++i) {
      const auto it = blobs_.find(request.sha256[i]);
      if (it == blobs_.end()) {
        unavailable.sha256.push_back(request.sha256[i]);
        unavailable.reason.push_back("not a file of any live revision");
        ++unavailable.num_blobs;
        continue;
      }
      const std::string& bytes = it->second;
      const std::int32_t count = bytes.empty() ? 1 : static_cast<std::int32_t>((bytes.size() + chunk_size_ - 1) / chunk_size_);
      const std::int32_t last = request.num_chunks[i] < 0 ? count : std::min(count, request.first_chunk[i] + request.num_chunks[i]);
      for (std::int32_t index = std::max(0, request.first_chunk[i]); index < last; ++index) {
        rdtf::blob_chunk_t c;
        c.utime = 1;
        c.sha256 = it->first;
        c.blob_size = static_cast<std::int64_t>(bytes.size());
        c.chunk_size = chunk_size_;
        c.index = index;
        c.count = count;
        const std::string part = bytes.substr(static_cast<std::size_t>(index) * chunk_size_, chunk_size_);
        c.data.assign(part.begin(), part.end());
        c.size = static_cast<std::int32_t>(part.size());
        out.push_back(datagram("RDTF/BLOB", c));
      }
    }
    if (unavailable.num_blobs > 0) out.push_back(datagram("RDTF/BLOB_UNAVAILABLE", unavailable));
    return out;
  }

 private:
  std::int32_t chunk_size_;
  std::map<std::string, std::string> blobs_;
};

}  // namespace rdtf::testing
