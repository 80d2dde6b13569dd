#include "rdtf/mesh_checks.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
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
// Each slot keeps 32 bits of the position's hash beside its id, so that probing past other
// positions rarely has to read them (those reads are cache misses: they were half the time of
// the surface check on a million-triangle mesh).
class Welder {
 public:
  explicit Welder(std::size_t expected) {
    std::size_t capacity = 16;
    while (capacity < 2 * expected) capacity *= 2;
    slots_.assign(capacity, kEmpty);
    first_.reserve(expected);
  }
  std::uint32_t id(const Eigen::Vector3d& p) {
    const std::uint64_t x = bits_of(p.x()), y = bits_of(p.y()), z = bits_of(p.z());
    const std::uint64_t hash = mix(x ^ (y * 0x9e3779b97f4a7c15ull) ^ (z * 0xc2b2ae3d27d4eb4full));
    const std::uint64_t tag = hash & 0xffffffff00000000ull;
    for (std::size_t slot = hash & (slots_.size() - 1);; slot = (slot + 1) & (slots_.size() - 1)) {
      const std::uint64_t entry = slots_[slot];
      if (entry == kEmpty) {
        const auto fresh = static_cast<std::uint32_t>(first_.size());
        slots_[slot] = tag | fresh;
        first_.push_back(&p);
        return fresh;
      }
      if ((entry & 0xffffffff00000000ull) != tag) continue;
      const auto found = static_cast<std::uint32_t>(entry);
      const Eigen::Vector3d& q = *first_[found];
      if (bits_of(q.x()) == x && bits_of(q.y()) == y && bits_of(q.z()) == z) return found;
    }
  }
  std::size_t size() const { return first_.size(); }

 private:
  // No id reaches 2^32 - 1 (vertex counts are capped far below), so this is never a real entry.
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  std::vector<std::uint64_t> slots_;                // hash tag << 32 | id
  std::vector<const Eigen::Vector3d*> first_;  // The first vertex seen at each position.
};

// Every directed edge of the welded surface, grouped by the vertex it leaves (compressed rows):
// the edges leaving v go to targets[begin[v] .. begin[v + 1]), sorted. Built by counting, which
// costs two passes over the triangles instead of sorting millions of edge keys.
struct DirectedEdges {
  std::vector<std::uint32_t> begin;
  std::unique_ptr<std::uint32_t[]> targets;  // Not zeroed first: every entry is written.

  std::span<const std::uint32_t> from(std::uint32_t v) const {
    return {targets.get() + begin[v], targets.get() + begin[v + 1]};
  }
  // How many edges go from v to w.
  std::size_t count(std::uint32_t v, std::uint32_t w) const {
    const auto out = from(v);
    if (out.size() <= 16) return static_cast<std::size_t>(std::count(out.begin(), out.end(), w));
    const auto [lo, hi] = std::equal_range(out.begin(), out.end(), w);
    return static_cast<std::size_t>(hi - lo);
  }
};

// Most vertices have about six edges: insertion sort beats std::sort's set-up there.
void sort_small(std::uint32_t* first, std::uint32_t* last) {
  if (last - first > 16) {
    std::sort(first, last);
    return;
  }
  for (std::uint32_t* i = first + 1; i < last; ++i) {
    const std::uint32_t value = *i;
    std::uint32_t* j = i;
    for (; j > first && *(j - 1) > value; --j) *j = *(j - 1);
    *j = value;
  }
}

// The pieces with their vertices welded: welded[offset[p] + i] is vertex i of piece p's id.
struct WeldedPieces {
  std::span<const TriangleMesh> pieces;
  std::vector<std::size_t> offset;
  std::vector<std::uint32_t> welded;
  std::size_t distinct = 0;

  // Calls f(v0, v1, v2) with the welded corners of every triangle whose corners differ.
  template <typename F>
  void for_each_proper_triangle(F&& f) const {
    for (std::size_t p = 0; p < pieces.size(); ++p) {
      const std::uint32_t* ids = welded.data() + offset[p];
      for (const auto& t : pieces[p].triangles) {
        const std::uint32_t v0 = ids[t[0]], v1 = ids[t[1]], v2 = ids[t[2]];
        if (v0 != v1 && v1 != v2 && v0 != v2) f(v0, v1, v2);
      }
    }
  }
};

DirectedEdges directed_edges(const WeldedPieces& mesh) {
  DirectedEdges edges;
  // Count the edges leaving each vertex (each corner leaves by one), then turn the counts into
  // end offsets and place every edge by decrementing: begin[v] ends at v's first edge.
  edges.begin.assign(mesh.distinct + 1, 0);
  mesh.for_each_proper_triangle([&](std::uint32_t v0, std::uint32_t v1, std::uint32_t v2) {
    ++edges.begin[v0];
    ++edges.begin[v1];
    ++edges.begin[v2];
  });
  std::uint32_t total = 0;
  for (auto& b : edges.begin) b = total += b;
  edges.targets.reset(new std::uint32_t[total]);
  std::uint32_t* targets = edges.targets.get();
  mesh.for_each_proper_triangle([&](std::uint32_t v0, std::uint32_t v1, std::uint32_t v2) {
    targets[--edges.begin[v0]] = v1;
    targets[--edges.begin[v1]] = v2;
    targets[--edges.begin[v2]] = v0;
  });
  for (std::size_t v = 0; v < mesh.distinct; ++v) {
    sort_small(targets + edges.begin[v], targets + edges.begin[v + 1]);
  }
  return edges;
}

// Classifies every undirected edge by its uses: `forward` times one way, `backward` the other.
void classify(std::size_t forward, std::size_t backward, SurfaceTopology& topology) {
  const std::size_t uses = forward + backward;
  if (uses == 1) {
    ++topology.boundary_edges;
  } else if (uses > 2) {
    ++topology.nonmanifold_edges;
  } else if (forward != 1) {
    ++topology.misoriented_edges;  // Both uses go the same way.
  }
}

}  // namespace

SurfaceTopology analyze_surface(std::span<const TriangleMesh> pieces) {
  SurfaceTopology topology;
  WeldedPieces mesh{pieces, {}, {}, 0};
  std::size_t vertices = 0;
  for (const TriangleMesh& piece : pieces) {
    mesh.offset.push_back(vertices);
    vertices += piece.positions.size();
  }
  Welder welder(vertices);
  mesh.welded.resize(vertices);
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    for (std::size_t i = 0; i < pieces[p].positions.size(); ++i) {
      mesh.welded[mesh.offset[p] + i] = welder.id(pieces[p].positions[i]);
    }
  }
  mesh.distinct = welder.size();
  const DirectedEdges edges = directed_edges(mesh);
  for (const TriangleMesh& piece : pieces) topology.triangles += piece.triangles.size();
  // Three directed edges for every triangle with three distinct corners.
  topology.degenerate_triangles = topology.triangles - edges.begin.back() / 3;
  // Each undirected edge {v, w} once: from v when v < w or when nothing goes back from w.
  for (std::uint32_t v = 0; v < mesh.distinct; ++v) {
    const auto out = edges.from(v);
    for (std::size_t i = 0; i < out.size();) {
      const std::uint32_t w = out[i];
      std::size_t forward = 0;
      while (i < out.size() && out[i] == w) ++forward, ++i;
      const std::size_t backward = edges.count(w, v);
      if (backward == 0 || v < w) classify(forward, backward, topology);
    }
  }
  return topology;
}

}  // namespace rdtf
