// The closed-surface counts by their definition, for tests of analyze_surface: weld by exact
// position with an ordered map keyed by the coordinates (+0.0 added, so -0 = +0), then tally each
// undirected edge's uses each way in another ordered map. Nothing of the fast path (hash table,
// rows laid out by counting, sorting networks) is shared with it.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "rdtf/mesh_checks.h"
#include "rdtf/triangle_mesh.h"

namespace rdtf::testing {

inline SurfaceTopology reference_topology(const std::vector<TriangleMesh>& pieces) {
  SurfaceTopology topology;
  std::map<std::tuple<double, double, double>, std::size_t> ids;
  std::map<std::pair<std::size_t, std::size_t>, std::pair<std::size_t, std::size_t>> uses;  // v < w: v->w, w->v
  for (const TriangleMesh& piece : pieces) {
    std::vector<std::size_t> welded;
    for (const Eigen::Vector3d& p : piece.positions) {
      welded.push_back(ids.emplace(std::make_tuple(p.x() + 0.0, p.y() + 0.0, p.z() + 0.0), ids.size()).first->second);
    }
    for (const auto& t : piece.triangles) {
      ++topology.triangles;
      const std::size_t v[3] = {welded[t[0]], welded[t[1]], welded[t[2]]};
      if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) {
        ++topology.degenerate_triangles;
        continue;
      }
      for (int k = 0; k < 3; ++k) {
        const std::size_t from = v[k], to = v[(k + 1) % 3];
        auto& counts = uses[{std::min(from, to), std::max(from, to)}];
        ++(from < to ? counts.first : counts.second);
      }
    }
  }
  for (const auto& [edge, counts] : uses) {
    const std::size_t total = counts.first + counts.second;
    if (total == 1) {
      ++topology.boundary_edges;
    } else if (total > 2) {
      ++(counts.first == counts.second ? topology.shared_edges : topology.nonmanifold_edges);
    } else if (counts.first != 1) {
      ++topology.misoriented_edges;
    }
  }
  return topology;
}

// Vertices renumbered and triangles reordered at random: the same surface, in another order.
inline void shuffle_mesh(TriangleMesh& mesh, std::mt19937& random) {
  std::vector<std::uint32_t> order(mesh.positions.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), random);
  std::vector<Eigen::Vector3d> positions(mesh.positions.size());
  for (std::size_t i = 0; i < order.size(); ++i) positions[order[i]] = mesh.positions[i];
  mesh.positions = positions;
  for (auto& t : mesh.triangles)
    for (std::uint32_t& v : t) v = order[v];
  std::shuffle(mesh.triangles.begin(), mesh.triangles.end(), random);
}

// Every count equal, and the verdicts they make.
inline void expect_equal(const SurfaceTopology& got, const SurfaceTopology& want) {
  EXPECT_EQ(got.triangles, want.triangles);
  EXPECT_EQ(got.degenerate_triangles, want.degenerate_triangles);
  EXPECT_EQ(got.boundary_edges, want.boundary_edges);
  EXPECT_EQ(got.misoriented_edges, want.misoriented_edges);
  EXPECT_EQ(got.nonmanifold_edges, want.nonmanifold_edges);
  EXPECT_EQ(got.shared_edges, want.shared_edges);
  EXPECT_EQ(got.closed(), want.closed());
  EXPECT_EQ(got.consistently_oriented(), want.consistently_oriented());
}

}  // namespace rdtf::testing
