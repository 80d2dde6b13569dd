// An indexed triangle mesh, the geometry every later stage works on.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace rdtf {

// Triangles wind counter-clockwise seen from the front (outside of a solid), glTF's rule.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

}  // namespace rdtf
