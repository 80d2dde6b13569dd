// Mass-properties kernel (volume, centroid, full tensor) against, in the same run: a streaming
// read of the same bytes (the memory-bandwidth bound), a plain scalar reference kernel, and ODE's
// dMassSetTrimesh. Counters: triangles/s ("items_per_second") and the relative difference of the
// results from the reference.
#include <benchmark/benchmark.h>
#include <ode/ode.h>

#include <cmath>
#include <map>
#include <span>

#include "rdtf/mass_properties.h"
#include "synthetic_models.h"

namespace {

using rdtf::TriangleMesh;

// Where the far spheres sit: 10 km away, where summing about the origin loses the inertia
// (facts.md), so the kernel must re-centre.
const Eigen::Vector3d kFar(6e3, -7e3, 4.5e3);

const TriangleMesh& sphere(std::size_t triangles, const Eigen::Vector3d& centre = Eigen::Vector3d::Zero()) {
  static std::map<std::pair<std::size_t, bool>, TriangleMesh> cache;
  const std::pair<std::size_t, bool> key{triangles, centre != Eigen::Vector3d::Zero()};
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, rdtf::bench::uv_sphere(triangles, 0.5, centre)).first;
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

// Relative differences from the reference (at the origin; `offset` moves its centroid):
// volume, centroid (against the sphere's radius) and the second moment about the centroid
// (largest entry difference against the largest entry).
void report_differences(benchmark::State& state, const rdtf::VolumeIntegrals& got,
                        const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) {
  const rdtf::VolumeIntegrals want = integrals_of(reference_kernel(sphere(static_cast<std::size_t>(state.range(0)))));
  state.counters["volume_rel_diff"] = std::abs(got.volume - want.volume) / want.volume;
  state.counters["centroid_rel_diff"] = (got.centroid - want.centroid - offset).norm() / 0.5;
  state.counters["inertia_rel_diff"] = (got.second_central - want.second_central).cwiseAbs().maxCoeff() /
                                       want.second_central.cwiseAbs().maxCoeff();
}

void run_rdtf_kernel(benchmark::State& state, const Eigen::Vector3d& centre) {
  const TriangleMesh& mesh = sphere(static_cast<std::size_t>(state.range(0)), centre);
  const std::span<const TriangleMesh> pieces(&mesh, 1);
  rdtf::VolumeIntegrals result;
  for (auto _ : state) {
    result = rdtf::integrate_solid(pieces, Eigen::Affine3d::Identity());
    benchmark::DoNotOptimize(result);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
  report_differences(state, result, centre);
}

void BM_RdtfKernel(benchmark::State& state) { run_rdtf_kernel(state, Eigen::Vector3d::Zero()); }

// The same sphere 10 km from the origin: compared with the reference's result at the origin.
void BM_RdtfKernelFar(benchmark::State& state) { run_rdtf_kernel(state, kFar); }

void BM_ScalarReference(benchmark::State& state) {
  const TriangleMesh& mesh = sphere(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    Reference r = reference_kernel(mesh);
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
}

// The plain reference on the far sphere: how much summing about the origin loses there.
void BM_ScalarReferenceFar(benchmark::State& state) {
  const TriangleMesh& mesh = sphere(static_cast<std::size_t>(state.range(0)), kFar);
  Reference r;
  for (auto _ : state) {
    r = reference_kernel(mesh);
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
  report_differences(state, integrals_of(r), kFar);
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
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
  dGeomDestroy(geom);
  dGeomTriMeshDataDestroy(data);
}

}  // namespace

BENCHMARK(BM_RdtfKernel)->Arg(300'000)->Arg(5'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RdtfKernelFar)->Arg(300'000)->Arg(5'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScalarReference)->Arg(300'000)->Arg(5'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScalarReferenceFar)->Arg(300'000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StreamingRead)->Arg(300'000)->Arg(5'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OdeTrimesh)->Arg(300'000)->Arg(5'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
