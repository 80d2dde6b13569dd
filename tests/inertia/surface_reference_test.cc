// analyze_surface against the simplest implementation of its definition, on random meshes of
// every kind: open, closed, non-manifold, misoriented, with duplicated vertices, signed zeros and
// degenerate triangles, in one or several pieces and in every storage a glTF buffer can have.
// Every count must be equal, not close: the surface check decides whether a mass is trusted.
// The reference is surface_reference.h.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <span>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "rdtf/mesh_checks.h"
#include "rdtf/triangle_mesh.h"
#include "surface_reference.h"

namespace rdtf {
namespace {

using Eigen::Vector3d;
using Triangle = std::array<std::uint32_t, 3>;
using testing::reference_topology;
using testing::shuffle_mesh;
using testing::expect_equal;

// A closed, consistently wound octahedron subdivided `level` times (every face into four), with
// its vertices shared: the base every closed random mesh below starts from.
TriangleMesh closed_octahedron(int level) {
  TriangleMesh mesh;
  mesh.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  mesh.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
    const auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto found = middle.find(key);
      if (found != middle.end()) return found->second;
      // Halves of dyadic coordinates are exact: equal midpoints are equal bits.
      mesh.positions.push_back(0.5 * (mesh.positions[a] + mesh.positions[b]));
      const auto id = static_cast<std::uint32_t>(mesh.positions.size() - 1);
      middle.emplace(key, id);
      return id;
    };
    std::vector<Triangle> finer;
    for (const Triangle& t : mesh.triangles) {
      const std::uint32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      finer.push_back({t[0], ab, ca});
      finer.push_back({ab, t[1], bc});
      finer.push_back({ca, bc, t[2]});
      finer.push_back({ab, bc, ca});
    }
    mesh.triangles = finer;
  }
  return mesh;
}

// Each vertex split into copies at the same position (as exporters split seams), the corners
// spread over the copies; one copy of some vertices with a coordinate's zero negated.
void split_vertices(TriangleMesh& mesh, std::mt19937& random, int copies) {
  const std::size_t original = mesh.positions.size();
  std::vector<std::vector<std::uint32_t>> copies_of(original);
  for (std::uint32_t v = 0; v < original; ++v) {
    copies_of[v].push_back(v);
    const int n = static_cast<int>(random() % static_cast<unsigned>(copies + 1));
    for (int c = 0; c < n; ++c) {
      Vector3d p = mesh.positions[v];
      if (random() % 4 == 0) {
        for (int k = 0; k < 3; ++k)
          if (p[k] == 0) p[k] = -0.0;
      }
      mesh.positions.push_back(p);
      copies_of[v].push_back(static_cast<std::uint32_t>(mesh.positions.size() - 1));
    }
  }
  for (Triangle& t : mesh.triangles) {
    for (std::uint32_t& v : t) v = copies_of[v][random() % copies_of[v].size()];
  }
}

// Triangles over a small pool of positions (so that many coincide after welding): any mixture
// of open, non-manifold, misoriented and degenerate.
TriangleMesh random_soup(std::mt19937& random, std::size_t positions, std::size_t triangles) {
  TriangleMesh mesh;
  for (std::size_t v = 0; v < positions; ++v) {
    // Coordinates from a few values, zeros of both signs among them.
    static constexpr double kValues[] = {0.0, -0.0, 1.0, -1.0, 0.5, 0.25};
    mesh.positions.emplace_back(kValues[random() % 6], kValues[random() % 6], kValues[random() % 3]);
  }
  for (std::size_t t = 0; t < triangles; ++t) {
    mesh.triangles.push_back({static_cast<std::uint32_t>(random() % positions),
                              static_cast<std::uint32_t>(random() % positions),
                              static_cast<std::uint32_t>(random() % positions)});
  }
  return mesh;
}

// Damage to a closed mesh: flipped, removed, repeated and degenerate triangles.
int damage(TriangleMesh& mesh, std::mt19937& random, int count) {
  for (int d = 0; d < count && !mesh.triangles.empty(); ++d) {
    const std::size_t t = random() % mesh.triangles.size();
    switch (random() % 4) {
      case 0: std::swap(mesh.triangles[t][1], mesh.triangles[t][2]); break;
      case 1: mesh.triangles.erase(mesh.triangles.begin() + static_cast<std::ptrdiff_t>(t)); break;
      case 2: mesh.triangles.push_back(mesh.triangles[t]); break;
      default: mesh.triangles[t][2] = mesh.triangles[t][0]; break;
    }
  }
  return count;
}

// A mesh's bytes as a glTF buffer may hold them: float32 (exact for every position used here)
// or float64, indices of 8, 16 or 32 bits or none (corners listed in order), with padding
// between elements filled with garbage.
struct Stored {
  std::vector<std::uint8_t> positions, indices;
  TriangleMeshView view;
};

Stored store(const TriangleMesh& mesh, bool float32, TriangleMeshView::Indices index_type) {
  Stored s;
  std::vector<Vector3d> vertices;
  if (index_type == TriangleMeshView::Indices::kNone) {
    for (const Triangle& t : mesh.triangles)
      for (std::uint32_t v : t) vertices.push_back(mesh.positions[v]);
  } else {
    vertices = mesh.positions;
  }
  const std::size_t size = float32 ? 4 : 8, stride = 3 * size + 4;
  s.positions.assign(vertices.size() * stride + 1, 0xA5);
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    for (int c = 0; c < 3; ++c) {
      std::uint8_t* at = s.positions.data() + v * stride + c * size;
      if (float32) {
        const auto value = static_cast<float>(vertices[v][c]);
        std::memcpy(at, &value, 4);
      } else {
        std::memcpy(at, &vertices[v][c], 8);
      }
    }
  }
  s.view.positions = s.positions.data();
  s.view.position_stride = stride;
  s.view.vertex_count = vertices.size();
  s.view.position_type = float32 ? TriangleMeshView::Positions::kFloat32 : TriangleMeshView::Positions::kFloat64;
  s.view.triangle_count = mesh.triangles.size();
  s.view.index_type = index_type;
  if (index_type != TriangleMeshView::Indices::kNone) {
    const std::size_t isize = index_type == TriangleMeshView::Indices::kUint8    ? 1
                              : index_type == TriangleMeshView::Indices::kUint16 ? 2
                                                                                 : 4;
    s.view.index_stride = isize + 1;
    s.indices.assign(3 * mesh.triangles.size() * s.view.index_stride + 1, 0x5A);
    for (std::size_t k = 0; k < 3 * mesh.triangles.size(); ++k) {
      const std::uint32_t v = mesh.triangles[k / 3][k % 3];
      std::memcpy(s.indices.data() + k * s.view.index_stride, &v, isize);  // Little-endian low bytes.
    }
    s.view.indices = s.indices.data();
  }
  return s;
}

TriangleMeshView::Indices index_type_for(std::size_t vertices, std::mt19937& random) {
  using Idx = TriangleMeshView::Indices;
  std::vector<Idx> fits{Idx::kNone, Idx::kUint32};
  if (vertices <= 65535) fits.push_back(Idx::kUint16);
  if (vertices <= 255) fits.push_back(Idx::kUint8);
  return fits[random() % fits.size()];
}

// The mesh in `parts` pieces (triangles dealt out at random, every piece with all the
// positions), each piece in a random storage; the same counts must come out of every form.
void check_all_forms(const TriangleMesh& mesh, std::mt19937& random, int parts, SurfaceTopology& seen) {
  std::vector<TriangleMesh> pieces(static_cast<std::size_t>(parts));
  for (TriangleMesh& piece : pieces) piece.positions = mesh.positions;
  for (const Triangle& t : mesh.triangles) pieces[random() % pieces.size()].triangles.push_back(t);
  const SurfaceTopology want = reference_topology(pieces);
  expect_equal(analyze_surface(pieces), want);
  std::vector<Stored> stored;
  for (const TriangleMesh& piece : pieces) {
    stored.push_back(store(piece, random() % 2 == 0, index_type_for(piece.positions.size(), random)));
  }
  std::vector<TriangleMeshView> views;
  for (const Stored& s : stored) views.push_back(s.view);
  expect_equal(analyze_surface(views), want);
  // Shared by threads (the weld's slots claimed atomically, the rows in segments per thread):
  // the same counts, down to meshes with fewer vertices or triangles than threads.
  for (unsigned threads : {2u, 3u, 7u}) expect_equal(analyze_surface(views, threads), want);
  seen.triangles += want.triangles;
  seen.degenerate_triangles += want.degenerate_triangles;
  seen.boundary_edges += want.boundary_edges;
  seen.misoriented_edges += want.misoriented_edges;
  seen.nonmanifold_edges += want.nonmanifold_edges;
}

TEST(SurfaceReference, ClosedMeshesWithSplitVerticesInEveryStorage) {
  std::mt19937 random(20261125);
  SurfaceTopology seen;
  int closed = 0;
  for (int trial = 0; trial < 40; ++trial) {
    SCOPED_TRACE(::testing::Message() << "trial " << trial);
    TriangleMesh mesh = closed_octahedron(trial % 4);
    split_vertices(mesh, random, trial % 3);
    shuffle_mesh(mesh, random);
    const SurfaceTopology want = reference_topology({mesh});
    closed += want.closed() && want.consistently_oriented() && want.degenerate_triangles == 0;
    check_all_forms(mesh, random, 1 + trial % 3, seen);
  }
  EXPECT_EQ(closed, 40);  // Splitting vertices never opens a surface.
}

TEST(SurfaceReference, DamagedClosedMeshes) {
  std::mt19937 random(7);
  SurfaceTopology seen;
  for (int trial = 0; trial < 60; ++trial) {
    SCOPED_TRACE(::testing::Message() << "trial " << trial);
    TriangleMesh mesh = closed_octahedron(1 + trial % 3);
    damage(mesh, random, 1 + trial % 6);
    split_vertices(mesh, random, 1 + trial % 2);
    shuffle_mesh(mesh, random);
    check_all_forms(mesh, random, 1 + trial % 4, seen);
  }
  EXPECT_GT(seen.degenerate_triangles, 0u);
  EXPECT_GT(seen.boundary_edges, 0u);
  EXPECT_GT(seen.misoriented_edges, 0u);
  EXPECT_GT(seen.nonmanifold_edges, 0u);
}

// Two copies of one closed mesh, the second's vertices separate but at the same positions: each
// copy alone is closed, welded together every edge has four uses, two each way: shared, and the
// surface closed (its volume is twice the copy's, which the overlap check reports).
TEST(SurfaceReference, CoincidentCopiesShareEveryEdge) {
  std::mt19937 random(11);
  for (int level = 0; level < 3; ++level) {
    TriangleMesh mesh = closed_octahedron(level);
    const auto n = static_cast<std::uint32_t>(mesh.positions.size());
    const std::size_t faces = mesh.triangles.size();
    for (std::uint32_t v = 0; v < n; ++v) mesh.positions.push_back(mesh.positions[v]);
    for (std::size_t t = 0; t < faces; ++t) {
      const Triangle f = mesh.triangles[t];
      mesh.triangles.push_back({f[0] + n, f[1] + n, f[2] + n});
    }
    shuffle_mesh(mesh, random);
    const SurfaceTopology got = analyze_surface(std::vector<TriangleMesh>{mesh});
    expect_equal(got, reference_topology({mesh}));
    EXPECT_EQ(got.shared_edges, 3 * faces / 2);
    EXPECT_EQ(got.nonmanifold_edges, 0u);
    EXPECT_TRUE(got.closed());
  }
}

TEST(SurfaceReference, RandomTriangleSoups) {
  std::mt19937 random(3);
  SurfaceTopology seen;
  for (int trial = 0; trial < 80; ++trial) {
    SCOPED_TRACE(::testing::Message() << "trial " << trial);
    const std::size_t positions = 3 + random() % (trial < 40 ? 12 : 300);
    const std::size_t triangles = random() % (trial < 40 ? 20 : 600);
    check_all_forms(random_soup(random, positions, triangles), random, 1 + trial % 3, seen);
  }
  EXPECT_GT(seen.degenerate_triangles, 0u);
  EXPECT_GT(seen.boundary_edges, 0u);
  EXPECT_GT(seen.misoriented_edges, 0u);
  EXPECT_GT(seen.nonmanifold_edges, 0u);
}

}  // namespace
}  // namespace rdtf
