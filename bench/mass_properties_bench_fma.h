// The FMA experiment of mass_properties_bench (mass_properties_bench_fma.cc).
#pragma once

#include "rdtf/mass_properties.h"

namespace rdtf::bench {

// Whether this processor runs AVX2 and FMA.
bool fma_available();

// The kernel's sums (six times the volume, 24 times the first moment, 120 times the second:
// xx yy zz xy yz zx) of `mesh` about the origin, with fused multiply-adds.
struct FmaSums {
  double six_volume = 0;
  double first24[3] = {};
  double second120[6] = {};
};
FmaSums fma_sums_about_origin(const TriangleMeshView& mesh);

}  // namespace rdtf::bench
