// The mass-properties kernel and the surface check on meshes read in place (TriangleMeshView:
// float positions, 8/16/32-bit or no indices, strides) against the same meshes as TriangleMesh
// values; both compiled copies of the kernel (baseline and AVX) against each other; and the
// surface check against a brute-force count on random meshes.
//
// The kernel promises the same bits whatever the storage and whichever copy runs (the same IEEE
// operations in the same order, floats widened exactly), so those comparisons are exact, which
// is stronger than the 1e-9 agreement issue 6 asks for.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <numbers>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "rdtf/mass_properties.h"
#include "rdtf/mesh_checks.h"
#include "rdtf/triangle_mesh.h"
#include "surface_reference.h"

namespace rdtf {
namespace {

using Eigen::Affine3d;
using Eigen::Vector3d;
using Triangle = std::array<std::uint32_t, 3>;

// Whether every coordinate of `p` is a float's value (a double with its low 29 mantissa bits
// zero: exact for the normal floats these meshes hold), checked on the bits alone.
bool holds_floats(const Vector3d& p) {
  for (int c = 0; c < 3; ++c) {
    std::uint64_t bits;
    const double value = p[c];
    std::memcpy(&bits, &value, sizeof(bits));
    if ((bits & ((std::uint64_t{1} << 29) - 1)) != 0) return false;
  }
  return true;
}

// A closed UV sphere (rings x 2 rings segments), counter-clockwise from outside, its vertices
// rounded to float so that a float copy holds exactly the same values.
//
// The floats are kept as a Vector3f and widened from there. g++ 12.2 at -O2 compiled the direct
// round trip (p.cast<float>().cast<double>(), or Vector3d(float(x), float(y), float(z))) into a
// plain copy of x and y: the "rounded" mesh then was not, and the in-place (float) views differed
// from it in the last bits. holds_floats checks that the rounding happened.
TriangleMesh float_sphere(int rings, double radius, const Vector3d& centre) {
  const int segments = 2 * rings;
  TriangleMesh mesh;
  std::vector<Eigen::Vector3f> floats;
  const auto add = [&](const Vector3d& p) {
    floats.push_back((centre + p).cast<float>());
    mesh.positions.push_back(floats.back().cast<double>());
    EXPECT_TRUE(holds_floats(mesh.positions.back())) << mesh.positions.back().transpose();
  };
  add(Vector3d(0, radius, 0));
  for (int i = 1; i < rings; ++i) {
    const double theta = std::numbers::pi * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * std::numbers::pi * j / segments;
      add(radius * Vector3d(std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi)));
    }
  }
  add(Vector3d(0, -radius, 0));
  const auto south = static_cast<std::uint32_t>(mesh.positions.size() - 1);
  const auto ring = [&](int i, int j) { return static_cast<std::uint32_t>(1 + (i - 1) * segments + j % segments); };
  for (int j = 0; j < segments; ++j) mesh.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i + 1 < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  }
  for (int j = 0; j < segments; ++j) mesh.triangles.push_back({south, ring(rings - 1, j + 1), ring(rings - 1, j)});
  return mesh;
}

// A mesh's bytes as a glTF buffer could hold them: float positions `position_stride` bytes apart
// (the rest of each vertex is filler), indices of type I `index_stride` bytes apart, or none (the
// vertices then listed once per corner).
struct Stored {
  std::vector<std::uint8_t> positions, indices;
  TriangleMeshView layout;  // Strides, counts and types; the pointers come from view().
  // Pointers into this value's own bytes, wherever it has been copied or moved to.
  TriangleMeshView view() const {
    TriangleMeshView v = layout;
    v.positions = positions.data();
    v.indices = indices.empty() ? nullptr : indices.data();
    return v;
  }
};

template <typename I>
Stored store(const TriangleMesh& mesh, std::size_t position_stride, std::size_t index_stride) {
  Stored s;
  constexpr bool kIndexed = !std::is_void_v<I>;
  std::vector<Vector3d> vertices;
  if constexpr (kIndexed) {
    vertices = mesh.positions;
  } else {
    for (const Triangle& t : mesh.triangles)
      for (std::uint32_t v : t) vertices.push_back(mesh.positions[v]);
  }
  s.positions.assign(vertices.size() * position_stride, 0xA5);
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    for (int c = 0; c < 3; ++c) {
      const auto value = static_cast<float>(vertices[v][c]);
      std::memcpy(s.positions.data() + v * position_stride + 4 * c, &value, 4);
    }
  }
  s.layout.positions = s.positions.data();
  s.layout.position_stride = position_stride;
  s.layout.vertex_count = vertices.size();
  s.layout.position_type = TriangleMeshView::Positions::kFloat32;
  s.layout.triangle_count = mesh.triangles.size();
  if constexpr (kIndexed) {
    s.indices.assign(mesh.triangles.size() * 3 * index_stride, 0x5A);
    for (std::size_t k = 0; k < 3 * mesh.triangles.size(); ++k) {
      const auto value = static_cast<I>(mesh.triangles[k / 3][k % 3]);
      std::memcpy(s.indices.data() + k * index_stride, &value, sizeof(I));
    }
    s.layout.indices = s.indices.data();
    s.layout.index_stride = index_stride;
    s.layout.index_type = sizeof(I) == 1   ? TriangleMeshView::Indices::kUint8
                        : sizeof(I) == 2 ? TriangleMeshView::Indices::kUint16
                                         : TriangleMeshView::Indices::kUint32;
  } else {
    s.layout.index_type = TriangleMeshView::Indices::kNone;
  }
  return s;
}

VolumeIntegrals solid_of(const TriangleMeshView& view, const Affine3d& X) {
  return integrate_solid(std::span<const TriangleMeshView>(&view, 1), X);
}

SurfaceTopology surface_of(const TriangleMeshView& view) {
  return analyze_surface(std::span<const TriangleMeshView>(&view, 1));
}

void expect_same_bits(const VolumeIntegrals& a, const VolumeIntegrals& b) {
  EXPECT_EQ(a.volume, b.volume);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a.centroid[i], b.centroid[i]) << "centroid " << i;
  for (int i = 0; i < 9; ++i) EXPECT_EQ(a.second_central(i), b.second_central(i)) << "second moment " << i;
}

std::vector<Affine3d> transforms() {
  Affine3d mirrored_shear = Affine3d::Identity();
  mirrored_shear.linear() << -1.5, 0.2, 0, 0.1, 0.7, 0.3, 0, -0.2, 2.0;
  mirrored_shear.translation() = Vector3d(3e3, -2e3, 5e2);
  return {Affine3d::Identity(),
          Eigen::Translation3d(1e4, -6e3, 8e3) * Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()),
          mirrored_shear};
}

// Meshes whose triangle counts leave every remainder by the kernel's four lanes, near and 10 km
// from the origin.
std::vector<TriangleMesh> test_meshes() {
  std::vector<TriangleMesh> meshes;
  for (int rings : {3, 4, 5, 7, 24}) meshes.push_back(float_sphere(rings, 0.5, Vector3d::Zero()));
  meshes.push_back(float_sphere(9, 0.25, Vector3d(6e3, -7e3, 4.5e3)));
  return meshes;
}

TEST(MassProperties, KernelCopiesAgreeBitForBit) {
  if (!detail::kernel_available(detail::KernelIsa::kAvx)) {
    GTEST_SKIP() << "this processor has no AVX: only the baseline copy can run here";
  }
  for (const TriangleMesh& mesh : test_meshes()) {
    const TriangleMeshView view = TriangleMeshView::of(mesh);
    const Stored stored = store<std::uint16_t>(mesh, 16, 2);
    for (const Affine3d& X : transforms()) {
      SCOPED_TRACE(::testing::Message() << mesh.triangles.size() << " triangles, X =\n" << X.matrix());
      for (const TriangleMeshView& v : {view, stored.view()}) {
        const std::span<const TriangleMeshView> pieces(&v, 1);
        const VolumeIntegrals baseline = detail::integrate_solid(pieces, X, detail::KernelIsa::kBaseline);
        const VolumeIntegrals avx = detail::integrate_solid(pieces, X, detail::KernelIsa::kAvx);
        expect_same_bits(baseline, avx);
        expect_same_bits(integrate_solid(pieces, X), avx);  // What the converter runs here.
      }
    }
  }
}

// The closed form of the sphere the meshes approximate is checked elsewhere; here the kernel in
// each copy must still give the polyhedron's exact volume: sum of its signed tetrahedra about
// the origin, written out independently in long double.
TEST(MassProperties, EachKernelCopyGivesThePolyhedronVolume) {
  const TriangleMesh mesh = float_sphere(24, 0.5, Vector3d::Zero());
  long double six_volume = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vector3d& a = mesh.positions[t[0]];
    const Vector3d& b = mesh.positions[t[1]];
    const Vector3d& c = mesh.positions[t[2]];
    six_volume += static_cast<long double>(a.dot(b.cross(c)));
  }
  const double volume = static_cast<double>(six_volume / 6);
  const TriangleMeshView view = TriangleMeshView::of(mesh);
  for (const auto isa : {detail::KernelIsa::kBaseline, detail::KernelIsa::kAvx}) {
    if (!detail::kernel_available(isa)) continue;
    const auto got = detail::integrate_solid(std::span<const TriangleMeshView>(&view, 1), Affine3d::Identity(), isa);
    EXPECT_NEAR(got.volume, volume, 1e-9 * volume);
    EXPECT_LT(got.centroid.norm(), 1e-9 * 0.5);  // Symmetric about the origin.
  }
}

TEST(MassProperties, InPlaceViewsGiveTheSameBits) {
  for (const TriangleMesh& mesh : test_meshes()) {
    SCOPED_TRACE(::testing::Message() << mesh.triangles.size() << " triangles");
    const std::vector<TriangleMesh> as_mesh{mesh};
    const std::vector<Stored> layouts = {
        store<std::uint32_t>(mesh, 12, 4), store<std::uint32_t>(mesh, 20, 8),
        store<std::uint16_t>(mesh, 12, 2), store<std::uint16_t>(mesh, 32, 4),
    };
    for (const Affine3d& X : transforms()) {
      const VolumeIntegrals want = integrate_solid(as_mesh, X);
      for (const Stored& s : layouts) {
        expect_same_bits(solid_of(s.view(), X), want);
      }
      if (mesh.positions.size() <= 256) {
        const Stored bytes = store<std::uint8_t>(mesh, 12, 1);
        expect_same_bits(solid_of(bytes.view(), X), want);
      }
      // Without indices the vertices come in another order; the tetrahedra and their sum do not.
      const Stored unindexed = store<void>(mesh, 12, 0);
      expect_same_bits(solid_of(unindexed.view(), X), want);
    }
  }
}

TEST(SurfaceTopology, InPlaceViewsGiveTheSameCounts) {
  TriangleMesh open = float_sphere(7, 0.5, Vector3d::Zero());
  open.triangles.erase(open.triangles.begin() + 5);  // A hole.
  std::swap(open.triangles[9][1], open.triangles[9][2]);  // A flipped triangle.
  open.triangles.push_back(open.triangles[20]);           // A doubled one: non-manifold edges.
  open.triangles.push_back({3, 3, 4});                    // A degenerate one.
  for (const TriangleMesh& mesh : {float_sphere(7, 0.5, Vector3d::Zero()), open}) {
    const std::vector<TriangleMesh> as_mesh{mesh};
    const SurfaceTopology want = analyze_surface(as_mesh);
    for (const Stored& s : {store<std::uint32_t>(mesh, 12, 4), store<std::uint16_t>(mesh, 24, 2),
                            store<std::uint8_t>(mesh, 12, 1), store<void>(mesh, 16, 0)}) {
      testing::expect_equal(surface_of(s.view()), want);
    }
  }
}

// Two pieces of one surface, one read in place (floats) and one a TriangleMesh (doubles): their
// shared vertices weld across the two storages.
TEST(SurfaceTopology, PiecesInDifferentStoragesWeldTogether) {
  const TriangleMesh sphere = float_sphere(6, 0.5, Vector3d::Zero());
  TriangleMesh first = sphere, second = sphere;
  const std::size_t half = sphere.triangles.size() / 2;
  first.triangles.resize(half);
  second.triangles.erase(second.triangles.begin(), second.triangles.begin() + static_cast<std::ptrdiff_t>(half));
  const Stored in_place = store<std::uint16_t>(first, 12, 2);
  const std::vector<TriangleMeshView> pieces{in_place.view(), TriangleMeshView::of(second)};
  const SurfaceTopology topology = analyze_surface(pieces);
  EXPECT_EQ(topology.triangles, sphere.triangles.size());
  EXPECT_TRUE(topology.closed());
  EXPECT_TRUE(topology.consistently_oriented());
  EXPECT_EQ(topology.degenerate_triangles, 0u);
  // Alone, each half is open along the equator of the split.
  EXPECT_FALSE(analyze_surface(std::span<const TriangleMeshView>(&pieces[0], 1)).closed());
}


// Random damage to closed spheres with their vertices renumbered at random (so that a vertex's
// edges fall in rows of every size, past the sorting networks' 2, 4, 6 and 8), split into pieces,
// with vertices duplicated as exporters split them: every count must match the definition.
TEST(SurfaceTopology, MatchesBruteForceOnRandomMeshes) {
  std::mt19937 random(20261123);
  SurfaceTopology seen;  // Sums over the trials: every kind of fault must have come up.
  for (int trial = 0; trial < 60; ++trial) {
    TriangleMesh mesh = float_sphere(3 + trial % 9, 0.5, Vector3d::Zero());
    testing::shuffle_mesh(mesh, random);
    // Damage: flips, removals, duplicates, degenerate triangles, a signed zero.
    const int damage = trial % 5 == 0 ? 0 : 1 + trial % 7;
    for (int d = 0; d < damage; ++d) {
      const std::size_t t = random() % mesh.triangles.size();
      switch (random() % 4) {
        case 0: std::swap(mesh.triangles[t][0], mesh.triangles[t][1]); break;
        case 1: mesh.triangles.erase(mesh.triangles.begin() + static_cast<std::ptrdiff_t>(t)); break;
        case 2: mesh.triangles.push_back(mesh.triangles[t]); break;
        default: mesh.triangles.push_back({mesh.triangles[t][0], mesh.triangles[t][0], mesh.triangles[t][1]}); break;
      }
    }
    // Duplicate some vertices (same position, new index) and use the copies in some corners.
    for (int d = 0; d < 1 + trial % 4; ++d) {
      const std::size_t t = random() % mesh.triangles.size();
      const int k = static_cast<int>(random() % 3);
      mesh.positions.push_back(mesh.positions[mesh.triangles[t][k]]);
      mesh.triangles[t][k] = static_cast<std::uint32_t>(mesh.positions.size() - 1);
    }
    if (trial % 3 == 0) {
      // The pole at (0, 0.5, 0) copied with x = -0: the same position.
      mesh.positions.push_back(Vector3d(-0.0, 0.5, 0.0));
      for (Triangle& t : mesh.triangles) {
        if (mesh.positions[t[0]] == Vector3d(0, 0.5, 0)) {
          t[0] = static_cast<std::uint32_t>(mesh.positions.size() - 1);
          break;
        }
      }
    }
    // Split into two pieces sharing every vertex (the second piece's vertices copied).
    std::vector<TriangleMesh> pieces(2);
    pieces[0].positions = pieces[1].positions = mesh.positions;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) pieces[t % 3 == 0].triangles.push_back(mesh.triangles[t]);
    SCOPED_TRACE(::testing::Message() << "trial " << trial);
    const SurfaceTopology want = testing::reference_topology(pieces);
    testing::expect_equal(analyze_surface(pieces), want);
    seen.degenerate_triangles += want.degenerate_triangles;
    seen.boundary_edges += want.boundary_edges;
    seen.misoriented_edges += want.misoriented_edges;
    seen.nonmanifold_edges += want.nonmanifold_edges;
    // And in place: the first piece as floats with 16-bit indices.
    const Stored first = store<std::uint16_t>(pieces[0], 12, 2);
    const std::vector<TriangleMeshView> views{first.view(), TriangleMeshView::of(pieces[1])};
    testing::expect_equal(analyze_surface(views), want);
  }
  EXPECT_GT(seen.degenerate_triangles, 0u);
  EXPECT_GT(seen.boundary_edges, 0u);
  EXPECT_GT(seen.misoriented_edges, 0u);
  EXPECT_GT(seen.nonmanifold_edges, 0u);
}

// A vertex shared by many triangles (a fan of 40 around a pole, closed by a second fan): rows far
// longer than the sorting networks handle, both ways round.
TEST(SurfaceTopology, LongRowsOfAHighValenceVertex) {
  for (int flip = 0; flip < 2; ++flip) {
    TriangleMesh bicone;
    const int n = 40;
    bicone.positions.push_back(Vector3d(0, 0, flip ? -1 : 1));  // Index 0: the high-valence vertex.
    for (int k = 0; k < n; ++k) {
      const double a = 2 * std::numbers::pi * k / n;
      bicone.positions.push_back(Vector3d(std::cos(a), std::sin(a), 0));
    }
    bicone.positions.push_back(Vector3d(0, 0, flip ? 1 : -1));
    const auto last = static_cast<std::uint32_t>(n + 1);
    for (std::uint32_t k = 0; k < static_cast<std::uint32_t>(n); ++k) {
      const std::uint32_t a = 1 + k, b = 1 + (k + 1) % n;
      bicone.triangles.push_back(flip ? Triangle{0, b, a} : Triangle{0, a, b});
      bicone.triangles.push_back(flip ? Triangle{last, a, b} : Triangle{last, b, a});
    }
    const std::vector<TriangleMesh> pieces{bicone};
    const SurfaceTopology topology = analyze_surface(pieces);
    testing::expect_equal(topology, testing::reference_topology(pieces));
    EXPECT_TRUE(topology.closed());
    EXPECT_TRUE(topology.consistently_oriented());
    EXPECT_GT(integrate_solid(pieces, Affine3d::Identity()).volume, 0.0);
  }
}

}  // namespace
}  // namespace rdtf
