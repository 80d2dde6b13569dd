// Chunk throughput of rdtfd's blob serving (docs/lcm.md, "Files and blobs") over real LCM (UDP
// multicast inside the program's own network namespace, see daemon_harness.h).
//
// BM_BlobThroughput/<max_chunk_bytes>: a model whose .bin is 64 MiB; each iteration asks for the
// whole blob on <prefix>/BLOB_REQUEST and waits until every chunk has arrived, asking again for
// the chunks still missing when nothing came for 300 ms. The time runs from the first request to
// the last chunk; MB/s and datagrams/s count the blob's bytes and chunks once. rdtfd's default
// pacing (chunk_rate_bytes_per_s 32e6, burst 128 KiB, counted in receive-buffer bytes per
// datagram) bounds the rate; the subscriber's socket has a 4 MiB receive buffer.
#include <benchmark/benchmark.h>

#include <cstring>
#include <map>
#include <set>
#include <string>

#include <rdtf/blob_chunk_t.hpp>
#include <rdtf/blob_request_t.hpp>
#include <rdtf/manifest_t.hpp>

#include "daemon_harness.h"

namespace {

using namespace rdtf::bench;
using namespace std::chrono_literals;

constexpr std::size_t kBlobBytes = 64u << 20;

// A one-box model whose buffer is the box (168 bytes) followed by `tail` bytes no accessor uses.
std::pair<std::string, std::string> box_with_tail(std::size_t tail) {
  std::string bin;
  auto put_float = [&](float f) { bin.append(reinterpret_cast<const char*>(&f), 4); };
  auto put_u16 = [&](std::uint16_t v) { bin.append(reinterpret_cast<const char*>(&v), 2); };
  for (int c = 0; c < 8; ++c) {
    put_float(c & 1 ? 0.1f : -0.1f);
    put_float(c & 2 ? 0.1f : -0.1f);
    put_float(c & 4 ? 0.1f : -0.1f);
  }
  const int quads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (const auto& q : quads) {
    for (int v : {q[0], q[1], q[2], q[0], q[2], q[3]}) put_u16(static_cast<std::uint16_t>(v));
  }
  std::string noise(tail, '\0');
  std::uint64_t x = 88172645463325252ull;
  for (std::size_t i = 0; i + 8 <= noise.size(); i += 8) {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    std::memcpy(&noise[i], &x, 8);
  }
  bin += noise;
  const Json document = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"name", "base"}, {"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"},
         {"min", {-0.1, -0.1, -0.1}}, {"max", {0.1, 0.1, 0.1}}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}, {"target", 34962}},
        {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 72}, {"target", 34963}}}},
      {"buffers", {{{"byteLength", bin.size()}, {"uri", "big.bin"}}}}};
  return {document.dump(1), bin};
}

struct Received {
  std::string sha;                     // The buffer's, from the MANIFEST.
  std::int32_t count = 0;
  std::set<std::int32_t> chunks;
  std::size_t datagrams = 0;           // Every chunk of the blob, repeats included.
  Clock::time_point last{};
};

void BM_BlobThroughput(benchmark::State& state) {
  const auto max_chunk_bytes = static_cast<int>(state.range(0));
  TempFolder root;
  const fs::path watch = root / "models", output = root / "out";
  fs::create_directories(watch);
  const auto [gltf, bin] = box_with_tail(kBlobBytes - 168);
  write_in_place(watch / "big.bin", bin);
  write_in_place(watch / "big.gltf", gltf);

  Received got;
  Subscriber subscriber("RDTF", [&](const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point at) {
    if (kind_of(channel) == "MANIFEST") {
      rdtf::manifest_t manifest;
      if (manifest.decode(buffer.data, 0, static_cast<int>(buffer.data_size)) < 0) return;
      for (const auto& file : manifest.files) {
        if (file.role == "buffer") got.sha = file.sha256;
      }
    } else if (channel == "RDTF/BLOB") {
      rdtf::blob_chunk_t chunk;
      if (chunk.decode(buffer.data, 0, static_cast<int>(buffer.data_size)) < 0 || chunk.sha256 != got.sha) return;
      got.count = chunk.count;
      got.chunks.insert(chunk.index);
      ++got.datagrams;
      got.last = at;
    }
  });
  Daemon daemon(watch, output, {{"validate", false}, {"simulate", false}, {"urdf", false}, {"max_chunk_bytes", max_chunk_bytes}});
  if (!subscriber.wait([&] { return !got.sha.empty(); }, 60s)) {
    state.SkipWithError(("no MANIFEST; rdtfd log:\n" + daemon.log()).c_str());
    return;
  }
  auto ask = [&](std::int32_t first, std::int32_t count) {
    rdtf::blob_request_t request;
    request.utime = 0;
    request.requester = "blob_bench";
    request.num_ranges = 1;
    request.sha256 = {got.sha};
    request.first_chunk = {first};
    request.num_chunks = {count};
    subscriber.publish("RDTF/BLOB_REQUEST", request);
  };
  std::size_t datagrams = 0, repeats = 0, count = 0;
  double seconds = 0;
  const UdpCounters udp_before = udp_counters();
  for (auto _ : state) {
    subscriber.locked([&] {
      got.chunks.clear();
      got.datagrams = 0;
      got.count = 0;
    });
    const Clock::time_point start = Clock::now();
    ask(0, -1);
    std::size_t heard = 0;
    for (;;) {
      bool done = false;
      subscriber.wait([&] { return done = got.count > 0 && got.chunks.size() == static_cast<std::size_t>(got.count); }, 300ms);
      if (done) break;
      bool progress = false;
      subscriber.locked([&] {
        progress = got.datagrams != heard;
        heard = got.datagrams;
      });
      if (progress) continue;
      if (Clock::now() - start > 120s) {
        state.SkipWithError("blob not complete after 120 s");
        return;
      }
      // Nothing for 300 ms: ask again for what is missing (every missing chunk, one range each run).
      std::vector<std::pair<std::int32_t, std::int32_t>> missing;
      subscriber.locked([&] {
        if (got.count == 0) missing.emplace_back(0, -1);
        for (std::int32_t i = 0; i < got.count;) {
          if (got.chunks.count(i) > 0) {
            ++i;
            continue;
          }
          std::int32_t end = i;
          while (end < got.count && got.chunks.count(end) == 0) ++end;
          missing.emplace_back(i, end - i);
          i = end;
        }
      });
      for (const auto& [first, n] : missing) ask(first, n);
      ++repeats;
    }
    subscriber.locked([&] {
      const double s = std::chrono::duration<double>(got.last - start).count();
      seconds += s;
      datagrams += got.datagrams;
      count = static_cast<std::size_t>(got.count);
      state.SetIterationTime(s);
    });
  }
  const UdpCounters udp_after = udp_counters();
  const double iterations = static_cast<double>(state.iterations());
  state.counters["MB_per_s"] = static_cast<double>(kBlobBytes) * iterations / seconds / 1e6;
  state.counters["datagrams_per_s"] = static_cast<double>(count) * iterations / seconds;
  state.counters["chunks"] = static_cast<double>(count);
  state.counters["datagrams_received"] = static_cast<double>(datagrams) / iterations;
  state.counters["re_requests"] = static_cast<double>(repeats) / iterations;
  state.counters["rcvbuf_errors"] = static_cast<double>(udp_after.receive_buffer_errors - udp_before.receive_buffer_errors);
  state.SetLabel("64 MiB blob, max_chunk_bytes " + std::to_string(max_chunk_bytes));
  daemon.stop();
}
BENCHMARK(BM_BlobThroughput)->Arg(60000)->Arg(8000)->Iterations(3)->UseManualTime()->Unit(benchmark::kSecond);

}  // namespace

int main(int argc, char** argv) {
  run_in_own_network_namespace(argc, argv);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
