#include "synthetic_models.h"

#include <cmath>
#include <cstring>
#include <numbers>

#include <nlohmann/json.hpp>

#include "rdtf/glb.h"

namespace rdtf::bench {

TriangleMesh uv_sphere(std::size_t approximate_triangles, double radius, const Eigen::Vector3d& centre) {
  // rings * segments * 2 triangles, with segments = 2 * rings.
  const auto rings = static_cast<std::size_t>(std::max(3.0, std::sqrt(approximate_triangles / 4.0)));
  const std::size_t segments = 2 * rings;
  TriangleMesh mesh;
  mesh.positions.push_back(centre + Eigen::Vector3d(0, radius, 0));  // North pole.
  for (std::size_t i = 1; i < rings; ++i) {
    const double theta = std::numbers::pi * static_cast<double>(i) / static_cast<double>(rings);
    for (std::size_t j = 0; j < segments; ++j) {
      const double phi = 2 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(segments);
      mesh.positions.push_back(centre + radius * Eigen::Vector3d(std::sin(theta) * std::cos(phi),
                                                                 std::cos(theta),
                                                                 -std::sin(theta) * std::sin(phi)));
    }
  }
  mesh.positions.push_back(centre + Eigen::Vector3d(0, -radius, 0));  // South pole.
  const auto south = static_cast<std::uint32_t>(mesh.positions.size() - 1);
  auto ring = [&](std::size_t i, std::size_t j) {
    return static_cast<std::uint32_t>(1 + (i - 1) * segments + j % segments);
  };
  for (std::size_t j = 0; j < segments; ++j) mesh.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
  for (std::size_t i = 1; i + 1 < rings; ++i) {
    for (std::size_t j = 0; j < segments; ++j) {
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  }
  for (std::size_t j = 0; j < segments; ++j) {
    mesh.triangles.push_back({south, ring(rings - 1, j + 1), ring(rings - 1, j)});
  }
  return mesh;
}

std::vector<std::uint8_t> mesh_glb(const TriangleMesh& mesh) {
  const std::size_t vertex_bytes = mesh.positions.size() * 12;
  const std::size_t index_bytes = mesh.triangles.size() * 12;
  std::vector<std::uint8_t> bin(vertex_bytes + index_bytes);
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = -lo;
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const Eigen::Vector3f p = mesh.positions[i].cast<float>();
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    std::memcpy(bin.data() + i * 12, p.data(), 12);
  }
  std::memcpy(bin.data() + vertex_bytes, mesh.triangles.data(), index_bytes);
  const nlohmann::ordered_json document = {
      {"asset", {{"version", "2.0"}, {"generator", "rdtf bench"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"name", "sphere"}, {"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"buffers", {{{"byteLength", bin.size()}}}},
      {"bufferViews", {{{"buffer", 0}, {"byteLength", vertex_bytes}, {"target", 34962}},
                       {{"buffer", 0}, {"byteOffset", vertex_bytes}, {"byteLength", index_bytes}, {"target", 34963}}}},
      {"accessors", {{{"bufferView", 0}, {"componentType", 5126}, {"count", mesh.positions.size()},
                      {"type", "VEC3"}, {"min", {lo.x(), lo.y(), lo.z()}}, {"max", {hi.x(), hi.y(), hi.z()}}},
                     {{"bufferView", 1}, {"componentType", 5125}, {"count", mesh.triangles.size() * 3},
                      {"type", "SCALAR"}}}}};
  return make_glb(document.dump(), bin);
}

}  // namespace rdtf::bench
