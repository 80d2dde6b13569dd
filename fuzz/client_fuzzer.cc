// libFuzzer target `client`: a sequence of datagrams from a hostile bus fed to one rdtf_client
// (clients/client/), as liblcm would hand them to its handlers, with time passing between them so
// that its retries run. Input: byte 0 picks the options (bit 0: every blob, else none; bit 1: one
// model, else all); then records of [channel byte][size: 2 bytes, little endian][payload], the
// channel byte picking one of kChannels.
//
// Besides a crash, leak, sanitizer report or hang, a target stops on a broken contract: a
// snapshot handed over whose documents, inertia table or blobs do not match what its description
// and manifest announce, a manifest path that is not a plain relative path, a state of another
// revision than its snapshot's, a SAVING of another model than its channel's, or a message the
// client sends that fails the schema check.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "rdtf/client.h"
#include "safe_decode.h"

namespace {

void require(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "rdtf fuzz: %s\n", what);
  std::abort();
}

const char* const kChannels[] = {
    "RDTF/m.gltf/DESCRIPTION", "RDTF/m.gltf/DESCRIPTION_CHUNK", "RDTF/m.gltf/URDF_CHUNK", "RDTF/m.gltf/INERTIA",
    "RDTF/m.gltf/MANIFEST",    "RDTF/m.gltf/VALIDATION",        "RDTF/m.gltf/ERROR",      "RDTF/m.gltf/REMOVED",
    "RDTF/m.gltf/JOINT_STATE", "RDTF/m.gltf/LINK_STATE",        "RDTF/BLOB",              "RDTF/BLOB_UNAVAILABLE",
    "RDTF/STATUS",             "RDTF/n/m.glb/DESCRIPTION",      "RDTF/n/m.glb/INERTIA",   "RDTF/n/m.glb/MANIFEST",
    "RDTF/m.gltf/SAVING",
};
constexpr std::size_t kChannelCount = sizeof(kChannels) / sizeof(kChannels[0]);

void check_snapshot(const rdtf::client::Snapshot& s) {
  const auto& d = s.description;
  require(static_cast<std::int64_t>(d.rdtf_json.size()) == d.rdtf_json_size, "snapshot: rdtf_json of another size");
  require(rdtf::client::sha256_hex(d.rdtf_json.data(), d.rdtf_json.size()) == d.rdtf_json_sha256,
          "snapshot: rdtf_json of another hash");
  require(static_cast<std::int64_t>(d.urdf.size()) == d.urdf_size, "snapshot: urdf of another size");
  if (!d.urdf_sha256.empty()) {
    require(rdtf::client::sha256_hex(d.urdf.data(), d.urdf.size()) == d.urdf_sha256, "snapshot: urdf of another hash");
  }
  require(s.inertia.links.size() == static_cast<std::size_t>(d.num_links), "snapshot: inertia table of another length");
  require(s.inertia.revision == d.revision && s.inertia.content_hash == d.content_hash, "snapshot: inertia of another revision");
  for (const auto& file : s.manifest) {
    require(rdtf::client::check_relative_path(file.path).empty(), "snapshot: an unsafe manifest path");
    const auto it = s.blobs.find(file.sha256);
    if (it == s.blobs.end()) continue;  // Blobs::kNone
    require(static_cast<std::int64_t>(it->second->size()) == file.size, "snapshot: a blob of another size");
    require(rdtf::client::sha256_hex(it->second->data(), it->second->size()) == file.sha256,
            "snapshot: a blob of another hash");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  rdtf::client::Options options;
  options.blobs = (data[0] & 1) != 0 ? rdtf::client::Blobs::kAll : rdtf::client::Blobs::kNone;
  if ((data[0] & 2) != 0) options.model = "m.gltf";
  options.requester = "fuzz";
  // Small limits: what the fuzzer may make the client hold stays within its memory budget.
  options.limits.max_document_bytes = 1 << 20;
  options.limits.max_blob_bytes = 1 << 20;
  options.limits.max_fetch_bytes = 4 << 20;
  options.limits.max_store_bytes = 8 << 20;
  options.limits.max_chunks = 4096;
  options.limits.max_links = 4096;
  options.limits.max_files = 4096;
  rdtf::client::Callbacks callbacks;
  callbacks.on_revision = [](std::shared_ptr<const rdtf::client::Snapshot> s) { check_snapshot(*s); };
  callbacks.on_joint_state = [](const rdtf::client::Snapshot& s, const rdtf::joint_state_t& state) {
    require(state.revision == s.revision() && state.content_hash == s.content_hash(), "a state of another revision");
  };
  callbacks.on_link_state = [](const rdtf::client::Snapshot& s, const rdtf::link_state_t& state) {
    require(state.revision == s.revision() && state.content_hash == s.content_hash(), "a link state of another revision");
  };
  callbacks.on_saving = [](const rdtf::model_saving_t& saving) {
    require(saving.model_id == "m.gltf", "a SAVING of another model than its channel's");
  };
  callbacks.on_drop = [](const std::string&, const std::string&) {};
  callbacks.on_problem = [](const std::string&, const std::string&) {};
  rdtf::client::Client client(
      [](const std::string&, const std::vector<std::uint8_t>& bytes) {
        require(rdtf::lcm_safe::check_known(bytes.data(), bytes.size()).empty(), "the client sent a malformed message");
      },
      options, callbacks);
  auto now = rdtf::client::Clock::time_point{} + std::chrono::hours(1);
  client.tick(now);
  std::size_t at = 1;
  while (at + 3 <= size) {
    const char* channel = kChannels[data[at] % kChannelCount];
    const std::size_t length = std::min<std::size_t>(data[at + 1] | (data[at + 2] << 8), size - at - 3);
    client.on_datagram(channel, data + at + 3, length, now);
    at += 3 + length;
    now += std::chrono::milliseconds(100);
    client.tick(now);
  }
  return 0;
}
