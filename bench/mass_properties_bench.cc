// Mass-properties kernel (volume, centroid, full tensor) on closed UV spheres of 0.3M and 5M
// triangles against, in the same run: a streaming read of the same bytes (the memory bound), a
// plain scalar reference kernel, and ODE's dMassSetTrimesh. Counters: triangles/s
// ("items_per_second", per CPU second) and the relative differences of the results from the
// reference. At the end, the comparisons issue 6 asks for, from this run's fastest repetitions.
//
//   mass_properties_bench --benchmark_repetitions=5
#include <benchmark/benchmark.h>
#include <ode/ode.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "../core/inertia/winding_sample.h"
#include "mass_properties_bench_fma.h"
#include "rdtf/mass_properties.h"
#include "side_by_side.h"
#include "synthetic_models.h"

namespace {

using rdtf::TriangleMesh;
using rdtf::TriangleMeshView;

constexpr std::int64_t kSizes[] = {300'000, 5'000'000};

// Where the far spheres sit: 10 km away, where summing about the origin loses the inertia
// (facts.md), so the kernel must re-centre.
const Eigen::Vector3d kFar(6e3, -7e3, 4.5e3);

enum class Storage { kDouble, kFloat };

// Each coordinate rounded to float, through float memory. g++ 12.2 at -O2 compiles the direct
// round trip of two neighbouring doubles (p[0] = float(p[0]); p[1] = float(p[1]); likewise
// p.cast<float>().cast<double>()) into nothing: its SLP vectoriser drops the conversion pair.
// The floats are therefore stored, widened in a second pass, and checked on their bits (a
// float's double has its low 29 mantissa bits zero).
void round_to_float(std::vector<Eigen::Vector3d>& positions) {
  std::vector<float> floats(3 * positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v) {
    for (int c = 0; c < 3; ++c) floats[3 * v + c] = static_cast<float>(positions[v][c]);
  }
  for (std::size_t v = 0; v < positions.size(); ++v) {
    for (int c = 0; c < 3; ++c) {
      positions[v][c] = floats[3 * v + c];
      std::uint64_t bits;
      std::memcpy(&bits, &positions[v][c], sizeof(bits));
      if ((bits & ((std::uint64_t{1} << 29) - 1)) != 0) {
        std::fprintf(stderr, "round_to_float: vertex %zu was not rounded\n", v);
        std::abort();
      }
    }
  }
}

// The spheres, made once: `kFloat` is the same sphere with its positions rounded to float (as a
// glTF file holds them), kept as doubles so that the reference runs on exactly those values.
const TriangleMesh& sphere(std::int64_t triangles, bool far = false, Storage storage = Storage::kDouble) {
  static std::map<std::tuple<std::int64_t, bool, Storage>, TriangleMesh> cache;
  const auto key = std::make_tuple(triangles, far, storage);
  auto it = cache.find(key);
  if (it == cache.end()) {
    TriangleMesh mesh = rdtf::bench::uv_sphere(static_cast<std::size_t>(triangles), 0.5,
                                               far ? kFar : Eigen::Vector3d::Zero());
    if (storage == Storage::kFloat) round_to_float(mesh.positions);
    it = cache.emplace(key, std::move(mesh)).first;
  }
  return it->second;
}

// The float sphere as a glTF buffer holds it: packed float32 positions and uint32 indices.
struct FloatBuffers {
  std::vector<float> positions;
  std::vector<std::uint32_t> indices;
  TriangleMeshView view() const {
    TriangleMeshView v;
    v.positions = reinterpret_cast<const std::uint8_t*>(positions.data());
    v.position_stride = 3 * sizeof(float);
    v.vertex_count = positions.size() / 3;
    v.position_type = TriangleMeshView::Positions::kFloat32;
    v.indices = reinterpret_cast<const std::uint8_t*>(indices.data());
    v.index_stride = sizeof(std::uint32_t);
    v.triangle_count = indices.size() / 3;
    v.index_type = TriangleMeshView::Indices::kUint32;
    return v;
  }
};

const FloatBuffers& float_buffers(std::int64_t triangles) {
  static std::map<std::int64_t, FloatBuffers> cache;
  auto it = cache.find(triangles);
  if (it == cache.end()) {
    const TriangleMesh& mesh = sphere(triangles, false, Storage::kFloat);
    FloatBuffers buffers;
    for (const auto& p : mesh.positions) {
      buffers.positions.insert(buffers.positions.end(),
                               {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
    }
    for (const auto& t : mesh.triangles) buffers.indices.insert(buffers.indices.end(), {t[0], t[1], t[2]});
    it = cache.emplace(triangles, std::move(buffers)).first;
  }
  return it->second;
}

// The plain kernel: sums about the origin, no re-centring, scalar doubles.
struct Reference {
  double volume = 0, cx = 0, cy = 0, cz = 0, xx = 0, yy = 0, zz = 0, xy = 0, yz = 0, zx = 0;
};

Reference reference_kernel(const TriangleMesh& mesh) {
  Reference r;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.positions[t[0]];
    const Eigen::Vector3d& b = mesh.positions[t[1]];
    const Eigen::Vector3d& c = mesh.positions[t[2]];
    const double d = a.x() * (b.y() * c.z() - b.z() * c.y()) - a.y() * (b.x() * c.z() - b.z() * c.x()) +
                     a.z() * (b.x() * c.y() - b.y() * c.x());
    const double sx = a.x() + b.x() + c.x(), sy = a.y() + b.y() + c.y(), sz = a.z() + b.z() + c.z();
    r.volume += d;
    r.cx += d * sx;
    r.cy += d * sy;
    r.cz += d * sz;
    r.xx += d * (sx * sx + a.x() * a.x() + b.x() * b.x() + c.x() * c.x());
    r.yy += d * (sy * sy + a.y() * a.y() + b.y() * b.y() + c.y() * c.y());
    r.zz += d * (sz * sz + a.z() * a.z() + b.z() * b.z() + c.z() * c.z());
    r.xy += d * (sx * sy + a.x() * a.y() + b.x() * b.y() + c.x() * c.y());
    r.yz += d * (sy * sz + a.y() * a.z() + b.y() * b.z() + c.y() * c.z());
    r.zx += d * (sz * sx + a.z() * a.x() + b.z() * b.x() + c.z() * c.x());
  }
  r.volume /= 6;
  return r;
}

// The reference's sums as volume, centroid and second moment about the centroid.
rdtf::VolumeIntegrals integrals_of(const Reference& r) {
  rdtf::VolumeIntegrals v;
  v.volume = r.volume;
  v.centroid = Eigen::Vector3d(r.cx, r.cy, r.cz) / 24.0 / r.volume;
  Eigen::Matrix3d second;
  second << r.xx, r.xy, r.zx, r.xy, r.yy, r.yz, r.zx, r.yz, r.zz;
  v.second_central = second / 120.0 - r.volume * v.centroid * v.centroid.transpose();
  return v;
}

// Relative differences from the reference on the sphere at the origin with the same storage
// (`offset` moves its centroid): volume, centroid (against the sphere's radius) and the second
// moment about the centroid (largest entry difference against the largest entry).
void report_differences(benchmark::State& state, const rdtf::VolumeIntegrals& got,
                        const Eigen::Vector3d& offset = Eigen::Vector3d::Zero(),
                        Storage storage = Storage::kDouble) {
  const rdtf::VolumeIntegrals want = integrals_of(reference_kernel(sphere(state.range(0), false, storage)));
  state.counters["volume_rel_diff"] = std::abs(got.volume - want.volume) / want.volume;
  state.counters["centroid_rel_diff"] = (got.centroid - want.centroid - offset).norm() / 0.5;
  state.counters["inertia_rel_diff"] = (got.second_central - want.second_central).cwiseAbs().maxCoeff() /
                                       want.second_central.cwiseAbs().maxCoeff();
}

void set_triangles(benchmark::State& state, std::size_t triangles) {
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(triangles));
}

void run_rdtf_kernel(benchmark::State& state, bool far, rdtf::detail::KernelIsa isa) {
  if (!rdtf::detail::kernel_available(isa)) {
    state.SkipWithError("this processor has no AVX");
    return;
  }
  const TriangleMesh& mesh = sphere(state.range(0), far);
  const TriangleMeshView view = TriangleMeshView::of(mesh);
  rdtf::VolumeIntegrals result;
  for (auto _ : state) {
    result = rdtf::detail::integrate_solid(std::span<const TriangleMeshView>(&view, 1),
                                           Eigen::Affine3d::Identity(), isa);
    benchmark::DoNotOptimize(result);
  }
  set_triangles(state, mesh.triangles.size());
  report_differences(state, result, far ? kFar : Eigen::Vector3d::Zero());
}

// rdtf's kernel as the converter runs it (the copy the processor picks: AVX where it has it).
void BM_RdtfKernel(benchmark::State& state) { run_rdtf_kernel(state, false, rdtf::detail::KernelIsa::kAuto); }

// Each compiled copy forced, to time both and to show they agree.
void BM_RdtfKernelBaseline(benchmark::State& state) {
  run_rdtf_kernel(state, false, rdtf::detail::KernelIsa::kBaseline);
}
void BM_RdtfKernelAvx(benchmark::State& state) { run_rdtf_kernel(state, false, rdtf::detail::KernelIsa::kAvx); }

// The same sphere 10 km from the origin: compared with the reference's result at the origin.
void BM_RdtfKernelFar(benchmark::State& state) { run_rdtf_kernel(state, true, rdtf::detail::KernelIsa::kAuto); }

// As the converter reads a GLB: float positions and uint32 indices in place (compared with the
// reference on the same float-rounded positions).
void BM_RdtfKernelFloatInPlace(benchmark::State& state) {
  const TriangleMeshView view = float_buffers(state.range(0)).view();
  rdtf::VolumeIntegrals result;
  for (auto _ : state) {
    result = rdtf::integrate_solid(std::span<const TriangleMeshView>(&view, 1), Eigen::Affine3d::Identity());
    benchmark::DoNotOptimize(result);
  }
  set_triangles(state, view.triangle_count);
  report_differences(state, result, Eigen::Vector3d::Zero(), Storage::kFloat);
}

// The overlap check's winding sample (core/inertia/winding_sample.h, LINK_PARTS_OVERLAP) on the
// same float sphere read in place: what the check adds to a link of this many triangles, beside
// the kernel that integrates it.
void BM_WindingSample(benchmark::State& state) {
  const TriangleMeshView view = float_buffers(state.range(0)).view();
  const rdtf::internal::PlacedSolid solid{std::span<const TriangleMeshView>(&view, 1), Eigen::Affine3d::Identity(), 1};
  rdtf::internal::WindingSample result;
  for (auto _ : state) {
    result = rdtf::internal::sample_winding(std::span<const rdtf::internal::PlacedSolid>(&solid, 1));
    benchmark::DoNotOptimize(result);
  }
  set_triangles(state, view.triangle_count);
  state.counters["excess_m3"] = result.excess;  // 0: a sphere overlaps nothing
  state.counters["inconsistent_rays"] = static_cast<double>(result.inconsistent_rays);
}

// What fused multiply-adds would give (mass_properties_bench_fma.cc; rdtf does not run it): the
// kernel's loop compiled for AVX2 + FMA, about the origin (the sphere's centre), timed, and its
// differences from the reference reported like the others'.
void BM_RdtfKernelFmaExperiment(benchmark::State& state) {
  if (!rdtf::bench::fma_available()) {
    state.SkipWithError("this processor has no AVX2 + FMA");
    return;
  }
  const TriangleMesh& mesh = sphere(state.range(0));
  const TriangleMeshView view = TriangleMeshView::of(mesh);
  rdtf::bench::FmaSums sums;
  for (auto _ : state) {
    sums = rdtf::bench::fma_sums_about_origin(view);
    benchmark::DoNotOptimize(sums);
  }
  set_triangles(state, mesh.triangles.size());
  Reference r;
  r.volume = sums.six_volume / 6;
  r.cx = sums.first24[0], r.cy = sums.first24[1], r.cz = sums.first24[2];
  r.xx = sums.second120[0], r.yy = sums.second120[1], r.zz = sums.second120[2];
  r.xy = sums.second120[3], r.yz = sums.second120[4], r.zx = sums.second120[5];
  report_differences(state, integrals_of(r));
}

void BM_ScalarReference(benchmark::State& state) {
  const TriangleMesh& mesh = sphere(state.range(0));
  for (auto _ : state) {
    Reference r = reference_kernel(mesh);
    benchmark::DoNotOptimize(r);
  }
  set_triangles(state, mesh.triangles.size());
}

// The plain reference on the far sphere: how much summing about the origin loses there.
void BM_ScalarReferenceFar(benchmark::State& state) {
  const TriangleMesh& mesh = sphere(state.range(0), true);
  Reference r;
  for (auto _ : state) {
    r = reference_kernel(mesh);
    benchmark::DoNotOptimize(r);
  }
  set_triangles(state, mesh.triangles.size());
  report_differences(state, integrals_of(r), kFar);
}

// Reads every index and all three coordinates of every corner, by index as the kernel must,
// and does as little as possible with them (XOR into independent accumulators, one-cycle
// operations with no long dependency chain): the cost of touching the kernel's bytes, its bound.
void BM_StreamingRead(benchmark::State& state) {
  const TriangleMesh& mesh = sphere(state.range(0));
  const auto* p = reinterpret_cast<const std::uint64_t*>(mesh.positions.data());
  for (auto _ : state) {
    std::uint64_t x = 0, y = 0, z = 0;
    for (const auto& t : mesh.triangles) {
      for (const std::uint32_t v : t) {
        x ^= p[3 * std::size_t{v}];
        y ^= p[3 * std::size_t{v} + 1];
        z ^= p[3 * std::size_t{v} + 2];
      }
    }
    benchmark::DoNotOptimize(x);
    benchmark::DoNotOptimize(y);
    benchmark::DoNotOptimize(z);
  }
  set_triangles(state, mesh.triangles.size());
}

void BM_OdeTrimesh(benchmark::State& state) {
  const TriangleMesh& mesh = sphere(state.range(0));
  dInitODE2(0);
  std::vector<dReal> vertices;
  for (const auto& p : mesh.positions) vertices.insert(vertices.end(), {p.x(), p.y(), p.z()});
  std::vector<dTriIndex> indices;
  for (const auto& t : mesh.triangles) indices.insert(indices.end(), {t[0], t[1], t[2]});
  dTriMeshDataID data = dGeomTriMeshDataCreate();
  dGeomTriMeshDataBuildDouble(data, vertices.data(), 3 * sizeof(dReal), static_cast<int>(mesh.positions.size()),
                              indices.data(), static_cast<int>(indices.size()), 3 * sizeof(dTriIndex));
  dGeomID geom = dCreateTriMesh(nullptr, data, nullptr, nullptr, nullptr);
  dMass mass;
  for (auto _ : state) {
    dMassSetTrimesh(&mass, 1.0, geom);
    benchmark::DoNotOptimize(mass);
  }
  // Density 1: mass is the volume; ODE's I is about the centroid here (a sphere at the origin):
  // second moment about the centroid C = tr(I)/2 1 - I.
  rdtf::VolumeIntegrals ode;
  ode.volume = mass.mass;
  ode.centroid = Eigen::Vector3d(mass.c[0], mass.c[1], mass.c[2]);
  Eigen::Matrix3d I;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) I(r, c) = mass.I[r * 4 + c];
  ode.second_central = 0.5 * I.trace() * Eigen::Matrix3d::Identity() - I;
  report_differences(state, ode);
  set_triangles(state, mesh.triangles.size());
  dGeomDestroy(geom);
  dGeomTriMeshDataDestroy(data);
}

void print_summary(const rdtf::bench::SideBySide& runs) {
  std::printf("\nIssue 6, mass-properties kernel side by side, fastest repetition of this run "
              "(M triangles/s per CPU second | per wall second; load average at the end: %s)\n",
              rdtf::bench::load_average().c_str());
  for (const std::int64_t size : kSizes) {
    const std::string arg = "/" + std::to_string(size);
    const double triangles = static_cast<double>(sphere(size).triangles.size());
    const auto rate = [&](const std::string& name) {
      const auto& best = runs.best(name + arg);
      return best.found() ? std::pair{triangles / best.cpu_seconds / 1e6, triangles / best.real_seconds / 1e6}
                          : std::pair{0.0, 0.0};
    };
    std::printf("  %.2fM triangles\n", triangles / 1e6);
    const auto kernel = rate("BM_RdtfKernel");
    const auto line = [&](const char* what, const std::string& name) {
      const auto r = rate(name);
      if (r.first == 0) return;
      std::printf("    %-52s %7.1f | %7.1f M tri/s", what, r.first, r.second);
      if (kernel.first > 0 && name != "BM_RdtfKernel") {
        std::printf("   rdtf kernel is %5.2fx | %5.2fx this", kernel.first / r.first, kernel.second / r.second);
      }
      const auto& best = runs.best(name + arg);
      if (best.counters.count("volume_rel_diff")) {
        std::printf("   vs reference: volume %.1e, centroid %.1e, inertia %.1e", best.counters.at("volume_rel_diff"),
                    best.counters.at("centroid_rel_diff"), best.counters.at("inertia_rel_diff"));
      }
      std::printf("\n");
    };
    line("rdtf kernel (re-centred; AVX copy where available)", "BM_RdtfKernel");
    line("rdtf kernel, baseline (SSE2) copy forced", "BM_RdtfKernelBaseline");
    line("rdtf kernel, AVX copy forced", "BM_RdtfKernelAvx");
    line("rdtf kernel, sphere 10 km from the origin", "BM_RdtfKernelFar");
    line("rdtf kernel, float32 + uint32 read in place (GLB)", "BM_RdtfKernelFloatInPlace");
    line("streaming read of the same bytes (memory bound)", "BM_StreamingRead");
    line("winding sample of the overlap check, float32 in place", "BM_WindingSample");
    line("kernel with FMA (AVX2 + FMA; experiment, not used)", "BM_RdtfKernelFmaExperiment");
    line("plain scalar reference (about the origin)", "BM_ScalarReference");
    line("plain scalar reference, 10 km away", "BM_ScalarReferenceFar");
    line("ODE dMassSetTrimesh", "BM_OdeTrimesh");
    std::printf("    goal >= 150 M tri/s per core: %s\n", kernel.first >= 150 ? "met" : "NOT met");
  }
}

}  // namespace

BENCHMARK(BM_RdtfKernel)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfKernelBaseline)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfKernelAvx)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfKernelFar)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfKernelFloatInPlace)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StreamingRead)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WindingSample)->Arg(1000)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfKernelFmaExperiment)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScalarReference)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScalarReferenceFar)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OdeTrimesh)->Arg(kSizes[0])->Arg(kSizes[1])->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  rdtf::bench::SideBySide runs;
  benchmark::RunSpecifiedBenchmarks(&runs);
  print_summary(runs);
  benchmark::Shutdown();
  return 0;
}
