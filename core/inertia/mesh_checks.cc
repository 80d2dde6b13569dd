#include "rdtf/mesh_checks.h"

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace rdtf {
namespace {

struct PositionHash {
  std::size_t operator()(const Eigen::Vector3d& p) const {
    const std::hash<double> h;
    std::size_t seed = h(p.x());
    seed ^= h(p.y()) + 0x9e3779b97f4a7c15ull + (seed << 6) + (seed >> 2);
    seed ^= h(p.z()) + 0x9e3779b97f4a7c15ull + (seed << 6) + (seed >> 2);
    return seed;
  }
};

struct PositionEqual {
  bool operator()(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const { return a == b; }
};

}  // namespace

SurfaceTopology analyze_surface(std::span<const TriangleMesh> pieces) {
  SurfaceTopology topology;
  std::unordered_map<Eigen::Vector3d, std::uint32_t, PositionHash, PositionEqual> ids;
  // Directed edges as (from << 32 | to) over welded vertex ids.
  std::vector<std::uint64_t> edges;
  for (const TriangleMesh& piece : pieces) {
    std::vector<std::uint32_t> welded(piece.positions.size());
    for (std::size_t i = 0; i < piece.positions.size(); ++i) {
      welded[i] = ids.try_emplace(piece.positions[i], static_cast<std::uint32_t>(ids.size()))
                      .first->second;
    }
    for (const auto& t : piece.triangles) {
      ++topology.triangles;
      const std::uint32_t v[3] = {welded[t[0]], welded[t[1]], welded[t[2]]};
      if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
        ++topology.degenerate_triangles;
        continue;
      }
      for (int k = 0; k < 3; ++k) {
        edges.push_back(static_cast<std::uint64_t>(v[k]) << 32 | v[(k + 1) % 3]);
      }
    }
  }
  std::sort(edges.begin(), edges.end());
  // Count each undirected edge's uses in both directions.
  std::vector<std::uint64_t> undirected;
  undirected.reserve(edges.size());
  for (std::uint64_t e : edges) {
    const std::uint64_t from = e >> 32;
    const std::uint64_t to = e & 0xffffffffu;
    undirected.push_back(std::min(from, to) << 32 | std::max(from, to));
  }
  std::sort(undirected.begin(), undirected.end());
  for (std::size_t i = 0; i < undirected.size();) {
    std::size_t j = i;
    while (j < undirected.size() && undirected[j] == undirected[i]) ++j;
    const std::size_t uses = j - i;
    const std::uint64_t low = undirected[i] >> 32;
    const std::uint64_t high = undirected[i] & 0xffffffffu;
    const auto forward = static_cast<std::size_t>(
        std::upper_bound(edges.begin(), edges.end(), low << 32 | high) -
        std::lower_bound(edges.begin(), edges.end(), low << 32 | high));
    const std::size_t backward = uses - forward;
    if (uses == 1) {
      ++topology.boundary_edges;
    } else if (uses > 2) {
      ++topology.nonmanifold_edges;
    } else if (forward != 1 || backward != 1) {
      ++topology.misoriented_edges;
    }
    i = j;
  }
  return topology;
}

}  // namespace rdtf
