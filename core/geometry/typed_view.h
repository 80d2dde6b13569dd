// A TriangleMeshView with its element types known at compile time, so that the loops over a
// mesh (mass properties, surface check) are compiled once per storage layout instead of
// switching on the layout per element.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "rdtf/triangle_mesh.h"

namespace rdtf::internal {

struct NoIndices {};  // Index type of a mesh without indices: index(k) = k.

// P: float or double; I: std::uint8_t, std::uint16_t, std::uint32_t or NoIndices.
template <typename P, typename I>
struct TypedView {
  const std::uint8_t* positions;
  std::size_t position_stride;
  std::size_t vertex_count;
  const std::uint8_t* indices;
  std::size_t index_stride;
  std::size_t triangle_count;

  [[gnu::always_inline]] std::uint32_t index(std::size_t k) const {
    if constexpr (std::is_same_v<I, NoIndices>) {
      return static_cast<std::uint32_t>(k);
    } else {
      I value;
      std::memcpy(&value, indices + k * index_stride, sizeof(I));
      return value;
    }
  }
  // Vertex v's coordinates as doubles (exact: a float converts to double without rounding).
  [[gnu::always_inline]] void vertex(std::uint32_t v, double out[3]) const {
    P xyz[3];
    std::memcpy(xyz, positions + std::size_t{v} * position_stride, sizeof(xyz));
    out[0] = xyz[0];
    out[1] = xyz[1];
    out[2] = xyz[2];
  }
  using Coordinate = P;
  // x and y of vertex v in one 16-byte vector (double positions only).
  template <typename Pair>
  [[gnu::always_inline]] Pair pair(std::uint32_t v) const {
    static_assert(sizeof(Pair) == 2 * sizeof(P));
    Pair value;
    std::memcpy(&value, positions + std::size_t{v} * position_stride, sizeof(Pair));
    return value;
  }
  // Coordinate c of vertex v as stored. (Read through memcpy: the bytes are a glTF buffer's,
  // with no float or double object in them, and need not be aligned for the type.)
  [[gnu::always_inline]] P coordinate(std::uint32_t v, int c) const {
    P value;
    std::memcpy(&value, positions + std::size_t{v} * position_stride + c * sizeof(P), sizeof(P));
    return value;
  }
};

// Calls f(TypedView<P, I>) for the view's layout and returns what f returns.
template <typename F>
decltype(auto) with_typed_view(const TriangleMeshView& view, F&& f) {
  using Pos = TriangleMeshView::Positions;
  using Idx = TriangleMeshView::Indices;
  const auto with_positions = [&]<typename I>() -> decltype(auto) {
    if (view.position_type == Pos::kFloat32) {
      return f(TypedView<float, I>{view.positions, view.position_stride, view.vertex_count,
                                   view.indices, view.index_stride, view.triangle_count});
    }
    return f(TypedView<double, I>{view.positions, view.position_stride, view.vertex_count,
                                  view.indices, view.index_stride, view.triangle_count});
  };
  switch (view.index_type) {
    case Idx::kUint8:
      return with_positions.template operator()<std::uint8_t>();
    case Idx::kUint16:
      return with_positions.template operator()<std::uint16_t>();
    case Idx::kUint32:
      return with_positions.template operator()<std::uint32_t>();
    case Idx::kNone:
    default:
      return with_positions.template operator()<NoIndices>();
  }
}

}  // namespace rdtf::internal
