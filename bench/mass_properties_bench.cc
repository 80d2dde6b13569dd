// Mass-properties kernel (volume, centroid, full tensor) against, in the same run: a streaming
// read of the same bytes (the memory-bandwidth bound), a plain scalar reference kernel, and ODE's
// dMassSetTrimesh. Counters: triangles/s ("items_per_second") and the relative difference of the
// results from the reference.
#include <benchmark/benchmark.h>
#include <ode/ode.h>

#include <cmath>

#include "rdtf/mass_properties.h"
#include "synthetic_models.h"

namespace {

using rdtf::TriangleMesh;

const TriangleMesh& sphere(std::size_t triangles) {
  static std::map<std::size_t, TriangleMesh> cache;
  auto it = cache.find(triangles);
  if (it == cache.end()) it = cache.emplace(triangles, rdtf::bench::uv_sphere(triangles, 0.5)).first;
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

void BM_RdtfKernel(benchmark::State& state) {
  const TriangleMesh& mesh = sphere(static_cast<std::size_t>(state.range(0)));
  const std::vector<TriangleMesh> pieces{mesh};
  rdtf::VolumeIntegrals result;
  for (auto _ : state) {
    result = rdtf::integrate_solid(pieces, Eigen::Affine3d::Identity());
    benchmark::DoNotOptimize(result);
  }
  const Reference reference = reference_kernel(mesh);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
  state.counters["volume_rel_diff"] = std::abs(result.volume - reference.volume) / reference.volume;
}

void BM_ScalarReference(benchmark::State& state) {
  const TriangleMesh& mesh = sphere(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    Reference r = reference_kernel(mesh);
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
}

// Reads every index and every corner position once, as the kernel must: the bandwidth bound.
void BM_StreamingRead(benchmark::State& state) {
  const TriangleMesh& mesh = sphere(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    double sum = 0;
    for (const auto& t : mesh.triangles) {
      sum += mesh.positions[t[0]].x() + mesh.positions[t[1]].y() + mesh.positions[t[2]].z();
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
}

void BM_OdeTrimesh(benchmark::State& state) {
  const TriangleMesh& mesh = sphere(static_cast<std::size_t>(state.range(0)));
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
  const Reference reference = reference_kernel(mesh);
  state.counters["volume_rel_diff"] = std::abs(mass.mass - reference.volume) / reference.volume;
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
  dGeomDestroy(geom);
  dGeomTriMeshDataDestroy(data);
}

}  // namespace

BENCHMARK(BM_RdtfKernel)->Arg(300'000)->Arg(5'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScalarReference)->Arg(300'000)->Arg(5'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StreamingRead)->Arg(300'000)->Arg(5'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OdeTrimesh)->Arg(300'000)->Arg(5'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
