// The winding sample (core/inertia/winding_sample.h) on solids whose overlaps are known exactly.
// Boxes whose faces are normal to the rays give exact lengths along every ray, and the rays sit
// at irrational fractions of their cells, so a ray is inside a box's outline or not, never on it:
// the sums are then exact up to rounding (1e-9 relative). A prism's curved outline is sampled by
// the grid, with an error bounded by the cells its outline passes through.
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "../core/inertia/winding_sample.h"
#include "rdtf/triangle_mesh.h"

namespace rdtf::internal {
namespace {

using Eigen::Affine3d;
using Eigen::AngleAxisd;
using Eigen::Vector3d;

constexpr double kTol = 1e-9;

// Axis-aligned box [lo, hi], counter-clockwise seen from outside (as tests/inertia's make_box);
// `inward` winds it the other way.
TriangleMesh box(const Vector3d& lo, const Vector3d& hi, bool inward = false) {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.positions.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
  }
  mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  if (inward) {
    for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  }
  return mesh;
}

// A prism along x over a regular n-gon of circumradius r about the x axis, from x0 to x1.
TriangleMesh prism(int n, double r, double x0, double x1) {
  TriangleMesh mesh;
  for (int k = 0; k < n; ++k) {
    const double a = 2 * std::numbers::pi * k / n;
    mesh.positions.emplace_back(x0, r * std::cos(a), r * std::sin(a));
    mesh.positions.emplace_back(x1, r * std::cos(a), r * std::sin(a));
  }
  const auto c0 = static_cast<std::uint32_t>(mesh.positions.size());
  mesh.positions.emplace_back(x0, 0, 0);
  mesh.positions.emplace_back(x1, 0, 0);
  for (int k = 0; k < n; ++k) {
    const auto a0 = static_cast<std::uint32_t>(2 * k), a1 = a0 + 1;
    const auto b0 = static_cast<std::uint32_t>(2 * ((k + 1) % n)), b1 = b0 + 1;
    mesh.triangles.push_back({a0, b0, b1});  // side, outward
    mesh.triangles.push_back({a0, b1, a1});
    mesh.triangles.push_back({c0, b0, a0});  // x0 cap, facing -x
    mesh.triangles.push_back({c0 + 1, a1, b1});  // x1 cap, facing +x
  }
  return mesh;
}

struct Solids {
  std::vector<std::vector<TriangleMeshView>> views;
  std::vector<PlacedSolid> placed;
  void add(const std::vector<const TriangleMesh*>& pieces) {
    views.emplace_back();
    for (const TriangleMesh* piece : pieces) views.back().push_back(TriangleMeshView::of(*piece));
  }
  std::vector<PlacedSolid> finish(const std::vector<Affine3d>& X, const std::vector<int>& orientation) {
    placed.clear();
    for (std::size_t s = 0; s < views.size(); ++s) placed.push_back({views[s], X[s], orientation[s]});
    return placed;
  }
};

WindingSample sample(const std::vector<std::vector<const TriangleMesh*>>& solids,
                     std::vector<Affine3d> X = {}, std::vector<int> orientation = {}) {
  Solids s;
  for (const auto& pieces : solids) s.add(pieces);
  X.resize(solids.size(), Affine3d::Identity());
  orientation.resize(solids.size(), 1);
  return sample_winding(s.finish(X, orientation));
}

TEST(WindingSample, TwoBoxesOverlappingByOneCubicMetre) {
  const TriangleMesh a = box({0, 0, 0}, {2, 1, 1}), b = box({1, 0, 0}, {3, 1, 1});
  const WindingSample apart = sample({{&a}, {&b}});
  EXPECT_NEAR(apart.excess, 1.0, kTol);
  EXPECT_EQ(apart.deficit, 0.0);
  EXPECT_EQ(apart.excess_a, 0);
  EXPECT_EQ(apart.excess_b, 1);
  EXPECT_EQ(apart.excess_axis, 0);  // every ray along x meets the overlap
  EXPECT_EQ(apart.rays, 64u * 64u + 37u * 111u + 111u * 37u);  // about 4,096 a direction, cells near square
  EXPECT_EQ(apart.inconsistent_rays, 0u);
  // The same two boxes as pieces of one mesh (objects joined with Ctrl+J): the mesh overlaps itself.
  const WindingSample joined = sample({{&a, &b}});
  EXPECT_NEAR(joined.excess, 1.0, kTol);
  EXPECT_EQ(joined.excess_a, 0);
  EXPECT_EQ(joined.excess_b, 0);
}

// Two bars crossing like a plus sign: no vertex of either lies inside the other, and their common
// cube of 1 m^3 is still found.
TEST(WindingSample, CrossedBarsWithNoVertexInsideTheOther) {
  const TriangleMesh bar = box({-2, -0.5, -0.5}, {2, 0.5, 0.5});
  // The second bar is the first turned a quarter about z (placed, not written out).
  const Affine3d turned(AngleAxisd(std::numbers::pi / 2, Vector3d::UnitZ()));
  const WindingSample crossed = sample({{&bar}, {&bar}}, {Affine3d::Identity(), turned});
  EXPECT_NEAR(crossed.excess, 1.0, kTol);
  EXPECT_EQ(crossed.deficit, 0.0);
  EXPECT_EQ(crossed.inconsistent_rays, 0u);
}

TEST(WindingSample, ANestedShellCountsTwiceUnlessWoundInwardAsACavity) {
  const TriangleMesh outer = box({0, 0, 0}, {4, 4, 4});
  const TriangleMesh inner = box({1, 1, 1}, {2, 2, 2});
  const TriangleMesh cavity = box({1, 1, 1}, {2, 2, 2}, /*inward=*/true);
  const WindingSample nested = sample({{&outer, &inner}});
  EXPECT_NEAR(nested.excess, 1.0, kTol);
  EXPECT_EQ(nested.deficit, 0.0);
  const WindingSample hollow = sample({{&outer, &cavity}});
  EXPECT_EQ(hollow.excess, 0.0);
  EXPECT_EQ(hollow.deficit, 0.0);
  EXPECT_EQ(hollow.inconsistent_rays, 0u);
}

// A shell wound inward beside the solid, not inside it: its volume is subtracted.
TEST(WindingSample, AnInwardShellOutsideAnySolidIsADeficit) {
  const TriangleMesh body = box({0, 0, 0}, {1, 1, 1});
  const TriangleMesh flipped = box({2, 0, 0}, {2.5, 1, 1}, /*inward=*/true);
  const WindingSample s = sample({{&body}, {&flipped}});
  EXPECT_EQ(s.excess, 0.0);
  EXPECT_NEAR(s.deficit, 0.5, kTol);
  EXPECT_EQ(s.deficit_solid, 1);
  // A whole mesh wound inward is turned right by its orientation, as the mass kernel turns it.
  const WindingSample turned = sample({{&body}, {&flipped}}, {}, {1, -1});
  EXPECT_EQ(turned.deficit, 0.0);
  EXPECT_EQ(turned.excess, 0.0);
  // So is one placed mirrored: a mirror turns an outward mesh's triangles clockwise.
  Affine3d mirrored = Affine3d::Identity();
  mirrored.matrix()(1, 1) = -1;
  const TriangleMesh bar = box({0, -1, 0}, {1, 0, 1});
  const WindingSample mirror = sample({{&body}, {&bar}}, {Affine3d::Identity(), mirrored});
  EXPECT_NEAR(mirror.excess, 1.0, kTol);  // the mirrored bar is the body again
  EXPECT_EQ(mirror.deficit, 0.0);
}

// Parts that touch face to face (stacked boxes) share no volume.
TEST(WindingSample, PartsThatTouchShareNothing) {
  const TriangleMesh a = box({0, 0, 0}, {1, 1, 1}), b = box({1, 0, 0}, {2, 1, 1}), c = box({0, 1, 0}, {1, 2, 1});
  const WindingSample s = sample({{&a, &b, &c}});
  EXPECT_EQ(s.excess, 0.0);
  EXPECT_EQ(s.deficit, 0.0);
  EXPECT_EQ(s.inconsistent_rays, 0u);
}

// A 32-sided prism of radius 0.45 along x through a box 0.5 m thick: every ray along x inside the
// polygon counts x in [-0.25, 0.25] twice, exactly, so the error is the polygon's area as the grid
// samples it (the rays along x meet the region most often: they give the estimate). A cell is misjudged only if the outline passes through it; the outline (perimeter P)
// crosses at most P / hy + P / hz + 2 n cells (one per grid line crossed, plus each edge's start).
TEST(WindingSample, APrismThroughABoxWithinTheGridsBound) {
  constexpr int n = 32;
  constexpr double r = 0.45;
  const TriangleMesh rod = prism(n, r, -1, 1), plate = box({-0.25, -0.5, -0.5}, {0.25, 0.5, 0.5});
  const WindingSample s = sample({{&rod}, {&plate}});
  const double area = 0.5 * n * r * r * std::sin(2 * std::numbers::pi / n);
  const double perimeter = 2 * n * r * std::sin(std::numbers::pi / n);
  const double h = 1.0 / 64;  // the box's 1 m by 1 m outline in 64 x 64 cells
  const double bound = (2 * perimeter / h + 2 * n) * h * h * 0.5;
  EXPECT_NEAR(s.excess, area * 0.5, bound);
  EXPECT_EQ(s.excess_axis, 0);
  EXPECT_LT(bound, 0.2 * area * 0.5);  // the bound is tight enough to mean something
  EXPECT_EQ(s.deficit, 0.0);
  EXPECT_EQ(s.inconsistent_rays, 0u);
  // Apart (the rod moved clear of the plate) they share nothing.
  const WindingSample apart = sample({{&rod}, {&plate}}, {Affine3d(Eigen::Translation3d(0, 2, 0)), Affine3d::Identity()});
  EXPECT_EQ(apart.excess, 0.0);
  EXPECT_EQ(apart.inconsistent_rays, 0u);
}

// Two plates overlapping by 3 mm across their thickness, in a body 1 m tall: rays along x or y
// pass 15.6 mm apart in z and meet the band in one row or none, while rays along z measure its
// thickness exactly in every cell: they give the estimate.
TEST(WindingSample, AThinOverlapIsMeasuredAlongItsThickness) {
  const TriangleMesh lower = box({0, 0, 0}, {1, 1, 0.5015}), upper = box({0, 0, 0.4985}, {1, 1, 1});
  const WindingSample s = sample({{&lower}, {&upper}});
  EXPECT_EQ(s.excess_axis, 2);
  // Crossings are kept as floats: each end of the band within half a float step at 0.5 (2^-25 m),
  // the length within 2^-24 m, over the band's 1 m^2.
  EXPECT_NEAR(s.excess, 0.003, std::ldexp(1.0, -24));
  EXPECT_EQ(s.inconsistent_rays, 0u);
}

// 700 plates 0.01 m thick, 0.01 m apart along x, beside two boxes that overlap by 1 m^3: 1,400
// faces on every ray along x through the plates, 5.7 million crossings with 4,096 rays, past the
// bound for one direction. That direction is left out, and the rays along y and z (each meeting
// a plate at most twice) still find the boxes' overlap. Seen along y, the region is a 1 m by 1 m
// square (z, x), every chord 1 m; the body's bounds across y are 1 m (z) by 11 m (x); the error
// is that of the cells the square's outline passes through (as in the prism test), and along z
// likewise.
TEST(WindingSample, ADirectionOfTooManyLayersIsLeftOutAndTheOthersMeasure) {
  std::vector<TriangleMesh> parts;
  for (int i = 0; i < 700; ++i) parts.push_back(box({0.01 * i, 0, 0}, {0.01 * i + 0.005, 1, 1}));
  parts.push_back(box({8, 0, 0}, {10, 1, 1}));
  parts.push_back(box({9, 0, 0}, {11, 1, 1}));
  std::vector<const TriangleMesh*> pieces;
  for (const TriangleMesh& part : parts) pieces.push_back(&part);
  const WindingSample s = sample({pieces});
  EXPECT_NE(s.excess_axis, 0);
  // The grids' cells as sample_winding makes them: about 4,096, near square.
  const auto cells = [](double extent_b, double extent_c) {
    const double nb = std::round(std::sqrt(4096 * extent_b / extent_c)), nc = std::round(4096 / nb);
    return std::array<double, 4>{nb, nc, extent_b / nb, extent_c / nc};
  };
  const auto along_y = cells(1, 11), along_z = cells(11, 1);  // (z, x) and (x, y)
  double bound = 0;
  for (const auto& g : {along_y, along_z}) bound = std::max(bound, (4 / g[2] + 4 / g[3] + 4) * g[2] * g[3] * 1.0);
  EXPECT_NEAR(s.excess, 1.0, bound);
  EXPECT_LT(bound, 0.5);
  EXPECT_EQ(s.rays, static_cast<std::size_t>(along_y[0] * along_y[1] + along_z[0] * along_z[1]));  // y and z only
  EXPECT_EQ(s.inconsistent_rays, 0u);
}

// A cavity (a shell wound inward) that pokes out of its solid into a lid beside it: there the
// winding numbers sum to 0 (the lid's 1, the cavity's -1), so the lid's material counts nothing.
// The cavity's solid winds below 0 on its own there: a deficit, named, though the place is filled.
TEST(WindingSample, ACavityPokingIntoAnotherPartIsADeficitOfItsOwnSolid) {
  const TriangleMesh body = box({0, 0, 0}, {1, 1, 1});
  const TriangleMesh cavity = box({0.5, 0.25, 0.25}, {1.25, 0.75, 0.75}, /*inward=*/true);
  const TriangleMesh lid = box({1, 0, 0}, {1.5, 1, 1});
  const WindingSample s = sample({{&body, &cavity}, {&lid}});
  EXPECT_NEAR(s.deficit, 0.25 * 0.5 * 0.5, kTol);
  EXPECT_EQ(s.deficit_solid, 0);
  EXPECT_EQ(s.excess, 0.0);
}

// A long thin triangle laid across the grid (a tilted cylinder's sides) is tested against the rays
// of its rows, not of its bounding box; the result is the same as for the cylinder upright.
TEST(WindingSample, TiltedPrismThroughABoxAgreesWithTheUprightOne) {
  const TriangleMesh rod = prism(64, 0.05, -1, 1), plate = box({-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1});
  const Affine3d tilted(AngleAxisd(std::numbers::pi / 4, Vector3d::UnitZ()));
  const WindingSample upright = sample({{&rod}, {&plate}});
  const WindingSample turned = sample({{&rod}, {&plate}}, {tilted, tilted});
  // Both are the 64-gon's area times the plate's 0.2 m, each within its own grid's error.
  const double exact = 0.5 * 64 * 0.05 * 0.05 * std::sin(2 * std::numbers::pi / 64) * 0.2;
  EXPECT_NEAR(upright.excess, exact, 0.02 * exact);
  EXPECT_NEAR(turned.excess, exact, 0.1 * exact);
  EXPECT_EQ(turned.inconsistent_rays, 0u);
}

TEST(WindingSample, NothingToSampleIsNothingFound) {
  EXPECT_EQ(sample({}).rays, 0u);
  const TriangleMesh flat = box({0, 0, 0}, {1, 1, 0});  // no extent in z
  const WindingSample s = sample({{&flat}});
  EXPECT_EQ(s.rays, 0u);
  EXPECT_EQ(s.excess, 0.0);
}

}  // namespace
}  // namespace rdtf::internal
