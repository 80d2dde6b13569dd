#include "winding_sample.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <utility>

#include "../geometry/typed_view.h"

namespace rdtf::internal {
namespace {

// The rays sit at these fractions of their cells, not at the centres: models are drawn on round
// coordinates (a box edge at 0.25 m), and a ray through an edge or a vertex is the one case the
// tie rule below must settle; irrational offsets make it rare.
constexpr double kFractionY = 0.41421356237309503;  // sqrt(2) - 1
constexpr double kFractionZ = 0.73205080756887719;  // sqrt(3) - 1

// Past this many crossings the sample gives up (an estimate is not worth more memory: 8 bytes
// each, so 32 MB). A closed solid is crossed twice per layer a ray meets; 16,384 rays through
// 100 layers of parts stay well below it.
constexpr std::size_t kMaxCrossings = std::size_t{4} << 20;

struct Grid {
  double y0 = 0, z0 = 0, hy = 0, hz = 0;
  double per_hy = 0, per_hz = 0;  // 1 / hy, 1 / hz
  std::size_t ny = 0, nz = 0;
  double y(std::size_t i) const { return y0 + (static_cast<double>(i) + kFractionY) * hy; }
  double z(std::size_t j) const { return z0 + (static_cast<double>(j) + kFractionZ) * hz; }
};

struct Crossing {
  std::uint32_t ray;
  float x;           // Along the ray, in the link frame.
  std::int32_t tag;  // solid * 2 + (1 where the ray enters the solid, 0 where it leaves)
};

// The side of the point q on which the directed edge p -> r passes, in the (y, z) plane, never 0:
// the edge is evaluated from its lexicographically smaller end, so both triangles that share it
// get opposite signs bit for bit, and an exact 0 is settled as if q were moved by (e, e^2) for a
// vanishing e. A ray through an edge of a closed surface thus crosses exactly one of its two
// triangles. `value` gets the edge function itself (the barycentric weight of the third corner).
int edge_side(const double p[3], const double r[3], double qy, double qz, double& value) {
  const bool swapped = r[1] < p[1] || (r[1] == p[1] && r[2] < p[2]);
  const double* a = swapped ? r : p;
  const double* b = swapped ? p : r;
  const double e = (b[1] - a[1]) * (qz - a[2]) - (b[2] - a[2]) * (qy - a[1]);
  int side;
  if (e != 0) {
    side = e > 0 ? 1 : -1;
  } else if (b[2] != a[2]) {
    side = b[2] > a[2] ? -1 : 1;
  } else {
    side = b[1] > a[1] ? 1 : -1;
  }
  value = swapped ? -e : e;
  return swapped ? -side : side;
}

// A box around the solids in L: each piece's box in its own frame, its corners placed. (Larger
// than the placed vertices' box for a turned piece, which only spreads the rays a little wider,
// and a pass of comparisons instead of a transform per vertex.)
void bound(std::span<const PlacedSolid> solids, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  lo.setConstant(kInf);
  hi.setConstant(-kInf);
  for (const PlacedSolid& solid : solids) {
    for (const TriangleMeshView& piece : solid.pieces) {
      Eigen::Vector3d lo_M = Eigen::Vector3d::Constant(kInf), hi_M = Eigen::Vector3d::Constant(-kInf);
      with_typed_view(piece, [&](const auto& view) {
        for (std::size_t v = 0; v < view.vertex_count; ++v) {
          Eigen::Vector3d p_M;
          view.vertex(static_cast<std::uint32_t>(v), p_M.data());
          lo_M = lo_M.cwiseMin(p_M);
          hi_M = hi_M.cwiseMax(p_M);
        }
      });
      if (!(lo_M.array() <= hi_M.array()).all()) continue;  // no vertices
      for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d p_M((corner & 1) ? hi_M.x() : lo_M.x(), (corner & 2) ? hi_M.y() : lo_M.y(),
                                  (corner & 4) ? hi_M.z() : lo_M.z());
        const Eigen::Vector3d p_L = solid.X_LM * p_M;
        lo = lo.cwiseMin(p_L);
        hi = hi.cwiseMax(p_L);
      }
    }
  }
}

// Where a coordinate lies among the rays of one axis, `u` = (coordinate - origin) / h - fraction
// (ray k at u = k), doubled so that it is an integer: 2k on ray k exactly, 2k + 1 strictly between
// rays k and k + 1. Clamped to just past the grid's ends; not a number counts as before them.
std::int32_t doubled_place(double u, std::size_t n) {
  const double top = static_cast<double>(n);
  if (!(u >= -1)) return -2;
  if (u > top) return static_cast<std::int32_t>(2 * n);
  const double k = std::floor(u);
  return 2 * static_cast<std::int32_t>(k) + (u != k ? 1 : 0);
}

// The rays (clamped to the grid) whose doubled places lie in [lo, hi]; empty when first > last.
std::pair<std::ptrdiff_t, std::ptrdiff_t> rays_between(std::int32_t lo, std::int32_t hi, std::size_t n) {
  // ceil(lo / 2) and floor(hi / 2), with arithmetic shifts (exact for negative values too).
  const std::ptrdiff_t first = std::max<std::ptrdiff_t>((lo + 1) >> 1, 0);
  const std::ptrdiff_t last = std::min<std::ptrdiff_t>(hi >> 1, static_cast<std::ptrdiff_t>(n) - 1);
  return {first, last};
}

// Adds the crossings of one solid's triangles with the grid's rays; false past kMaxCrossings.
// Each vertex is placed among the rays once (most are shared by six triangles), so that a
// triangle between two rays, as most of a large mesh's are, is passed over with integer
// comparisons; only the others are placed in full and tested edge by edge.
bool add_crossings(const PlacedSolid& solid, std::int32_t index, const Grid& grid, std::vector<Crossing>& out,
                   std::vector<std::array<std::int32_t, 2>>& places) {
  const Eigen::Matrix3d L = solid.X_LM.linear();
  const Eigen::Vector3d t = solid.X_LM.translation();
  // A mirroring placement turns the winding over, as an inside-out mesh does.
  const int orientation = solid.orientation * (L.determinant() < 0 ? -1 : 1);
  bool within = true;
  for (const TriangleMeshView& piece : solid.pieces) {
    if (!within) break;
    with_typed_view(piece, [&](const auto& view) {
      places.resize(view.vertex_count);
      for (std::size_t v = 0; v < view.vertex_count; ++v) {
        double p[3];
        view.vertex(static_cast<std::uint32_t>(v), p);
        const double y = L(1, 0) * p[0] + L(1, 1) * p[1] + L(1, 2) * p[2] + t[1];
        const double z = L(2, 0) * p[0] + L(2, 1) * p[1] + L(2, 2) * p[2] + t[2];
        places[v] = {doubled_place((y - grid.y0) * grid.per_hy - kFractionY, grid.ny),
                     doubled_place((z - grid.z0) * grid.per_hz - kFractionZ, grid.nz)};
      }
      double c[3][3];
      for (std::size_t tri = 0; tri < view.triangle_count && within; ++tri) {
        const std::uint32_t v0 = view.index(3 * tri), v1 = view.index(3 * tri + 1), v2 = view.index(3 * tri + 2);
        if (v0 >= view.vertex_count || v1 >= view.vertex_count || v2 >= view.vertex_count) continue;
        const auto& a = places[v0];
        const auto& b = places[v1];
        const auto& d = places[v2];
        const auto [i_first, i_last] =
            rays_between(std::min({a[0], b[0], d[0]}), std::max({a[0], b[0], d[0]}), grid.ny);
        if (i_first > i_last) continue;
        const auto [j_first, j_last] =
            rays_between(std::min({a[1], b[1], d[1]}), std::max({a[1], b[1], d[1]}), grid.nz);
        if (j_first > j_last) continue;
        const std::uint32_t corners[3] = {v0, v1, v2};
        for (int k = 0; k < 3; ++k) {
          double p[3];
          view.vertex(corners[k], p);
          for (int r = 0; r < 3; ++r) c[k][r] = L(r, 0) * p[0] + L(r, 1) * p[1] + L(r, 2) * p[2] + t[r];
        }
        // A corner that is not a finite number (the loader refuses them; this never trusts it) has
        // no place along a ray, and a NaN would break the sort below.
        bool finite = true;
        for (int k = 0; k < 3; ++k) finite = finite && std::isfinite(c[k][0] + c[k][1] + c[k][2]);
        if (!finite) continue;
        // Twice the triangle's area seen along x: the x component of its normal (b - a) x (c - a).
        const double area2 = (c[1][1] - c[0][1]) * (c[2][2] - c[0][2]) - (c[1][2] - c[0][2]) * (c[2][1] - c[0][1]);
        if (area2 == 0) continue;  // Edge on: no ray passes through it.
        const int facing = area2 > 0 ? 1 : -1;
        // A ray along +x enters a solid through a face whose outward normal points against it.
        const std::int32_t enters = (area2 < 0) == (orientation > 0) ? 1 : 0;
        for (std::ptrdiff_t i = i_first; i <= i_last; ++i) {
          const double qy = grid.y(static_cast<std::size_t>(i));
          for (std::ptrdiff_t j = j_first; j <= j_last; ++j) {
            const double qz = grid.z(static_cast<std::size_t>(j));
            double w_c, w_a, w_b;
            if (edge_side(c[0], c[1], qy, qz, w_c) != facing || edge_side(c[1], c[2], qy, qz, w_a) != facing ||
                edge_side(c[2], c[0], qy, qz, w_b) != facing) {
              continue;
            }
            const double sum = w_a + w_b + w_c;
            const double x = sum != 0 ? (w_a * c[0][0] + w_b * c[1][0] + w_c * c[2][0]) / sum
                                      : (c[0][0] + c[1][0] + c[2][0]) / 3;
            if (out.size() == kMaxCrossings) {
              within = false;
              return;
            }
            out.push_back({static_cast<std::uint32_t>(static_cast<std::size_t>(i) * grid.nz + static_cast<std::size_t>(j)),
                           static_cast<float>(x), index * 2 + enters});
          }
        }
      }
    });
  }
  return within;
}

}  // namespace

WindingSample sample_winding(std::span<const PlacedSolid> solids, std::size_t rays) {
  WindingSample result;
  if (solids.empty() || rays == 0) return result;
  Eigen::Vector3d lo, hi;
  bound(solids, lo, hi);
  const double extent_y = hi.y() - lo.y(), extent_z = hi.z() - lo.z();
  if (!(extent_y > 0) || !(extent_z > 0) || !std::isfinite(extent_y) || !std::isfinite(extent_z)) return result;

  // Cells as near square as the box allows, about `rays` of them.
  Grid grid;
  const double n = static_cast<double>(rays);
  grid.ny = static_cast<std::size_t>(std::clamp(std::round(std::sqrt(n * extent_y / extent_z)), 1.0, n));
  grid.nz = static_cast<std::size_t>(std::clamp(std::round(n / static_cast<double>(grid.ny)), 1.0, n));
  grid.y0 = lo.y();
  grid.z0 = lo.z();
  grid.hy = extent_y / static_cast<double>(grid.ny);
  grid.hz = extent_z / static_cast<double>(grid.nz);
  grid.per_hy = 1 / grid.hy;
  grid.per_hz = 1 / grid.hz;
  result.rays = grid.ny * grid.nz;

  std::vector<Crossing> crossings;
  std::vector<std::array<std::int32_t, 2>> places;  // per vertex of the piece at hand, reused
  for (std::size_t s = 0; s < solids.size(); ++s) {
    if (!add_crossings(solids[s], static_cast<std::int32_t>(s), grid, crossings, places)) return WindingSample{};
  }
  std::sort(crossings.begin(), crossings.end(), [](const Crossing& a, const Crossing& b) {
    return a.ray != b.ray ? a.ray < b.ray : a.x < b.x;
  });

  const double cell = grid.hy * grid.hz;
  std::map<std::pair<int, int>, double> excess_by_pair;
  std::map<int, double> deficit_by_solid;
  std::vector<int> winding(solids.size(), 0);
  std::vector<int> touched;
  std::vector<std::pair<std::pair<int, int>, double>> ray_excess;
  std::vector<std::pair<int, double>> ray_deficit;
  for (std::size_t begin = 0; begin < crossings.size();) {
    std::size_t end = begin;
    while (end < crossings.size() && crossings[end].ray == crossings[begin].ray) ++end;
    int total = 0;
    ray_excess.clear();
    ray_deficit.clear();
    for (std::size_t k = begin; k < end; ++k) {
      const int solid = crossings[k].tag >> 1;
      const int delta = (crossings[k].tag & 1) != 0 ? 1 : -1;
      if (winding[solid] == 0) touched.push_back(solid);
      winding[solid] += delta;
      total += delta;
      if (k + 1 == end) break;
      const double length = static_cast<double>(crossings[k + 1].x) - static_cast<double>(crossings[k].x);
      if (length <= 0 || (total >= 0 && total <= 1)) continue;
      if (total >= 2) {
        // The solid inside itself twice, else the first two that hold this stretch.
        int a = -1, b = -1;
        for (int s : touched) {
          if (winding[s] >= 2) {
            a = b = s;
            break;
          }
          if (winding[s] >= 1 && a < 0) {
            a = s;
          } else if (winding[s] >= 1 && s != a) {
            b = s;
            break;
          }
        }
        if (a >= 0 && b < 0) b = a;
        ray_excess.push_back({{std::min(a, b), std::max(a, b)}, (total - 1) * length});
      } else {
        int culprit = -1;
        for (int s : touched) {
          if (winding[s] < 0) {
            culprit = s;
            break;
          }
        }
        ray_deficit.push_back({culprit, -total * length});
      }
    }
    bool consistent = total == 0;
    for (int s : touched) {
      consistent = consistent && winding[s] == 0;
      winding[s] = 0;
    }
    touched.clear();
    if (consistent) {
      for (const auto& [pair, volume] : ray_excess) excess_by_pair[pair] += volume * cell;
      for (const auto& [solid, volume] : ray_deficit) deficit_by_solid[solid] += volume * cell;
    } else {
      ++result.inconsistent_rays;
    }
    begin = end;
  }
  double largest = 0;
  for (const auto& [pair, volume] : excess_by_pair) {
    result.excess += volume;
    if (volume > largest) {
      largest = volume;
      result.excess_a = pair.first;
      result.excess_b = pair.second;
    }
  }
  largest = 0;
  for (const auto& [solid, volume] : deficit_by_solid) {
    result.deficit += volume;
    if (volume > largest) {
      largest = volume;
      result.deficit_solid = solid;
    }
  }
  return result;
}

}  // namespace rdtf::internal
