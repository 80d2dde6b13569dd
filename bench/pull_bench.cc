// pull_bench: the whole model over LCM with rdtf_client (docs/benchmarks.md, "Pulling a model").
//
// rdtfd (a child, validate and simulate off: this measures the bus, not ODE) watches a two-link
// model whose links share one UV-sphere mesh of about N triangles (default 1,000,000; argument 1)
// with its buffer in a .bin beside the .gltf, and writes its URDF with one STL mesh per link.
//  1. Cold: once revision 1 is published, a client with an empty blob store (Blobs::kAll) starts,
//     asks, and is timed until it holds every file of the revision. Bytes on the bus are every
//     datagram on RDTF/.* meanwhile (as the client's socket received them), and the blob bytes.
//  2. Edit: the joint's upper limit is changed in the .gltf; the same client (holding revision 1's
//     blobs) is timed from the save until it holds revision 2, and what came over the bus is
//     split into mesh bytes (chunks of blobs with role buffer or urdf_mesh) and the rest.
// Runs in a network namespace of its own (daemon_harness.h).
#include <cmath>
#include <cstdio>
#include <set>

#include <rdtf/blob_chunk_t.hpp>
#include <rdtf/request_t.hpp>

#include "daemon_harness.h"
#include "rdtf/client.h"
#include "safe_decode.h"
#include "synthetic_models.h"

namespace {

using namespace rdtf::bench;

// Two links, each a node of the same sphere mesh, joined by a revolute joint with limits.
std::pair<std::string, std::string> two_link_model(std::size_t triangles, double upper) {
  const rdtf::TriangleMesh mesh = uv_sphere(triangles, 0.1);
  std::string bin;
  float lo[3] = {1e9f, 1e9f, 1e9f};
  float hi[3] = {-1e9f, -1e9f, -1e9f};
  for (const auto& p : mesh.positions) {
    for (int i = 0; i < 3; ++i) {
      const auto f = static_cast<float>(p[i]);
      bin.append(reinterpret_cast<const char*>(&f), 4);
      lo[i] = std::min(lo[i], f);
      hi[i] = std::max(hi[i], f);
    }
  }
  const std::size_t positions = bin.size();
  for (const auto& t : mesh.triangles) bin.append(reinterpret_cast<const char*>(t.data()), 12);
  const Json document = {
      {"asset", {{"version", "2.0"}, {"generator", "rdtf pull_bench"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes",
       {{{"name", "base"}, {"mesh", 0}, {"children", {1}}},
        {{"name", "hinge"},
         {"translation", {0.0, 0.3, 0.0}},
         {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", {0.0, 0.0, 1.0}}, {"rdtf_lower", -1.0}, {"rdtf_upper", upper}}},
         {"children", {2}}},
        {{"name", "arm"}, {"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", mesh.positions.size()}, {"type", "VEC3"},
         {"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}},
        {{"bufferView", 1}, {"componentType", 5125}, {"count", 3 * mesh.triangles.size()}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", positions}, {"target", 34962}},
        {{"buffer", 0}, {"byteOffset", positions}, {"byteLength", bin.size() - positions}, {"target", 34963}}}},
      {"buffers", {{{"byteLength", bin.size()}, {"uri", "model.bin"}}}}};
  return {document.dump(1), bin};
}

struct Traffic {
  std::uint64_t datagrams = 0;
  std::uint64_t bytes = 0;
  std::uint64_t mesh_bytes = 0;  // payload of BLOB chunks of buffers and URDF meshes
};

}  // namespace

int main(int argc, char** argv) {
  run_in_own_network_namespace(argc, argv);
  const std::size_t triangles = argc > 1 ? std::stoul(argv[1]) : 1000000;
  TempFolder root;
  fs::create_directories(root / "models");
  fs::create_directories(root / "out");
  auto [gltf, bin] = two_link_model(triangles, 1.0);
  write_in_place(root / "models" / "model.bin", bin);
  write_in_place(root / "models" / "model.gltf", gltf);
  Daemon daemon(root / "models", root / "out", Json{{"validate", false}, {"simulate", false}});

  lcm::LCM lcm;
  if (!lcm.good()) return 1;
  Traffic traffic;
  std::set<std::string> mesh_blobs;
  struct Counter {
    Traffic* traffic;
    std::set<std::string>* mesh_blobs;
    void on(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
      ++traffic->datagrams;
      traffic->bytes += buffer->data_size;
      if (channel != "RDTF/BLOB") return;
      std::string why;
      auto chunk = rdtf::lcm_safe::decode<rdtf::blob_chunk_t>(buffer->data, buffer->data_size, why);
      if (chunk && mesh_blobs->count(chunk->sha256)) traffic->mesh_bytes += static_cast<std::uint64_t>(chunk->size);
    }
  } counter{&traffic, &mesh_blobs};
  lcm.subscribe("RDTF/.*", &Counter::on, &counter)->setQueueCapacity(100000);

  // Wait for revision 1 without a client (a client would fetch as soon as it is published).
  {
    bool published = false;
    struct Watch {
      bool* published;
      void on(const lcm::ReceiveBuffer*, const std::string&) { *published = true; }
    } watch{&published};
    auto* s = lcm.subscribe("RDTF/model\\.gltf/DESCRIPTION", &Watch::on, &watch);
    rdtf::request_t request{};
    request.model_id = "model.gltf";
    request.requester = "pull_bench";
    const auto deadline = Clock::now() + std::chrono::minutes(5);
    auto next_request = Clock::now();
    while (!published && Clock::now() < deadline) {
      if (Clock::now() >= next_request) {
        lcm.publish("RDTF/REQUEST", &request);
        next_request = Clock::now() + std::chrono::seconds(1);
      }
      lcm.handleTimeout(50);
    }
    lcm.unsubscribe(s);
    if (!published) {
      std::fprintf(stderr, "pull_bench: no revision 1 within 5 min; rdtfd log:\n%s\n", daemon.log().c_str());
      return 1;
    }
    // Let the answers to the requests pass before counting.
    const auto quiet = Clock::now() + std::chrono::milliseconds(1500);
    while (Clock::now() < quiet) lcm.handleTimeout(50);
  }

  std::shared_ptr<const rdtf::client::Snapshot> snapshot;
  rdtf::client::Options options;
  options.model = "model.gltf";
  options.blobs = rdtf::client::Blobs::kAll;
  options.states = false;
  rdtf::client::Callbacks callbacks;
  callbacks.on_revision = [&](std::shared_ptr<const rdtf::client::Snapshot> s) {
    snapshot = std::move(s);
    for (const auto& f : snapshot->manifest) {
      if (f.role == "buffer" || f.role == "urdf_mesh") mesh_blobs.insert(f.sha256);
    }
  };
  traffic = Traffic{};
  const auto t0 = Clock::now();
  rdtf::client::Client client(lcm, options, callbacks);
  while (!snapshot && Clock::now() - t0 < std::chrono::minutes(2)) {
    lcm.handleTimeout(10);
    client.tick();
  }
  if (!snapshot) return 1;
  const double cold_s = std::chrono::duration<double>(Clock::now() - t0).count();
  const Traffic cold = traffic;
  const auto cold_stats = client.stats();
  std::int64_t files_bytes = 0;
  std::int64_t mesh_files_bytes = 0;
  for (const auto& f : snapshot->manifest) {
    files_bytes += f.size;
    if (f.role == "buffer" || f.role == "urdf_mesh") mesh_files_bytes += f.size;
    std::printf("  file %-40s %-10s %12lld bytes\n", f.path.c_str(), f.role.c_str(), static_cast<long long>(f.size));
  }
  std::printf("model: %zu triangles per link mesh, %zu files, %lld bytes (%lld of meshes and buffers)\n", triangles,
              snapshot->manifest.size(), static_cast<long long>(files_bytes), static_cast<long long>(mesh_files_bytes));
  std::printf("cold pull: %.3f s, %llu datagrams, %llu bytes on the bus (%llu blob bytes), %llu chunks asked for "
              "again in %llu re-requests\n",
              cold_s, static_cast<unsigned long long>(cold.datagrams), static_cast<unsigned long long>(cold.bytes),
              static_cast<unsigned long long>(cold_stats.blob_bytes),
              static_cast<unsigned long long>(cold_stats.blob_chunks_reasked),
              static_cast<unsigned long long>(cold_stats.blob_retries));

  // The edit: one joint limit.
  const std::int64_t revision = snapshot->revision();
  traffic = Traffic{};
  const std::uint64_t blob_bytes_before = client.stats().blob_bytes;
  const auto t1 = write_in_place(root / "models" / "model.gltf", two_link_model(triangles, 0.5).first);
  while (snapshot->revision() == revision && Clock::now() - t1 < std::chrono::minutes(5)) {
    lcm.handleTimeout(10);
    client.tick();
  }
  if (snapshot->revision() == revision) return 1;
  const double edit_s = std::chrono::duration<double>(Clock::now() - t1).count();
  const Traffic edit = traffic;
  std::printf("edit of one joint limit: revision %lld after %.3f s from the save (conversion included), "
              "%llu datagrams, %llu bytes on the bus, %llu blob bytes fetched, %llu mesh bytes\n",
              static_cast<long long>(snapshot->revision()), edit_s, static_cast<unsigned long long>(edit.datagrams),
              static_cast<unsigned long long>(edit.bytes),
              static_cast<unsigned long long>(client.stats().blob_bytes - blob_bytes_before),
              static_cast<unsigned long long>(edit.mesh_bytes));
  return 0;
}
