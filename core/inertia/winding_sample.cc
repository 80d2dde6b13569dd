#include "winding_sample.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <utility>

#include "../geometry/typed_view.h"

namespace rdtf::internal {
namespace {

// The rays sit at these fractions of their cells, not at the centres: models are drawn on round
// coordinates (a box edge at 0.25 m), and a ray through an edge or a vertex is the one case the
// tie rule below must settle; irrational offsets make it rare. One per coordinate.
constexpr double kFraction[3] = {0.23606797749978969,   // sqrt(5) - 2
                                 0.41421356237309503,   // sqrt(2) - 1
                                 0.73205080756887719};  // sqrt(3) - 1

// Past this many crossings a direction is left out: a body of many layers along it (a stack of
// plates, a finned heat sink) is measured by the other two, across its layers. Where all three
// are left out, the sample is cast again with a quarter of the rays, down to kFewestRays a
// direction. 12 bytes a crossing: at most 48 MB in all.
constexpr std::size_t kMaxCrossingsPerAxis = (std::size_t{4} << 20) / 3;
constexpr std::size_t kFewestRays = 256;

// Corners farther than this from the link frame's origin are not sampled: crossings are kept as
// floats.
constexpr double kFarthest = 1e30;

// A place among the rays is kept in 16 bits (doubled_place): at most this many rays a row.
constexpr std::size_t kMaxRaysPerRow = 16383;

// The rays parallel to axis `a`, on a grid over the other two coordinates `b` and `c` (a, b, c in
// cyclic order, so that (b, c) seen along a is turned as (y, z) is seen along x).
struct Grid {
  int a = 0, b = 1, c = 2;
  double b0 = 0, c0 = 0, hb = 0, hc = 0;
  double per_hb = 0, per_hc = 0;  // 1 / hb, 1 / hc
  std::size_t nb = 0, nc = 0;
  double at_b(std::size_t i) const { return b0 + (static_cast<double>(i) + kFraction[b]) * hb; }
  double at_c(std::size_t j) const { return c0 + (static_cast<double>(j) + kFraction[c]) * hc; }
  // Cells as near square as the box allows, about `rays` of them; false where the box is flat.
  bool cover(int axis, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::size_t rays) {
    a = axis;
    b = (axis + 1) % 3;
    c = (axis + 2) % 3;
    const double extent_b = hi[b] - lo[b], extent_c = hi[c] - lo[c];
    if (!(extent_b > 0) || !(extent_c > 0) || !std::isfinite(extent_b) || !std::isfinite(extent_c)) return false;
    const double n = static_cast<double>(rays), most = static_cast<double>(kMaxRaysPerRow);
    nb = static_cast<std::size_t>(std::clamp(std::round(std::sqrt(n * extent_b / extent_c)), 1.0, most));
    nc = static_cast<std::size_t>(std::clamp(std::round(n / static_cast<double>(nb)), 1.0, most));
    b0 = lo[b];
    c0 = lo[c];
    hb = extent_b / static_cast<double>(nb);
    hc = extent_c / static_cast<double>(nc);
    per_hb = 1 / hb;
    per_hc = 1 / hc;
    return true;
  }
};

}  // namespace

// Outside the anonymous namespace: WindingScratch::Buffers, which the header names, holds them.
struct WindingCrossing {
  std::uint32_t ray;
  float along;       // The coordinate along the ray, in the link frame.
  std::int32_t tag;  // solid * 2 + (1 where the ray enters the solid, 0 where it leaves)
};
using Crossing = WindingCrossing;

struct WindingScratch::Buffers {
  std::array<std::vector<Crossing>, 3> crossings;
  std::vector<std::uint32_t> start, next;           // order_by_ray's counts
  std::vector<std::array<std::int16_t, 6>> places;  // per vertex of the piece at hand
};

namespace {

// The side of the point q on which the directed edge p -> r passes, in the (b, c) plane, never 0:
// the edge is evaluated from its lexicographically smaller end, so both triangles that share it
// get opposite signs bit for bit, and an exact 0 is settled as if q were moved by (e, e^2) for a
// vanishing e. A ray through an edge of a closed surface thus crosses exactly one of its two
// triangles. `value` gets the edge function itself (the barycentric weight of the third corner).
int edge_side(const double p[3], const double r[3], int b, int c, double qb, double qc, double& value) {
  const bool swapped = r[b] < p[b] || (r[b] == p[b] && r[c] < p[c]);
  const double* u = swapped ? r : p;
  const double* w = swapped ? p : r;
  const double e = (w[b] - u[b]) * (qc - u[c]) - (w[c] - u[c]) * (qb - u[b]);
  int side;
  if (e != 0) {
    side = e > 0 ? 1 : -1;
  } else if (w[c] != u[c]) {
    side = w[c] > u[c] ? -1 : 1;
  } else {
    side = w[b] > u[b] ? 1 : -1;
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

// Where a coordinate lies among one row of rays, `u` = (coordinate - origin) / h - fraction (ray k
// at u = k), doubled so that it is an integer: 2k on ray k exactly, 2k + 1 strictly between rays k
// and k + 1. Clamped to just past the row's ends; not a number counts as before them.
std::int16_t doubled_place(double u, std::size_t n) {
  if (!(u >= -1)) return -2;
  if (u > static_cast<double>(n)) return static_cast<std::int16_t>(2 * n);
  // floor(u) for u >= -1 by truncation toward zero of u + 1 (a conversion, not a call).
  const int k = static_cast<int>(u + 1) - 1;
  return static_cast<std::int16_t>(2 * k + (u != static_cast<double>(k) ? 1 : 0));
}

// The rays (clamped to the row) whose doubled places lie in [lo, hi]; empty when first > last.
std::pair<std::ptrdiff_t, std::ptrdiff_t> rays_between(int lo, int hi, std::size_t n) {
  // ceil(lo / 2) and floor(hi / 2), with arithmetic shifts (exact for negative values too).
  return {std::max<std::ptrdiff_t>((lo + 1) >> 1, 0), std::min<std::ptrdiff_t>(hi >> 1, static_cast<std::ptrdiff_t>(n) - 1)};
}

// The rays of one grid that a triangle (corners c, in L) may cross, row by row: the triangle's
// extent in c where the row's line crosses it, one ray wider on each side (the edge test alone
// decides). A long thin triangle laid across the grid thus costs its rows, not its bounding box.
template <typename F>
void for_each_candidate(const Grid& g, const double c[3][3], std::ptrdiff_t i_first, std::ptrdiff_t i_last,
                        std::ptrdiff_t j_first, std::ptrdiff_t j_last, F&& f) {
  for (std::ptrdiff_t i = i_first; i <= i_last; ++i) {
    const double qb = g.at_b(static_cast<std::size_t>(i));
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int k = 0; k < 3; ++k) {
      const double* p = c[k];
      const double* r = c[(k + 1) % 3];
      if ((p[g.b] - qb) * (r[g.b] - qb) > 0) continue;  // the edge is on one side of the row
      double at;
      if (p[g.b] == r[g.b]) {
        at = std::min(p[g.c], r[g.c]);
        hi = std::max({hi, p[g.c], r[g.c]});
      } else {
        at = p[g.c] + (qb - p[g.b]) * (r[g.c] - p[g.c]) / (r[g.b] - p[g.b]);
      }
      lo = std::min(lo, at);
      hi = std::max(hi, at);
    }
    if (!(lo <= hi)) continue;
    double first = std::ceil((lo - g.c0) * g.per_hc - kFraction[g.c]) - 1;
    double last = std::floor((hi - g.c0) * g.per_hc - kFraction[g.c]) + 1;
    // Clamped before they become integers (a cell of denormal size makes them infinite, or NaN):
    // where they say nothing, every ray of the span is a candidate and the edge test decides.
    if (std::isnan(first) || std::isnan(last)) {
      first = -1;
      last = static_cast<double>(g.nc);
    }
    const double top = static_cast<double>(g.nc);
    const std::ptrdiff_t j0 = std::max<std::ptrdiff_t>(j_first, static_cast<std::ptrdiff_t>(std::clamp(first, -1.0, top)));
    const std::ptrdiff_t j1 = std::min<std::ptrdiff_t>(j_last, static_cast<std::ptrdiff_t>(std::clamp(last, -1.0, top)));
    for (std::ptrdiff_t j = j0; j <= j1; ++j) f(i, j, qb, g.at_c(static_cast<std::size_t>(j)));
  }
}

// Adds the crossings of one solid's triangles with the rays of the grids not yet `full`; a grid
// past kMaxCrossingsPerAxis is marked full and its crossings dropped. Each vertex is placed among the rows of rays once (most are shared by six
// triangles), so that a triangle between two rows, as most of a large mesh's are, is passed over
// with integer comparisons; only the others are placed in full and tested edge by edge.
void add_crossings(const PlacedSolid& solid, std::int32_t index, const std::array<Grid, 3>& grids,
                   std::array<std::vector<Crossing>, 3>& out, std::array<bool, 3>& full,
                   std::vector<std::array<std::int16_t, 6>>& places) {
  const Eigen::Matrix3d L = solid.X_LM.linear();
  const Eigen::Vector3d t = solid.X_LM.translation();
  // A mirroring placement turns the winding over, as an inside-out mesh does.
  const int orientation = solid.orientation * (L.determinant() < 0 ? -1 : 1);
  for (const TriangleMeshView& piece : solid.pieces) {
    if (full[0] && full[1] && full[2]) break;
    with_typed_view(piece, [&](const auto& view) {
      places.resize(view.vertex_count);
      for (std::size_t v = 0; v < view.vertex_count; ++v) {
        double p[3];
        view.vertex(static_cast<std::uint32_t>(v), p);
        double q[3];
        for (int r = 0; r < 3; ++r) q[r] = L(r, 0) * p[0] + L(r, 1) * p[1] + L(r, 2) * p[2] + t[r];
        for (int g = 0; g < 3; ++g) {
          const Grid& grid = grids[g];
          places[v][2 * g] = doubled_place((q[grid.b] - grid.b0) * grid.per_hb - kFraction[grid.b], grid.nb);
          places[v][2 * g + 1] = doubled_place((q[grid.c] - grid.c0) * grid.per_hc - kFraction[grid.c], grid.nc);
        }
      }
      double c[3][3];
      for (std::size_t tri = 0; tri < view.triangle_count; ++tri) {
        const std::uint32_t v0 = view.index(3 * tri), v1 = view.index(3 * tri + 1), v2 = view.index(3 * tri + 2);
        if (v0 >= view.vertex_count || v1 >= view.vertex_count || v2 >= view.vertex_count) continue;
        const auto& p0 = places[v0];
        const auto& p1 = places[v1];
        const auto& p2 = places[v2];
        bool placed = false;
        for (int g = 0; g < 3; ++g) {
          if (full[g]) continue;
          const Grid& grid = grids[g];
          const auto [i_first, i_last] = rays_between(std::min({p0[2 * g], p1[2 * g], p2[2 * g]}),
                                                      std::max({p0[2 * g], p1[2 * g], p2[2 * g]}), grid.nb);
          if (i_first > i_last) continue;
          const auto [j_first, j_last] = rays_between(std::min({p0[2 * g + 1], p1[2 * g + 1], p2[2 * g + 1]}),
                                                      std::max({p0[2 * g + 1], p1[2 * g + 1], p2[2 * g + 1]}), grid.nc);
          if (j_first > j_last) continue;
          if (!placed) {
            const std::uint32_t corners[3] = {v0, v1, v2};
            bool finite = true;
            for (int k = 0; k < 3; ++k) {
              double p[3];
              view.vertex(corners[k], p);
              for (int r = 0; r < 3; ++r) c[k][r] = L(r, 0) * p[0] + L(r, 1) * p[1] + L(r, 2) * p[2] + t[r];
              // A corner that is not a finite number (the loader refuses them; this never trusts
              // it) has no place along a ray, and a NaN would break the sort below; one beyond
              // float's range (a model 1e30 m across, refused later for its inertia) has no float
              // to be kept in.
              for (int r = 0; r < 3; ++r) finite = finite && std::abs(c[k][r]) < kFarthest;
            }
            if (!finite) break;
            placed = true;
          }
          const int a = grid.a, b = grid.b, cc = grid.c;
          // Twice the triangle's area seen along a: the a component of its normal (q1 - q0) x (q2 - q0).
          const double area2 = (c[1][b] - c[0][b]) * (c[2][cc] - c[0][cc]) - (c[1][cc] - c[0][cc]) * (c[2][b] - c[0][b]);
          if (area2 == 0) continue;  // Edge on: no ray passes through it.
          const int facing = area2 > 0 ? 1 : -1;
          // A ray along +a enters a solid through a face whose outward normal points against it.
          const std::int32_t enters = (area2 < 0) == (orientation > 0) ? 1 : 0;
          for_each_candidate(grid, c, i_first, i_last, j_first, j_last,
                             [&](std::ptrdiff_t i, std::ptrdiff_t j, double qb, double qc) {
                               if (full[g]) return;
                               double w_2, w_0, w_1;
                               if (edge_side(c[0], c[1], b, cc, qb, qc, w_2) != facing ||
                                   edge_side(c[1], c[2], b, cc, qb, qc, w_0) != facing ||
                                   edge_side(c[2], c[0], b, cc, qb, qc, w_1) != facing) {
                                 return;
                               }
                               const double sum = w_0 + w_1 + w_2;
                               const double along = sum != 0 ? (w_0 * c[0][a] + w_1 * c[1][a] + w_2 * c[2][a]) / sum
                                                             : (c[0][a] + c[1][a] + c[2][a]) / 3;
                               if (out[g].size() == kMaxCrossingsPerAxis) {
                                 full[g] = true;
                                 out[g].clear();
                                 return;
                               }
                               out[g].push_back({static_cast<std::uint32_t>(static_cast<std::size_t>(i) * grid.nc +
                                                                            static_cast<std::size_t>(j)),
                                                 static_cast<float>(along), index * 2 + enters});
                             });
        }
      }
    });
  }
}

// What the rays of one grid found.
struct AxisSample {
  std::map<std::pair<int, int>, double> excess_by_pair;
  std::map<int, double> deficit_by_solid;
  double covered = 0;            // m^3 inside at least one solid
  std::size_t excess_rays = 0;   // Rays that found some excess.
  std::size_t deficit_rays = 0;  // Rays that found some deficit.
  std::size_t inconsistent_rays = 0;
};

// Puts the crossings in ray order, and each ray's in order along it (ties by tag, so that the
// order is the same on every run): a counting sort on the ray, whose number is below the grid's
// nb * nc, in place (each crossing is swapped into the next free place of its ray's range), then
// a sort of each ray's few crossings. One sort of them all by (ray, along) took a third of a
// small model's check, and a second array for the counting sort cost as many fresh pages.
void order_by_ray(std::vector<Crossing>& crossings, const Grid& grid, std::vector<std::uint32_t>& start,
                  std::vector<std::uint32_t>& next) {
  const std::size_t rays = grid.nb * grid.nc;
  start.assign(rays + 1, 0);
  for (const Crossing& x : crossings) ++start[x.ray + 1];
  for (std::size_t r = 0; r < rays; ++r) start[r + 1] += start[r];
  next.assign(start.begin(), start.end() - 1);
  for (std::size_t r = 0; r < rays; ++r) {
    while (next[r] < start[r + 1]) {
      Crossing& x = crossings[next[r]];
      if (x.ray == r) {
        ++next[r];
      } else {
        std::swap(x, crossings[next[x.ray]++]);
      }
    }
  }
  for (std::size_t r = 0; r < rays; ++r) {
    if (start[r + 1] - start[r] < 2) continue;
    std::sort(crossings.begin() + start[r], crossings.begin() + start[r + 1], [](const Crossing& a, const Crossing& b) {
      return a.along != b.along ? a.along < b.along : a.tag < b.tag;
    });
  }
}

// Walks each ray's crossings in order, keeping every solid's winding number: where the solids
// holding a stretch number two or more (counting each solid as often as it winds there) the
// stretch is excess; where a solid's own winding is below 0 (a shell wound inward outside that
// solid, even where another part's material fills it), deficit.
AxisSample walk(std::vector<Crossing>& crossings, const Grid& grid, std::size_t solids,
                WindingScratch::Buffers& scratch) {
  order_by_ray(crossings, grid, scratch.start, scratch.next);
  AxisSample sample;
  const double cell = grid.hb * grid.hc;
  std::vector<int> winding(solids, 0);
  std::vector<int> touched;
  std::vector<std::pair<std::pair<int, int>, double>> ray_excess;
  std::vector<std::pair<int, double>> ray_deficit;
  for (std::size_t begin = 0; begin < crossings.size();) {
    std::size_t end = begin;
    while (end < crossings.size() && crossings[end].ray == crossings[begin].ray) ++end;
    int inside = 0;    // sum over solids of max(w, 0)
    int negative = 0;  // sum over solids of max(-w, 0)
    ray_excess.clear();
    ray_deficit.clear();
    double ray_covered = 0;
    for (std::size_t k = begin; k < end; ++k) {
      const int solid = crossings[k].tag >> 1;
      const int delta = (crossings[k].tag & 1) != 0 ? 1 : -1;
      int& w = winding[static_cast<std::size_t>(solid)];
      if (w == 0) touched.push_back(solid);
      inside -= std::max(w, 0);
      negative -= std::max(-w, 0);
      w += delta;
      inside += std::max(w, 0);
      negative += std::max(-w, 0);
      if (k + 1 == end) break;
      const double length = static_cast<double>(crossings[k + 1].along) - static_cast<double>(crossings[k].along);
      if (length <= 0) continue;
      if (inside >= 1) ray_covered += length;
      if (inside >= 2) {
        // The solid inside itself twice, else the first two that hold this stretch.
        int first = -1, second = -1;
        for (int s : touched) {
          const int ws = winding[static_cast<std::size_t>(s)];
          if (ws >= 2) {
            first = second = s;
            break;
          }
          if (ws >= 1 && first < 0) {
            first = s;
          } else if (ws >= 1 && s != first) {
            second = s;
            break;
          }
        }
        if (second < 0) second = first;
        ray_excess.push_back({{std::min(first, second), std::max(first, second)}, (inside - 1) * length});
      }
      if (negative > 0) {
        int culprit = -1;
        for (int s : touched) {
          if (winding[static_cast<std::size_t>(s)] < 0) {
            culprit = s;
            break;
          }
        }
        ray_deficit.push_back({culprit, negative * length});
      }
    }
    bool consistent = true;
    for (int s : touched) {
      consistent = consistent && winding[static_cast<std::size_t>(s)] == 0;
      winding[static_cast<std::size_t>(s)] = 0;
    }
    touched.clear();
    if (consistent) {
      for (const auto& [pair, volume] : ray_excess) sample.excess_by_pair[pair] += volume * cell;
      for (const auto& [solid, volume] : ray_deficit) sample.deficit_by_solid[solid] += volume * cell;
      sample.covered += ray_covered * cell;
      sample.excess_rays += ray_excess.empty() ? 0 : 1;
      sample.deficit_rays += ray_deficit.empty() ? 0 : 1;
    } else {
      ++sample.inconsistent_rays;
    }
    begin = end;
  }
  return sample;
}

}  // namespace

WindingScratch::WindingScratch() : buffers(std::make_unique<Buffers>()) {}
WindingScratch::~WindingScratch() = default;

WindingSample sample_winding(std::span<const PlacedSolid> solids, std::size_t rays, WindingScratch* scratch) {
  if (solids.empty() || rays == 0) return {};
  std::optional<WindingScratch> own;
  WindingScratch::Buffers& memory = *(scratch != nullptr ? scratch : &own.emplace())->buffers;
  Eigen::Vector3d lo, hi;
  bound(solids, lo, hi);
  for (std::size_t tried = rays;; tried /= 4) {
    std::array<Grid, 3> grids;
    for (int axis = 0; axis < 3; ++axis) {
      if (!grids[axis].cover(axis, lo, hi, tried)) return {};  // flat: no volume to count
    }
    std::array<std::vector<Crossing>, 3>& crossings = memory.crossings;
    for (int axis = 0; axis < 3; ++axis) {
      // A closed surface crosses each ray that meets it at least twice: room for that from the
      // start, instead of growing (and copying) by doubling.
      crossings[axis].clear();
      crossings[axis].reserve(std::min(2 * grids[axis].nb * grids[axis].nc + 64, kMaxCrossingsPerAxis));
    }
    std::array<bool, 3> full{};
    for (std::size_t s = 0; s < solids.size(); ++s) {
      add_crossings(solids[s], static_cast<std::int32_t>(s), grids, crossings, full, memory.places);
    }
    if (full[0] && full[1] && full[2]) {
      if (tried / 4 < kFewestRays) return {};
      continue;
    }
    // Each direction measures a region exactly along its rays and samples it across them, so a
    // region thin across one direction's rays can fall between them (or fill a whole cell) while
    // the direction along its thickness measures it well: the direction whose rays found the
    // region most often is taken, for the excess and for the deficit each.
    WindingSample result;
    std::array<AxisSample, 3> samples;
    int best_excess = -1, best_deficit = -1;
    for (int axis = 0; axis < 3; ++axis) {
      if (full[axis]) continue;
      samples[axis] = walk(crossings[axis], grids[axis], solids.size(), memory);
      result.rays += grids[axis].nb * grids[axis].nc;
      result.inconsistent_rays += samples[axis].inconsistent_rays;
      if (best_excess < 0 || samples[axis].excess_rays > samples[best_excess].excess_rays) best_excess = axis;
      if (best_deficit < 0 || samples[axis].deficit_rays > samples[best_deficit].deficit_rays) best_deficit = axis;
    }
    result.covered = samples[best_excess].covered;
    result.deficit_covered = samples[best_deficit].covered;
    result.excess_axis = best_excess;
    result.deficit_axis = best_deficit;
    double largest = 0;
    for (const auto& [pair, volume] : samples[best_excess].excess_by_pair) {
      result.excess += volume;
      if (volume > largest) {
        largest = volume;
        result.excess_a = pair.first;
        result.excess_b = pair.second;
      }
    }
    largest = 0;
    for (const auto& [solid, volume] : samples[best_deficit].deficit_by_solid) {
      result.deficit += volume;
      if (volume > largest) {
        largest = volume;
        result.deficit_solid = solid;
      }
    }
    return result;
  }
}

}  // namespace rdtf::internal
