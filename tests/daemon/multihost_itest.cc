// rdtfd on one host, `rdtf pull` on another (two_hosts.h: two network namespaces joined by a veth
// pair, LCM with ttl=1; the puller in a mount namespace where the daemon's folders are empty
// tmpfs mounts). What pull writes must be the daemon's output folder for the model, byte for
// byte: for a .glb model, for a .gltf + .bin model, and again after an edit.
//
// Loss: the link from A to B is shaped to 12 Mbit/s by a token bucket (tc tbf on A's end, a
// 5 ms queue; netem is not in this kernel) while rdtfd sends faster: chunks of at most 1,400
// bytes (max_chunk_bytes: one packet each, so a drop loses one chunk, not a 41-fragment 60 KB
// datagram) paced at 8 MB/s of receive-buffer cost (chunk_rate_bytes_per_s; docs/lcm.md charges
// size + size + 2 KiB, so about 1,650 chunks or 2.1 MB/s of payload a second). The shaper passes
// about 1,070 such packets a second: about a third of the chunks are dropped, in every round. The
// puller's socket also has a receive buffer of a few KiB (recv_buf_size=4096). Pull must still
// complete, by asking for the missing chunk ranges again. The bound: with a chunk loss p per
// round (re-sent ranges go at the same pace), N chunks need about log(N) / log(1 / p) + 1 rounds:
// 9 for the model here (about 6.8 MB, 5,200 chunks) at p = 0.35. Its bytes go N / (1 - p) times in
// all at 2.1 MB/s (5 s) plus 150 ms without chunks before each round (the back-off doubles to 2 s
// only when a round brings nothing): about 6.5 s. The description's own parts (its RDTF JSON in
// 1,400-byte chunks, the manifest parts) are lost at the same rate; what arrived is kept across
// republications, and each round costs a request that rdtfd answers at most once a second, at
// most 2 s apart (the back-off's cap): M parts need about log(M) / log(1 / p) + 1 such rounds.
// Measured on the shared 2-core machine (load 8-10): 20.3 s, 13 blob re-requests, 11 description
// requests. The test allows 120 s (a loaded machine or a sanitizer build; not a measurement). Do the same on a
// real network: keep chunk_rate_bytes_per_s under the link's rate, or a link that stays
// overloaded drops a fragment of nearly every 60 KB chunk (measured here: 18 of 2,995 chunks got
// through in 30 s at 40 Mbit/s against 49 Mbit/s sent).
#include <cmath>

#include "daemon/harness.h"
#include "support/harness/two_hosts.h"

namespace rdtf::itest {
namespace {

// A closed UV sphere of about `triangles` triangles (radius 0.1 m) as a .gltf with an external
// .bin: a model whose buffer takes many chunks.
GeneratedModel sphere_model(const std::string& name, int triangles, const std::string& bin_name) {
  const int rings = std::max(3, static_cast<int>(std::sqrt(triangles / 2.0)));
  const int segments = std::max(3, triangles / (2 * rings));
  const double r = 0.1;
  std::vector<std::array<float, 3>> vertices;
  vertices.push_back({0, static_cast<float>(r), 0});
  for (int i = 1; i < rings; ++i) {
    const double phi = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double theta = 2 * M_PI * j / segments;
      vertices.push_back({static_cast<float>(r * std::sin(phi) * std::cos(theta)), static_cast<float>(r * std::cos(phi)),
                          static_cast<float>(r * std::sin(phi) * std::sin(theta))});
    }
  }
  vertices.push_back({0, static_cast<float>(-r), 0});
  const auto ring = [&](int i, int j) { return static_cast<std::uint32_t>(1 + (i - 1) * segments + (j % segments)); };
  const auto bottom = static_cast<std::uint32_t>(vertices.size() - 1);
  std::vector<std::array<std::uint32_t, 3>> faces;
  for (int j = 0; j < segments; ++j) {
    faces.push_back({0, ring(1, j), ring(1, j + 1)});
    for (int i = 1; i + 1 < rings; ++i) {
      faces.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      faces.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
    faces.push_back({bottom, ring(rings - 1, j + 1), ring(rings - 1, j)});
  }
  // Outward winding whatever the order above: the normal must point away from the centre.
  for (auto& f : faces) {
    const auto& a = vertices[f[0]];
    const auto& b = vertices[f[1]];
    const auto& c = vertices[f[2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    if (n[0] * (a[0] + b[0] + c[0]) + n[1] * (a[1] + b[1] + c[1]) + n[2] * (a[2] + b[2] + c[2]) < 0) std::swap(f[1], f[2]);
  }
  std::string bin;
  for (const auto& p : vertices) bin.append(reinterpret_cast<const char*>(p.data()), 12);
  const std::size_t positions = bin.size();
  for (const auto& f : faces) bin.append(reinterpret_cast<const char*>(f.data()), 12);
  const Json document = {
      {"asset", {{"version", "2.0"}, {"generator", "rdtf itest sphere"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"name", name}, {"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", vertices.size()}, {"type", "VEC3"},
         {"min", {-r, -r, -r}}, {"max", {r, r, r}}},
        {{"bufferView", 1}, {"componentType", 5125}, {"count", 3 * faces.size()}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", positions}, {"target", 34962}},
        {{"buffer", 0}, {"byteOffset", positions}, {"byteLength", bin.size() - positions}, {"target", 34963}}}},
      {"buffers", {{{"byteLength", bin.size()}, {"uri", bin_name}}}}};
  GeneratedModel model;
  model.gltf = document.dump(1);
  model.bin = bin;
  model.bin_name = bin_name;
  model.links = 1;
  return model;
}

// Every file below `folder`, as relative path -> bytes, or the error (a folder that is not there).
std::map<std::string, std::string> files_of(const fs::path& folder) {
  if (!fs::is_directory(folder)) return {{"(missing)", folder.string()}};
  return snapshot(folder);
}

std::vector<std::string> pull_args(const std::string& model_id, const fs::path& dir, const std::string& url,
                                   double timeout = 30) {
  return {testing::cli_path(), "pull", model_id, "-o", dir.string(), "--lcm-url", url, "--timeout",
          std::to_string(timeout)};
}

// The daemon on host A, its LCM at ttl=1 (the harness's subscriber listens there too).
struct MultiHost {
  TwoHosts hosts;  // Before the session: its sockets join the group over the veth route.
  Session s;
  TempDir pulls;

  DaemonProcess& start() { return s.start(DaemonOptions().with("lcm_url", TwoHosts::kUrl)); }

  // `rdtf pull` on host B, where the daemon's folders are hidden; asserts exit 0.
  void pull(const std::string& model_id, const fs::path& dir, const std::string& url = TwoHosts::kUrl) {
    const auto run = hosts.on_b(pull_args(model_id, dir, url), {s.root.path()});
    ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
    std::printf("%s", run.out.c_str());
  }
};

TEST(MultiHost, PullReproducesTheDaemonsOutputOfAGltfAndAGlbModelAndAnEdit) {
  MultiHost m;
  copy_fixture(m.s.watch, "arm3");
  fs::copy_file(testing::data_dir() / "blender" / "arm3.glb", m.s.watch / "arm3.glb");
  m.start();
  ASSERT_TRUE(m.s.wait_revision("arm3.gltf", 1, fixture_hash("arm3")));
  ASSERT_TRUE(m.s.wait_revision("arm3.glb", 1, content_hash(read(m.s.watch / "arm3.glb"))));

  for (const std::string id : {"arm3.gltf", "arm3.glb"}) {
    SCOPED_TRACE(id);
    const fs::path dir = m.pulls / (id + "-r1");
    m.pull(id, dir);
    const auto pulled = files_of(dir);
    EXPECT_EQ(pulled, files_of(m.s.output / id));
    // The RDTF file, its buffer and the URDF at least (arm3's URDF has no meshes).
    EXPECT_GE(pulled.size(), 3u);
  }

  // An edit of one joint limit: revision 2, pulled again from host B.
  Json document = Json::parse(read(m.s.watch / "arm3.gltf"));
  for (auto& node : document["nodes"]) {
    if (node.value("name", "") == "shoulder") node["extras"]["rdtf_upper"] = 1.2;
  }
  write_by_rename(m.s.watch / "arm3.gltf", document.dump(1), ".arm3.gltf.tmp");
  const std::string edited = content_hash(read(m.s.watch / "arm3.gltf"), {read(m.s.watch / "arm3.bin")});
  ASSERT_TRUE(m.s.wait_revision("arm3.gltf", 2, edited));
  ASSERT_TRUE(m.s.wait_idle());
  const fs::path dir = m.pulls / "arm3.gltf-r2";
  m.pull("arm3.gltf", dir);
  EXPECT_EQ(files_of(dir), files_of(m.s.output / "arm3.gltf"));
  EXPECT_NE(files_of(dir), files_of(m.pulls / "arm3.gltf-r1"));
}

TEST(MultiHost, PullOfAModelNobodyServesExits2NamingTheModelsItSaw) {
  MultiHost m;
  copy_fixture(m.s.watch, "arm3");
  m.start();
  ASSERT_TRUE(m.s.wait_revision("arm3.gltf", 1, fixture_hash("arm3")));
  const fs::path dir = m.pulls / "nothing";
  const auto run = m.hosts.on_b(pull_args("arm9.gltf", dir, TwoHosts::kUrl, 1.5), {m.s.root.path()});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find("no model 'arm9.gltf' on the bus within 1.5 s; models seen: arm3.gltf"), std::string::npos)
      << run.err;
  EXPECT_FALSE(fs::exists(dir));
  // Nothing half-written beside it either.
  EXPECT_TRUE(fs::is_empty(m.pulls.path()));
}

TEST(MultiHost, PullThroughALossyLinkCompletesByAskingAgain) {
  MultiHost m;
  const GeneratedModel sphere = sphere_model("ball", 100000, "ball.bin");
  ASSERT_GT(sphere.bin.size(), 1'000'000u);
  write_model(m.s.watch, "ball.gltf", sphere);
  m.s.start(DaemonOptions().with("lcm_url", TwoHosts::kUrl).with("chunk_rate_bytes_per_s", 8e6).with("max_chunk_bytes", 1400));
  ASSERT_TRUE(m.s.wait_revision("ball.gltf", 1, content_hash(sphere), 60s));
  TwoHosts::shape_a_to_b("12mbit", "16kb", "5ms");
  const fs::path dir = m.pulls / "ball";
  const auto run = m.hosts.on_b(pull_args("ball.gltf", dir, std::string(TwoHosts::kUrl) + "&recv_buf_size=4096", 120),
                                {m.s.root.path()});
  ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
  std::printf("%s", run.out.c_str());
  EXPECT_EQ(files_of(dir), files_of(m.s.output / "ball.gltf"));
  // Chunks were dropped, and asked for again.
  const auto retries = run.out.find(" blob re-requests (");
  ASSERT_NE(retries, std::string::npos) << run.out;
  const auto from = run.out.rfind(' ', retries - 1);
  EXPECT_GT(std::stoi(run.out.substr(from + 1, retries - from - 1)), 0) << run.out;
}

}  // namespace
}  // namespace rdtf::itest
