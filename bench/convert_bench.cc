// End-to-end `rdtf convert` of a one-million-triangle .glb against the floor of reading the file
// and parsing it with tinygltf alone (images not decoded), with the converter's stages timed
// alone on the same file, and the ratio the issue sets a goal for (convert / floor <= 1.5)
// printed at the end from this run's fastest repetitions.
//
//   convert_bench --benchmark_repetitions=5
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <tiny_gltf.h>

#include <cstdio>
#include <fstream>
#include <span>

#include "rdtf/convert.h"
#include "rdtf/geometry.h"
#include "rdtf/gltf.h"
#include "rdtf/json_text.h"
#include "rdtf/mass_properties.h"
#include "rdtf/mesh_checks.h"
#include "rdtf/write.h"
#include "side_by_side.h"
#include "synthetic_models.h"

namespace {

const std::filesystem::path& model_path() {
  static const std::filesystem::path path = [] {
    const auto folder = std::filesystem::temp_directory_path() / "rdtf-bench";
    std::filesystem::create_directories(folder);
    const auto file = folder / "sphere_1m.glb";
    const auto glb = rdtf::bench::mesh_glb(rdtf::bench::uv_sphere(1'000'000, 0.5));
    std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(glb.data()),
                                                static_cast<std::streamsize>(glb.size()));
    return file;
  }();
  return path;
}

bool no_images(tinygltf::Image*, const int, std::string*, std::string*, int, int,
               const unsigned char*, int, void*) {
  return true;
}

// Minor page faults (first touches of fresh memory) per iteration: the cost the floor and the
// converter both pay for new memory, which perf showed was a third of a conversion.
class PageFaults {
 public:
  PageFaults() : start_(count()) {}
  void report(benchmark::State& state) const {
    state.counters["page_faults"] = static_cast<double>(count() - start_) / static_cast<double>(state.iterations());
  }

 private:
  static long count() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_minflt;
  }
  long start_;
};

void BM_TinygltfLoadFloor(benchmark::State& state) {
  const auto path = model_path();
  const PageFaults faults;
  for (auto _ : state) {
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&no_images, nullptr);
    tinygltf::Model model;
    std::string error, warning;
    const bool ok = loader.LoadBinaryFromFile(&model, &error, &warning, path.string());
    if (!ok) state.SkipWithError(error.c_str());
    benchmark::DoNotOptimize(model);
  }
  faults.report(state);
  state.counters["bytes"] = static_cast<double>(std::filesystem::file_size(path));
}

// The part of the floor that is only reading the file into memory.
void BM_ReadFile(benchmark::State& state) {
  const auto path = model_path();
  const PageFaults faults;
  for (auto _ : state) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes(std::filesystem::file_size(path));
    in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    benchmark::DoNotOptimize(bytes.data());
  }
  faults.report(state);
}

// Stages of the converter alone: load (read, JSON, document checks, buffers, data checks)...
void BM_RdtfLoad(benchmark::State& state) {
  const auto path = model_path();
  const PageFaults faults;
  for (auto _ : state) {
    rdtf::Diagnostics diag;
    auto asset = rdtf::load_gltf(path, rdtf::LoadLimits{}, diag);
    if (!asset) state.SkipWithError("load failed");
    benchmark::DoNotOptimize(asset);
  }
  faults.report(state);
}

// ... and, on the loaded model's triangles read in place, the closed-surface check and the mass
// properties.
struct LoadedSphere {
  rdtf::GltfAsset asset;
  rdtf::TriangleMeshView view;
};

const LoadedSphere& loaded_sphere() {
  static const LoadedSphere sphere = [] {
    rdtf::Diagnostics diag;
    LoadedSphere loaded{*rdtf::load_gltf(model_path(), rdtf::LoadLimits{}, diag), {}};
    loaded.view = rdtf::read_primitive_in_place(loaded.asset, 0, 0, diag)->view();
    return loaded;
  }();
  return sphere;
}

void BM_RdtfSurfaceCheck(benchmark::State& state) {
  const auto& sphere = loaded_sphere();
  const PageFaults faults;
  for (auto _ : state) {
    auto topology = rdtf::analyze_surface(std::span<const rdtf::TriangleMeshView>(&sphere.view, 1));
    if (!topology.closed() || !topology.consistently_oriented()) state.SkipWithError("not closed");
    benchmark::DoNotOptimize(topology);
  }
  faults.report(state);
}

void BM_RdtfMassProperties(benchmark::State& state) {
  const auto& sphere = loaded_sphere();
  for (auto _ : state) {
    auto integrals = rdtf::integrate_solid(std::span<const rdtf::TriangleMeshView>(&sphere.view, 1),
                                           Eigen::Affine3d::Identity());
    benchmark::DoNotOptimize(integrals);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(sphere.view.triangle_count));
}

void BM_RdtfConvertNoWrite(benchmark::State& state) {
  const auto path = model_path();
  const PageFaults faults;
  for (auto _ : state) {
    rdtf::Diagnostics diag;
    auto conversion = rdtf::convert_file(path, rdtf::ConvertOptions{}, diag);
    if (!conversion) state.SkipWithError("conversion failed");
    benchmark::DoNotOptimize(conversion);
  }
  faults.report(state);
}

void BM_RdtfConvertToGlb(benchmark::State& state) {
  const auto path = model_path();
  const auto output = path.parent_path() / "sphere_1m.rdtf.glb";
  for (auto _ : state) {
    rdtf::Diagnostics diag;
    auto conversion = rdtf::convert_file(path, rdtf::ConvertOptions{}, diag);
    if (!conversion || !rdtf::write_rdtf(conversion->asset, output, rdtf::OutputFormat::kGlb, diag)) {
      state.SkipWithError("conversion failed");
    }
  }
}

void print_summary(const rdtf::bench::SideBySide& runs) {
  const auto& floor = runs.best("BM_TinygltfLoadFloor");
  const auto& convert = runs.best("BM_RdtfConvertNoWrite");
  std::printf("\nIssue 6, convert of a 1M-triangle GLB (%.1f MB) against the floor, fastest repetition "
              "of this run (load average at the end: %s)\n",
              floor.counters.count("bytes") ? floor.counters.at("bytes") / 1e6 : 0.0,
              rdtf::bench::load_average().c_str());
  const auto row = [&](const char* what, const char* name) {
    const auto& best = runs.best(name);
    if (!best.found()) return;
    std::printf("  %-58s %8.1f ms CPU %8.1f ms wall", what, best.cpu_seconds * 1e3, best.real_seconds * 1e3);
    if (floor.found()) {
      std::printf("   %5.2fx / %5.2fx floor", best.cpu_seconds / floor.cpu_seconds,
                  best.real_seconds / floor.real_seconds);
    }
    if (best.counters.count("page_faults")) std::printf("   %6.0f page faults", best.counters.at("page_faults"));
    std::printf("\n");
  };
  row("floor: read + tinygltf parse (images not decoded)", "BM_TinygltfLoadFloor");
  row("  of which reading the file (ifstream)", "BM_ReadFile");
  row("rdtf convert, no write", "BM_RdtfConvertNoWrite");
  row("  stage: load (read, JSON, checks, buffers, data checks)", "BM_RdtfLoad");
  row("  stage: closed-surface check", "BM_RdtfSurfaceCheck");
  row("  stage: mass properties (volume, centroid, tensor)", "BM_RdtfMassProperties");
  row("rdtf convert + write .glb", "BM_RdtfConvertToGlb");
  if (floor.found() && convert.found()) {
    const double ratio = convert.cpu_seconds / floor.cpu_seconds;
    std::printf("  convert / floor = %.2f (CPU), %.2f (wall); goal <= 1.5: %s\n", ratio,
                convert.real_seconds / floor.real_seconds, ratio <= 1.5 ? "met" : "NOT met");
  }
}

// An object of n keys ("TEXCOORD_0": 0, ...), as a hostile primitive's attributes: rdtf's parser
// against nlohmann's own ordered parse, which walks the keys read so far at each new one.
std::string object_of_keys(std::int64_t n) {
  std::string text = "{";
  for (std::int64_t i = 0; i < n; ++i) text += (i == 0 ? "\"TEXCOORD_" : ",\"TEXCOORD_") + std::to_string(i) + "\":0";
  return text + "}";
}

void BM_ParseJsonText(benchmark::State& state) {
  const std::string text = object_of_keys(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(rdtf::parse_json_text(text));
}

void BM_NlohmannOrderedParse(benchmark::State& state) {
  const std::string text = object_of_keys(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(rdtf::Json::parse(text));
}

}  // namespace

BENCHMARK(BM_ParseJsonText)->Arg(1000)->Arg(10000)->Arg(40000)->Arg(160000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_NlohmannOrderedParse)->Arg(1000)->Arg(10000)->Arg(40000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TinygltfLoadFloor)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadFile)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfConvertNoWrite)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfLoad)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfSurfaceCheck)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfMassProperties)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfConvertToGlb)->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  rdtf::bench::SideBySide runs;
  benchmark::RunSpecifiedBenchmarks(&runs);
  print_summary(runs);
  benchmark::Shutdown();
  return 0;
}
