#include "rdtf/mesh_checks.h"

#include <algorithm>
#include <cmath>
#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <span>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <vector>

#include "../geometry/big_arrays.h"
#include "../geometry/typed_view.h"

namespace rdtf {
namespace {

using internal::BigArray;

// Runs share(0) .. share(n - 1) at once: share 0 on this thread, each other on a thread of its own
// (where none can be had, on this one after share 0: the shares of one call are independent of
// each other). The first exception of a share is thrown here, once every share is done.
template <typename F>
void run_shares(unsigned n, const F& share) {
  std::vector<std::exception_ptr> errors(n);
  const auto guarded = [&](unsigned i) {
    try {
      share(i);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  };
  // Room first, so that nothing below allocates once a thread runs: a std::thread destroyed
  // joinable (an exception past it) would end the process, with shares still reading this frame.
  std::vector<std::thread> threads;
  std::vector<unsigned> here;
  threads.reserve(n);
  here.reserve(n);
  for (unsigned i = 1; i < n; ++i) {
    try {
      threads.emplace_back(guarded, i);
    } catch (...) {  // std::system_error, or std::bad_alloc for the thread's own state.
      here.push_back(i);
    }
  }
  guarded(0);
  for (unsigned i : here) guarded(i);
  for (std::thread& thread : threads) thread.join();
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
}

// The part [n * share / shares, n * (share + 1) / shares) of n things.
std::size_t share_begin(std::size_t n, unsigned share, unsigned shares) { return n * share / shares; }

// A position as the bits of its three coordinates as doubles (floats convert exactly), -0.0 and
// +0.0 made one: two vertices weld exactly when these are equal, whatever their storage.
struct PositionBits {
  std::uint64_t x, y, z;
  bool operator==(const PositionBits&) const = default;
};

std::uint64_t bits_of(double value) {
  value += 0.0;  // -0.0 and +0.0 are one position.
  std::uint64_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  return bits;
}

// `cell` 0: the exact position. Otherwise each coordinate rounded to a multiple of `cell` (the
// near weld of analyze_surface).
template <typename View>
PositionBits position_bits(const View& view, std::uint32_t v, double cell) {
  double p[3];
  view.vertex(v, p);
  if (cell > 0) [[unlikely]] {
    for (double& c : p) c = std::nearbyint(c / cell);
  }
  return {bits_of(p[0]), bits_of(p[1]), bits_of(p[2])};
}

// The high and low halves of a 128-bit product folded together (wyhash's "mum"): one
// multiplication spreads both operands' bits over the whole result, upwards and downwards.
__extension__ using Uint128 = unsigned __int128;  // GCC and Clang on 64-bit targets.

std::uint64_t mum(std::uint64_t a, std::uint64_t b) {
  const Uint128 product = static_cast<Uint128>(a) * b;
  return static_cast<std::uint64_t>(product) ^ static_cast<std::uint64_t>(product >> 64);
}

// A float's double has its low 29 bits zero, so hashes that only carry bits upwards (x ^ y * K1
// ^ z * K2, the previous one) keep little of a float position: on a float UV sphere that one
// averaged 4.3 probes per vertex and 1.5 false tag matches (each a cache miss) where this one
// gives 1.45 and none; a finaliser per coordinate gave the same spread at twice the cost.
std::uint64_t hash_of(const PositionBits& p) {
  return mum(mum(p.x ^ 0xa0761d6478bd642full, p.y ^ 0xe7037ed1a0b428dbull) ^ 0x8ebc6af09c88c6e3ull,
             p.z ^ 0x589965cc75374cc3ull);
}

// Vertex numbers across all pieces: piece p's vertex i is offset[p] + i.
struct Pieces {
  std::span<const TriangleMeshView> views;
  std::vector<std::size_t> offset;  // One per piece, and the total last.
  double cell = 0;                  // Positions welded within it (position_bits); 0: exactly.

  explicit Pieces(std::span<const TriangleMeshView> v) : views(v) {
    std::size_t total = 0;
    for (const TriangleMeshView& view : views) {
      offset.push_back(total);
      total += view.vertex_count;
    }
    offset.push_back(total);
  }
  std::size_t vertices() const { return offset.back(); }
  PositionBits bits(std::size_t global) const {
    const std::size_t p =
        static_cast<std::size_t>(std::upper_bound(offset.begin(), offset.end(), global) - offset.begin()) - 1;
    return internal::with_typed_view(views[p], [&](const auto& view) {
      return position_bits(view, static_cast<std::uint32_t>(global - offset[p]), cell);
    });
  }
};

// Welds vertices by exact position with an open-addressing table: each vertex gets the number
// of the first vertex at its position (its representative). Each slot keeps 32 bits of the
// position's hash beside that number, so that probing past other positions rarely has to read
// them. The number is kept plus one, so that an all-zero slot is empty: the table needs no fill
// of its own (a 16 MB memset for a million triangles), it comes zeroed, which memory fresh from
// the kernel is without cost. The table (8 MB for half a million vertices) is far larger than the caches, so every
// lookup is a cache miss: the hashes of the next vertices are computed ahead and their slots
// prefetched, so that many misses are in flight at once instead of one (issue 6: the waits on
// this table were a quarter of a million-triangle conversion).
class Welder {
 public:
  // Slots for `vertices` vertices, at most half full.
  static std::size_t capacity_for(std::size_t vertices) {
    std::size_t capacity = 16;
    while (capacity < 2 * vertices) capacity *= 2;
    return capacity;
  }
  // `slots`: capacity_for(vertices) entries of memory, all zero (empty).
  Welder(std::uint64_t* slots, std::size_t vertices) : slots_(slots), mask_(capacity_for(vertices) - 1) {}

  // rep[i] = the representative of vertex i of `view` (global vertex number first + i), for i in
  // [begin, end). kShared: other threads weld other vertices into the same table meanwhile.
  template <bool kShared, typename View>
  void weld(const View& view, std::size_t first, std::size_t begin, std::size_t end, const Pieces& pieces,
            std::uint32_t* rep) {
    constexpr std::size_t kBlock = 32;
    std::array<PositionBits, kBlock> bits;
    std::array<std::uint64_t, kBlock> hash;
    for (std::size_t start = begin; start < end; start += kBlock) {
      const std::size_t n = std::min(kBlock, end - start);
      for (std::size_t k = 0; k < n; ++k) {
        bits[k] = position_bits(view, static_cast<std::uint32_t>(start + k), pieces.cell);
        hash[k] = hash_of(bits[k]);
        __builtin_prefetch(slots_ + (hash[k] & mask_));
      }
      for (std::size_t k = 0; k < n; ++k) {
        rep[start + k] =
            representative<kShared>(bits[k], hash[k], static_cast<std::uint32_t>(first + start + k), pieces);
      }
    }
  }

 private:
  // Shared, a slot is claimed by compare-and-swap: of two threads welding the same position at
  // once, one claims the slot and the other finds it there, as it would have a moment later, so
  // every vertex of a position gets the one that claimed it (which one depends on the timing,
  // the counts of analyze_surface do not). The slot holds nothing but the number: the positions
  // compared are the input's, which nobody writes.
  template <bool kShared>
  std::uint32_t representative(const PositionBits& p, std::uint64_t hash, std::uint32_t global,
                               const Pieces& pieces) {
    const std::uint64_t tag = hash & 0xffffffff00000000ull;
    for (std::size_t slot = hash & mask_;; slot = (slot + 1) & mask_) {
      std::uint64_t entry;
      if constexpr (kShared) {
        entry = std::atomic_ref<std::uint64_t>(slots_[slot]).load(std::memory_order_relaxed);
      } else {
        entry = slots_[slot];
      }
      if (entry == kEmpty) {
        const std::uint64_t mine = tag | (std::uint64_t{global} + 1);
        if constexpr (kShared) {
          if (std::atomic_ref<std::uint64_t>(slots_[slot]).compare_exchange_strong(entry, mine,
                                                                                   std::memory_order_relaxed)) {
            return global;
          }
          // Taken meanwhile: `entry` is now the vertex that took it, checked as any other.
        } else {
          slots_[slot] = mine;
          return global;
        }
      }
      if ((entry & 0xffffffff00000000ull) != tag) continue;
      const auto found = static_cast<std::uint32_t>(entry) - 1;
      if (pieces.bits(found) == p) return found;
    }
  }

  // Vertex numbers stay below 2^32 - 1 (analyze_surface checks), so an entry's low half, the
  // number plus one, is never zero, nor is the entry.
  static constexpr std::uint64_t kEmpty = 0;
  std::uint64_t* slots_;  // hash tag << 32 | (representative + 1)
  std::size_t mask_;
};

// Classifies every undirected edge by its uses: `forward` times one way, `backward` the other.
void classify(std::size_t forward, std::size_t backward, SurfaceTopology& topology) {
  const std::size_t uses = forward + backward;
  if (uses == 1) {
    ++topology.boundary_edges;
  } else if (uses > 2) {
    ++(forward == backward ? topology.shared_edges : topology.nonmanifold_edges);
  } else if (forward != 1) {
    ++topology.misoriented_edges;  // Both uses go the same way.
  }
}

template <typename T>
[[gnu::always_inline]] inline void compare_exchange(T& a, T& b) {
  const T lo = std::min(a, b), hi = std::max(a, b);  // Conditional moves: no branch to mispredict.
  a = lo;
  b = hi;
}

// Sorts a row of edges. Rows of 2, 4, 6 and 8 (the sizes of a closed surface's rows, and nearly
// all of them) go through sorting networks, which have no data-dependent branches: with them and
// the pair check in classify_surface, the rows of a million-triangle sphere took 1.9 ms instead
// of the 4.0 ms of insertion sort, which mispredicted its way through them.
template <typename T>
void sort_row(T* e, std::size_t n) {
  switch (n) {
    case 2:
      compare_exchange(e[0], e[1]);
      return;
    case 4:  // Optimal networks (Knuth, TAOCP 5.3.4; Dobbelaere's list).
      compare_exchange(e[0], e[2]), compare_exchange(e[1], e[3]);
      compare_exchange(e[0], e[1]), compare_exchange(e[2], e[3]);
      compare_exchange(e[1], e[2]);
      return;
    case 6:
      compare_exchange(e[0], e[5]), compare_exchange(e[1], e[3]), compare_exchange(e[2], e[4]);
      compare_exchange(e[1], e[2]), compare_exchange(e[3], e[4]);
      compare_exchange(e[0], e[3]), compare_exchange(e[2], e[5]);
      compare_exchange(e[0], e[1]), compare_exchange(e[2], e[3]), compare_exchange(e[4], e[5]);
      compare_exchange(e[1], e[2]), compare_exchange(e[3], e[4]);
      return;
    case 8:
      compare_exchange(e[0], e[2]), compare_exchange(e[1], e[3]), compare_exchange(e[4], e[6]),
          compare_exchange(e[5], e[7]);
      compare_exchange(e[0], e[4]), compare_exchange(e[1], e[5]), compare_exchange(e[2], e[6]),
          compare_exchange(e[3], e[7]);
      compare_exchange(e[0], e[1]), compare_exchange(e[2], e[3]), compare_exchange(e[4], e[5]),
          compare_exchange(e[6], e[7]);
      compare_exchange(e[2], e[4]), compare_exchange(e[3], e[5]);
      compare_exchange(e[1], e[4]), compare_exchange(e[3], e[6]);
      compare_exchange(e[1], e[2]), compare_exchange(e[3], e[4]), compare_exchange(e[5], e[6]);
      return;
    default:
      break;
  }
  if (n > 16) {
    std::sort(e, e + n);
    return;
  }
  for (std::size_t i = 1; i < n; ++i) {
    const T value = e[i];
    std::size_t j = i;
    for (; j > 0 && e[j - 1] > value; --j) e[j] = e[j - 1];
    e[j] = value;
  }
}

// Calls f(v0, v1, v2) with the welded corners of every triangle whose corners differ, of share
// `share` of `shares` of each piece's triangles.
// Two halves of each piece's triangles go through the loop side by side: consecutive triangles
// share vertices, so their updates of the same row counter form a chain of dependent memory
// operations, and a second, independent chain beside it took the two passes over a
// million-triangle sphere from 5.2 to 3.8 ms. (Four chains were slower.) Only the order of the
// calls changes, which nothing depends on.
template <typename F>
void for_each_proper_triangle(const Pieces& pieces, const std::uint32_t* welded, unsigned share, unsigned shares,
                              F&& f) {
  for (std::size_t p = 0; p < pieces.views.size(); ++p) {
    const std::uint32_t* ids = welded + pieces.offset[p];
    internal::with_typed_view(pieces.views[p], [&](const auto& view) {
      const auto triangle = [&](std::size_t t) {
        const std::uint32_t v0 = ids[view.index(3 * t)], v1 = ids[view.index(3 * t + 1)],
                            v2 = ids[view.index(3 * t + 2)];
        if (v0 != v1 && v1 != v2 && v0 != v2) [[likely]] f(v0, v1, v2);
      };
      const std::size_t begin = share_begin(view.triangle_count, share, shares);
      const std::size_t end = share_begin(view.triangle_count, share + 1, shares);
      const std::size_t half = (end - begin) / 2;
      for (std::size_t t = begin; t < begin + half; ++t) {
        triangle(t);
        triangle(half + t);
      }
      if ((end - begin) % 2 != 0) triangle(end - 1);
    });
  }
}

// Every undirected edge {v, w} of the welded surface, v < w (by representative), is filed once
// per use under v, its smaller end, as (w << 1 | d), d = 1 when that use goes from w to v. A row
// sorted thus holds each edge's uses together, forward ones first, so every edge is classified
// from its row alone: no lookup in another vertex's row (those were random reads over 12 MB).
// The rows are laid out by counting (two passes over the triangles), not by sorting millions of
// keys.
//
// Memory: one block, in huge pages (big_arrays.h), reused between the two phases: the weld's
// table first, then the row counts and the edges in the same bytes. Every fresh megabyte costs
// time here (zeroed by the kernel on first touch), and this saves 10 MB of the 26 MB that
// separate arrays needed for a million triangles.
//
// Shared by `shares` threads (analyze_surface's `threads`), each phase is split: the weld by
// vertices (one table, slots claimed atomically), the counting and the filing by triangles (each
// share counts its triangles' edges in a row count array of its own, and files them into a
// segment of each row of their own: share 0's first, then share 1's, ...), the rows by vertex.
// No two threads write the same memory, and every count comes out as with one.
template <typename Edge>
void classify_surface(const Pieces& pieces, unsigned shares, SurfaceTopology& topology) {
  const std::size_t vertices = pieces.vertices();
  const std::size_t slots = Welder::capacity_for(vertices);
  const std::size_t rep_words = (vertices + 1) / 2;  // uint32 representatives, in 64-bit words.
  const std::size_t count_words = (vertices + 2) / 2;
  const std::size_t edge_words = (3 * topology.triangles * sizeof(Edge) + 7) / 8;  // At most.
  BigArray<std::uint64_t> scratch(rep_words + std::max(slots, count_words + edge_words), internal::ZeroFilled{});
  auto* const rep = reinterpret_cast<std::uint32_t*>(scratch.data());
  {
    Welder welder(scratch.data() + rep_words, vertices);
    run_shares(shares, [&](unsigned share) {
      for (std::size_t p = 0; p < pieces.views.size(); ++p) {
        internal::with_typed_view(pieces.views[p], [&](const auto& view) {
          const std::size_t begin = share_begin(view.vertex_count, share, shares);
          const std::size_t end = share_begin(view.vertex_count, share + 1, shares);
          if (shares > 1) {
            welder.weld<true>(view, pieces.offset[p], begin, end, pieces, rep + pieces.offset[p]);
          } else {
            welder.weld<false>(view, pieces.offset[p], begin, end, pieces, rep + pieces.offset[p]);
          }
        });
      }
    });
  }
  // The table is done with: its bytes become share 0's row counts and the rows; the other shares'
  // counts come zeroed in a block of their own.
  BigArray<std::uint32_t> other_counts((shares - 1) * (vertices + 1), internal::ZeroFilled{});
  const auto count_of = [&](unsigned share) {
    return share == 0 ? reinterpret_cast<std::uint32_t*>(scratch.data() + rep_words)
                      : other_counts.data() + (share - 1) * (vertices + 1);
  };
  auto* const out = reinterpret_cast<Edge*>(scratch.data() + rep_words + count_words);
  run_shares(shares, [&](unsigned share) {
    std::uint32_t* const count = count_of(share);
    if (share == 0) std::fill_n(count, vertices + 1, 0u);
    for_each_proper_triangle(pieces, rep, share, shares, [&](std::uint32_t v0, std::uint32_t v1, std::uint32_t v2) {
      ++count[std::min(v0, v1)];
      ++count[std::min(v1, v2)];
      ++count[std::min(v2, v0)];
    });
  });
  // Counts to end offsets, each share's segment of a row after the ones before it; placing each
  // edge then decrements its share's offset, so share 0's ends at the row's start.
  std::size_t total = 0;
  for (std::size_t v = 0; v <= vertices; ++v) {
    for (unsigned share = 0; share < shares; ++share) {
      std::uint32_t& count = count_of(share)[v];
      count = static_cast<std::uint32_t>(total += count);
    }
  }
  topology.degenerate_triangles = topology.triangles - total / 3;
  run_shares(shares, [&](unsigned share) {
    std::uint32_t* const count = count_of(share);
    const auto file = [&](std::uint32_t from, std::uint32_t to) {
      // Without a branch on the direction, which is as good as random.
      const std::uint32_t lo = std::min(from, to), hi = std::max(from, to);
      out[--count[lo]] = static_cast<Edge>(Edge{hi} << 1 | Edge{from > to});
    };
    for_each_proper_triangle(pieces, rep, share, shares, [&](std::uint32_t v0, std::uint32_t v1, std::uint32_t v2) {
      file(v0, v1);
      file(v1, v2);
      file(v2, v0);
    });
  });
  const std::uint32_t* const row_start = count_of(0);
  std::vector<SurfaceTopology> found(shares);
  run_shares(shares, [&](unsigned share) {
    SurfaceTopology mine;  // Counted here, not in `found`: its neighbours share a cache line.
    const std::size_t last = share_begin(vertices, share + 1, shares);
    for (std::size_t v = share_begin(vertices, share, shares); v < last; ++v) {
      Edge* row = out + row_start[v];
      const std::size_t n = row_start[v + 1] - row_start[v];
      sort_row(row, n);
      // A closed, consistently wound surface's rows are pairs (w << 1, w << 1 | 1) of distinct w:
      // each edge used once each way, which changes no count. Checked without branches first.
      // (Rows of vertices that are not representatives are empty.)
      if (n % 2 == 0) {
        Edge odd = 0;
        for (std::size_t i = 0; i < n; i += 2) odd |= (row[i] & 1) | (row[i + 1] ^ (row[i] + 1));
        if (odd == 0) continue;
      }
      Edge* const end = row + n;
      while (row < end) {
        const Edge w = *row >> 1;
        std::size_t forward = 0, backward = 0;
        for (; row < end && (*row >> 1) == w; ++row) ++((*row & 1) != 0 ? backward : forward);
        classify(forward, backward, mine);
      }
    }
    found[share] = mine;
  });
  for (const SurfaceTopology& part : found) {
    topology.boundary_edges += part.boundary_edges;
    topology.nonmanifold_edges += part.nonmanifold_edges;
    topology.shared_edges += part.shared_edges;
    topology.misoriented_edges += part.misoriented_edges;
  }
}

}  // namespace

SurfaceTopology analyze_surface(std::span<const TriangleMeshView> views) { return analyze_surface(views, 1); }

SurfaceTopology analyze_surface(std::span<const TriangleMeshView> views, unsigned threads) {
  // Each share beyond the first costs a thread and a row count array of 4 bytes a vertex.
  constexpr unsigned kMaxShares = 64;
  const unsigned shares = std::clamp(threads, 1u, kMaxShares);
  SurfaceTopology topology;
  const Pieces pieces(views);
  for (const TriangleMeshView& view : views) topology.triangles += view.triangle_count;
  // Vertices are numbered in 32 bits, 2^32 - 1 excluded (the weld keeps number + 1), and rows are
  // offsets into 3 x triangles edges, also in 32 bits; glTF input is capped far below
  // (LoadLimits::max_accessor_count, max_triangles).
  constexpr std::size_t kMax = std::numeric_limits<std::uint32_t>::max();
  if (pieces.vertices() >= kMax || topology.triangles >= kMax / 3) {
    throw std::length_error("analyze_surface: 2^32 - 1 vertices, or a third of it in triangles, or more");
  }
  // An edge is filed as its far end's number shifted left once: 32 bits hold that below 2^31.
  const auto classify = [&](const Pieces& welded, SurfaceTopology& result) {
    if (welded.vertices() <= (std::size_t{1} << 31)) {
      classify_surface<std::uint32_t>(welded, shares, result);
    } else {
      classify_surface<std::uint64_t>(welded, shares, result);
    }
  };
  classify(pieces, topology);
  if (topology.boundary_edges == 0) return topology;
  // Open by exact position: weld again within 2^-30 of the part's largest coordinate, far below what float32
  // tells apart across it (2^-24), so no opening a modeller made is closed. A seam generated by
  // sin(2 pi) != 0 (three.js's cylinders, spheres, cones, tori: vertices 1e-17 m apart across the
  // seam) opened every curved primitive, a false MESH_OPEN that also left it out of the overlap
  // check (s90tools D3).
  // The largest coordinate of a vertex a triangle uses: one no triangle uses (an accessor shared
  // with another part, 1e7 m away) welded a 1 mm gap shut (s100xform D5).
  double extent = 0;
  for (const TriangleMeshView& view : views) {
    internal::with_typed_view(view, [&](const auto& typed) {
      for (std::size_t k = 0; k < 3 * view.triangle_count; ++k) {
        double p[3];
        typed.vertex(typed.index(k), p);
        for (const double c : p) {
          if (std::isfinite(c)) extent = std::max(extent, std::abs(c));
        }
      }
    });
  }
  Pieces near(views);
  near.cell = std::ldexp(extent, -30);
  if (!(near.cell > 0) || !std::isfinite(near.cell)) return topology;
  SurfaceTopology near_topology;
  near_topology.triangles = topology.triangles;
  classify(near, near_topology);
  return near_topology.boundary_edges < topology.boundary_edges ? near_topology : topology;
}

SurfaceTopology analyze_surface(std::span<const TriangleMesh> meshes) {
  std::vector<TriangleMeshView> views;
  views.reserve(meshes.size());
  for (const TriangleMesh& mesh : meshes) views.push_back(TriangleMeshView::of(mesh));
  return analyze_surface(views);
}

}  // namespace rdtf
