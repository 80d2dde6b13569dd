// An indexed triangle mesh, the geometry every later stage works on.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace rdtf {

// Triangles wind counter-clockwise seen from the front (outside of a solid), glTF's rule.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// The same mesh read where it lies, without copying it: in a glTF buffer (float positions, 8-,
// 16- or 32-bit indices or none, any byte strides) or in a TriangleMesh. Triangle t has the
// corners index(3t), index(3t + 1), index(3t + 2); without indices, index(k) = k. Issue 6: copying
// a million-triangle model's buffers into a TriangleMesh (24 MB of doubles and indices, every
// page of it faulted in) cost more than the mass properties themselves.
//
// A view borrows: whatever it points into must outlive it.
struct TriangleMeshView {
  enum class Positions : std::uint8_t { kFloat32, kFloat64 };
  enum class Indices : std::uint8_t { kNone, kUint8, kUint16, kUint32 };

  const std::uint8_t* positions = nullptr;  // x, y, z of vertex v at positions + v * position_stride
  std::size_t position_stride = 0;          // bytes
  std::size_t vertex_count = 0;
  Positions position_type = Positions::kFloat64;
  const std::uint8_t* indices = nullptr;  // index k at indices + k * index_stride
  std::size_t index_stride = 0;           // bytes
  std::size_t triangle_count = 0;
  Indices index_type = Indices::kNone;

  static TriangleMeshView of(const TriangleMesh& mesh) {
    TriangleMeshView view;
    view.positions = reinterpret_cast<const std::uint8_t*>(mesh.positions.data());
    view.position_stride = sizeof(Eigen::Vector3d);
    view.vertex_count = mesh.positions.size();
    view.position_type = Positions::kFloat64;
    view.indices = reinterpret_cast<const std::uint8_t*>(mesh.triangles.data());
    view.index_stride = sizeof(std::uint32_t);
    view.triangle_count = mesh.triangles.size();
    view.index_type = Indices::kUint32;
    return view;
  }
};

static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double) &&
              sizeof(std::array<std::uint32_t, 3>) == 3 * sizeof(std::uint32_t));

}  // namespace rdtf
