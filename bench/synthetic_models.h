// Large models made on the spot for benchmarks (nothing big is committed): a closed UV sphere
// with about the requested number of triangles, as a GLB.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "rdtf/triangle_mesh.h"

namespace rdtf::bench {

// A closed, outward-wound UV sphere of radius r centred at `centre`.
TriangleMesh uv_sphere(std::size_t approximate_triangles, double radius,
                       const Eigen::Vector3d& centre = Eigen::Vector3d::Zero());

// A one-node GLB holding `mesh` (float32 positions, uint32 indices).
std::vector<std::uint8_t> mesh_glb(const TriangleMesh& mesh);

}  // namespace rdtf::bench
