// End-to-end `rdtf convert` of a one-million-triangle .glb against the floor of reading the file
// and parsing it with tinygltf alone (images not decoded).
#include <benchmark/benchmark.h>
#include <tiny_gltf.h>

#include <fstream>

#include "rdtf/convert.h"
#include "rdtf/write.h"
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

void BM_TinygltfLoadFloor(benchmark::State& state) {
  const auto path = model_path();
  for (auto _ : state) {
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&no_images, nullptr);
    tinygltf::Model model;
    std::string error, warning;
    const bool ok = loader.LoadBinaryFromFile(&model, &error, &warning, path.string());
    if (!ok) state.SkipWithError(error.c_str());
    benchmark::DoNotOptimize(model);
  }
  state.counters["bytes"] = static_cast<double>(std::filesystem::file_size(path));
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

void BM_RdtfConvertNoWrite(benchmark::State& state) {
  const auto path = model_path();
  for (auto _ : state) {
    rdtf::Diagnostics diag;
    auto conversion = rdtf::convert_file(path, rdtf::ConvertOptions{}, diag);
    if (!conversion) state.SkipWithError("conversion failed");
    benchmark::DoNotOptimize(conversion);
  }
}

}  // namespace

BENCHMARK(BM_TinygltfLoadFloor)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfConvertNoWrite)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfConvertToGlb)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
