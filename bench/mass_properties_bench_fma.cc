// An experiment, not used by rdtf: the kernel's loop (core/inertia/tetrahedron_sums.h) compiled
// for AVX2 with fused multiply-adds, to see what FMA would give against the streaming-read bound
// before anyone changes the kernel's dispatch and its bit-for-bit tests for it.
//
// This file alone is compiled with -ffp-contract=fast (bench/CMakeLists.txt); the AVX2 + FMA
// target is on the wrapper only, as core/inertia/mass_properties.cc does for AVX, so that inline
// functions this file emits out of line are baseline code like everyone else's copies.
#include "mass_properties_bench_fma.h"

#include "../core/geometry/typed_view.h"
#include "../core/inertia/tetrahedron_sums.h"

namespace rdtf::bench {
namespace {

template <typename View>
[[gnu::target("avx2,fma")]] void add_view_fma(detail::TetrahedronSums<double>& sums, const View& view,
                                              const detail::Corner<double>& apex) {
  detail::add_mesh(sums, view, apex);
}

}  // namespace

bool fma_available() { return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"); }

FmaSums fma_sums_about_origin(const TriangleMeshView& mesh) {
  detail::TetrahedronSums<double> sums;
  const detail::Corner<double> origin{0, 0, 0};
  internal::with_typed_view(mesh, [&](const auto& view) { add_view_fma(sums, view, origin); });
  FmaSums out;
  out.six_volume = sums.six_volume;
  for (int k = 0; k < 3; ++k) out.first24[k] = sums.first24[k];
  for (int k = 0; k < 6; ++k) out.second120[k] = sums.second120[k];
  return out;
}

}  // namespace rdtf::bench
