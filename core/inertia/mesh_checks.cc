#include "rdtf/mesh_checks.h"

#include <bit>
#include <cstdint>
#include <cstring>
#include <vector>

namespace rdtf {
namespace {

std::uint64_t bits_of(double value) {
  value += 0.0;  // -0.0 and +0.0 are one position.
  std::uint64_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  return bits;
}

std::uint64_t mix(std::uint64_t x) {  // splitmix64's finaliser
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Welds vertices by exact position with an open-addressing table: one id per distinct position.
class Welder {
 public:
  explicit Welder(std::size_t expected) {
    std::size_t capacity = 16;
    while (capacity < 2 * expected) capacity *= 2;
    slots_.assign(capacity, kEmpty);
  }
  std::uint32_t id(const Eigen::Vector3d& p) {
    const std::uint64_t x = bits_of(p.x()), y = bits_of(p.y()), z = bits_of(p.z());
    std::size_t slot = mix(x ^ mix(y ^ mix(z))) & (slots_.size() - 1);
    for (;;) {
      const std::uint32_t found = slots_[slot];
      if (found == kEmpty) {
        slots_[slot] = static_cast<std::uint32_t>(positions_.size());
        positions_.push_back({x, y, z});
        return slots_[slot];
      }
      const auto& q = positions_[found];
      if (q[0] == x && q[1] == y && q[2] == z) return found;
      slot = (slot + 1) & (slots_.size() - 1);
    }
  }

 private:
  static constexpr std::uint32_t kEmpty = 0xffffffffu;
  std::vector<std::uint32_t> slots_;
  std::vector<std::array<std::uint64_t, 3>> positions_;
};

// LSD radix sort of 64-bit keys, 16 bits a pass: much faster than comparison sorting for the
// millions of edges of a large mesh.
void radix_sort(std::vector<std::uint64_t>& keys) {
  std::vector<std::uint64_t> scratch(keys.size());
  std::vector<std::size_t> counts(1 << 16);
  for (int shift = 0; shift < 64; shift += 16) {
    std::fill(counts.begin(), counts.end(), 0);
    for (std::uint64_t k : keys) ++counts[(k >> shift) & 0xffff];
    std::size_t total = 0;
    for (auto& c : counts) {
      const std::size_t n = c;
      c = total;
      total += n;
    }
    for (std::uint64_t k : keys) scratch[counts[(k >> shift) & 0xffff]++] = k;
    keys.swap(scratch);
  }
}

}  // namespace

SurfaceTopology analyze_surface(std::span<const TriangleMesh> pieces) {
  SurfaceTopology topology;
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  for (const TriangleMesh& piece : pieces) {
    vertices += piece.positions.size();
    triangles += piece.triangles.size();
  }
  Welder welder(vertices);
  // Each directed edge as one key: (low id << 33) | (high id << 1) | (goes high -> low). Sorting
  // brings the uses of one undirected edge together, with their directions. Ids fit 31 bits: the
  // accessor limits keep vertex counts far below 2^31.
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * triangles);
  for (const TriangleMesh& piece : pieces) {
    std::vector<std::uint32_t> welded(piece.positions.size());
    for (std::size_t i = 0; i < piece.positions.size(); ++i) welded[i] = welder.id(piece.positions[i]);
    for (const auto& t : piece.triangles) {
      ++topology.triangles;
      const std::uint64_t v[3] = {welded[t[0]], welded[t[1]], welded[t[2]]};
      if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
        ++topology.degenerate_triangles;
        continue;
      }
      for (int k = 0; k < 3; ++k) {
        const std::uint64_t from = v[k];
        const std::uint64_t to = v[(k + 1) % 3];
        edges.push_back(from < to ? (from << 33 | to << 1) : (to << 33 | from << 1 | 1));
      }
    }
  }
  radix_sort(edges);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    std::size_t backward = 0;
    while (j < edges.size() && (edges[j] >> 1) == (edges[i] >> 1)) backward += edges[j++] & 1;
    const std::size_t uses = j - i;
    if (uses == 1) {
      ++topology.boundary_edges;
    } else if (uses > 2) {
      ++topology.nonmanifold_edges;
    } else if (backward != 1) {
      ++topology.misoriented_edges;
    }
    i = j;
  }
  return topology;
}

}  // namespace rdtf
