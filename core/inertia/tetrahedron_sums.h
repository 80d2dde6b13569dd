// The inner loop of integrate_solid: moments of the signed tetrahedra (apex, a, b, c) summed over
// every triangle of a mesh, in the mesh's own frame, about an apex near the mesh.
//
// Why it looks the way it does (issue 6: the kernel was half the speed of a plain loop):
// - No temporary arrays: corners are gathered by index straight from the positions (in the
//   glTF buffer itself when the mesh is read in place) and moved to the apex in registers; the
//   affine map is applied once to the ten sums afterwards.
// - Four triangles at a time in GCC/Clang vector types (portable: they lower to SSE2 on any
//   x86-64, NEON on ARM, scalar elsewhere), which also gives independent accumulators, so no
//   long chain of dependent additions limits the loop. mass_properties.cc also compiles the loop
//   for AVX and picks that copy at run time on processors that have it: no -march flag is
//   needed, and the binary still runs on any x86-64.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace rdtf::detail {

// Tetrahedron (0, a, b, c) with D = a.(b x c): volume D/6, first moment D(a+b+c)/24, second
// moment D/120 ((a+b+c)(a+b+c)^T + aa^T + bb^T + cc^T). The sums keep those integer multiples.
template <typename T>
struct TetrahedronSums {
  T six_volume{};
  T first24[3]{};
  T second120[6]{};  // xx yy zz xy yz zx
};

template <typename T>
struct Corner {
  T x, y, z;
};

template <typename T>
[[gnu::always_inline]] inline void add_tetrahedron(TetrahedronSums<T>& sums, const Corner<T>& a, const Corner<T>& b,
                            const Corner<T>& c) {
  const T D = a.x * (b.y * c.z - b.z * c.y) + a.y * (b.z * c.x - b.x * c.z) +
              a.z * (b.x * c.y - b.y * c.x);
  const T sx = a.x + b.x + c.x, sy = a.y + b.y + c.y, sz = a.z + b.z + c.z;
  sums.six_volume += D;
  sums.first24[0] += D * sx;
  sums.first24[1] += D * sy;
  sums.first24[2] += D * sz;
  sums.second120[0] += D * (sx * sx + a.x * a.x + b.x * b.x + c.x * c.x);
  sums.second120[1] += D * (sy * sy + a.y * a.y + b.y * b.y + c.y * c.y);
  sums.second120[2] += D * (sz * sz + a.z * a.z + b.z * b.z + c.z * c.z);
  sums.second120[3] += D * (sx * sy + a.x * a.y + b.x * b.y + c.x * c.y);
  sums.second120[4] += D * (sy * sz + a.y * a.z + b.y * b.z + c.y * c.z);
  sums.second120[5] += D * (sz * sx + a.z * a.x + b.z * b.x + c.z * c.x);
}

// Four lanes of doubles, one triangle per lane. Vectors are only ever passed by reference: by
// value, their ABI would depend on whether AVX is enabled.
using Lanes = double __attribute__((vector_size(4 * sizeof(double))));
constexpr std::size_t kLanes = 4;

using Pair = double __attribute__((vector_size(2 * sizeof(double))));

// Corner k of triangles t .. t + 3 of `view`, moved to the apex, one triangle per lane.
template <typename View>
[[gnu::always_inline]] inline void gather_corner(const View& view, std::size_t t, int k,
                                                 const Corner<double>& apex, Corner<Lanes>& out) {
  const std::uint32_t v0 = view.index(3 * t + k), v1 = view.index(3 * (t + 1) + k),
                      v2 = view.index(3 * (t + 2) + k), v3 = view.index(3 * (t + 3) + k);
  if constexpr (std::is_same_v<typename View::Coordinate, double>) {
    // x and y of each vertex in one 16-byte load, then two shuffles make the x and y lanes:
    // 8 loads for the 12 coordinates instead of 12, which the loop was bound by (the values,
    // and so every bit of the sums, are the same). z stays one load per vertex: a 32-byte load
    // of the whole vertex would read past the last vertex of the buffer.
    const Pair xy0 = view.template pair<Pair>(v0), xy1 = view.template pair<Pair>(v1),
               xy2 = view.template pair<Pair>(v2), xy3 = view.template pair<Pair>(v3);
    const Lanes a = __builtin_shufflevector(xy0, xy2, 0, 1, 2, 3);  // x0 y0 x2 y2
    const Lanes b = __builtin_shufflevector(xy1, xy3, 0, 1, 2, 3);  // x1 y1 x3 y3
    out.x = __builtin_shufflevector(a, b, 0, 4, 2, 6) - apex.x;
    out.y = __builtin_shufflevector(a, b, 1, 5, 3, 7) - apex.y;
  } else {
    // (Widening four floats in one vector conversion instead measured 20% slower.)
    out.x = Lanes{view.coordinate(v0, 0), view.coordinate(v1, 0), view.coordinate(v2, 0),
                  view.coordinate(v3, 0)} - apex.x;
    out.y = Lanes{view.coordinate(v0, 1), view.coordinate(v1, 1), view.coordinate(v2, 1),
                  view.coordinate(v3, 1)} - apex.y;
  }
  out.z = Lanes{view.coordinate(v0, 2), view.coordinate(v1, 2), view.coordinate(v2, 2),
                view.coordinate(v3, 2)} - apex.z;
}

// Adds the tetrahedra of every triangle of `view` (a internal::TypedView) about `apex` to
// `sums`. Corners are read by index straight from where the mesh lies (a glTF buffer's floats or
// a TriangleMesh's doubles) and converted to doubles exactly. Plain IEEE operations in a fixed
// order (no fused multiply-add: neither the baseline nor the AVX target has it): every build and
// every copy of the loop gives the same bits.
template <typename View>
[[gnu::always_inline]] inline void add_mesh(TetrahedronSums<double>& sums, const View& view,
                                            const Corner<double>& apex) {
  const std::size_t n = view.triangle_count;
  std::size_t i = 0;
  TetrahedronSums<Lanes> wide;
  for (; i + kLanes <= n; i += kLanes) {
    Corner<Lanes> a, b, c;
    gather_corner(view, i, 0, apex, a);
    gather_corner(view, i, 1, apex, b);
    gather_corner(view, i, 2, apex, c);
    add_tetrahedron(wide, a, b, c);
  }
  for (; i < n; ++i) {
    Corner<double> c[3];
    for (int k = 0; k < 3; ++k) {
      double p[3];
      view.vertex(view.index(3 * i + k), p);
      c[k] = {p[0] - apex.x, p[1] - apex.y, p[2] - apex.z};
    }
    add_tetrahedron(sums, c[0], c[1], c[2]);
  }
  for (std::size_t lane = 0; lane < kLanes; ++lane) {
    sums.six_volume += wide.six_volume[lane];
    for (int k = 0; k < 3; ++k) sums.first24[k] += wide.first24[k][lane];
    for (int k = 0; k < 6; ++k) sums.second120[k] += wide.second120[k][lane];
  }
}

}  // namespace rdtf::detail
