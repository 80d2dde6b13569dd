#include "rdtf/mass_properties.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "tetrahedron_sums.h"

namespace rdtf {

namespace {

// The apex of the tetrahedra: the centre of the bounding box of up to kApexSamples vertices
// spread evenly over the mesh (nothing without vertices). Any point inside the mesh's bounding box
// keeps a far mesh's precision (every vertex is then within the box's diagonal of it); sampling
// spares a whole pass over the vertices, which cost 15% of the kernel on a 5M-triangle mesh.
constexpr std::size_t kApexSamples = 4096;

std::optional<Eigen::Vector3d> apex_of(std::span<const TriangleMesh> pieces) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Eigen::Vector3d lo(kInf, kInf, kInf);
  Eigen::Vector3d hi = -lo;
  std::size_t vertices = 0;
  for (const TriangleMesh& piece : pieces) vertices += piece.positions.size();
  const std::size_t step = std::max<std::size_t>(1, vertices / kApexSamples);
  for (const TriangleMesh& piece : pieces) {
    for (std::size_t i = 0; i < piece.positions.size(); i += step) {
      lo = lo.cwiseMin(piece.positions[i]);
      hi = hi.cwiseMax(piece.positions[i]);
    }
  }
  if (!(lo.array() <= hi.array()).all()) return std::nullopt;
  return 0.5 * (lo + hi);
}

// The triangle loop, compiled twice on x86-64 (baseline SSE2 and AVX, chosen at load time by
// the processor): the same operations in the same order, so both give the same bits.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
[[gnu::target_clones("avx", "default")]]
#endif
void add_piece(detail::TetrahedronSums<double>& sums, const TriangleMesh& piece,
               const Eigen::Vector3d& p_MoA_M) {
  detail::add_mesh(sums, piece.positions, piece.triangles, {p_MoA_M.x(), p_MoA_M.y(), p_MoA_M.z()});
}

}  // namespace

VolumeIntegrals integrate_solid(std::span<const TriangleMesh> pieces, const Eigen::Affine3d& X) {
  // Sums in the mesh's own frame about a point inside its bounding box (p_MoA_M, the apex of
  // every tetrahedron), so that a mesh far from the origin keeps its precision.
  VolumeIntegrals result;
  const std::optional<Eigen::Vector3d> p_MoA_M = apex_of(pieces);
  if (!p_MoA_M) return result;  // No vertices at all.
  detail::TetrahedronSums<double> sums;
  for (const TriangleMesh& piece : pieces) {
    add_piece(sums, piece, *p_MoA_M);
  }
  // Each tetrahedron (A, a, b, c) maps to (X A, X a, X b, X c): about the mapped apex, the volume
  // scales by det(L), the first moment by det(L) L and the second by det(L) L (.) L^T, exactly.
  // A mirroring map (det < 0) turns counter-clockwise triangles clockwise: |det| undoes that.
  const Eigen::Matrix3d L = X.linear();
  const double scale = std::abs(L.determinant());
  Eigen::Matrix3d second_M;
  const auto& s = sums.second120;
  second_M << s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2];
  const double volume = scale * sums.six_volume / 6.0;
  const Eigen::Vector3d first =  // About the mapped apex.
      scale * L * Eigen::Vector3d(sums.first24[0], sums.first24[1], sums.first24[2]) / 24.0;
  const Eigen::Matrix3d second = scale * L * (second_M / 120.0) * L.transpose();
  const Eigen::Vector3d apex = X * *p_MoA_M;
  result.volume = volume;
  if (volume == 0.0) {
    result.centroid = apex;
    return result;
  }
  const Eigen::Vector3d offset = first / volume;  // Centroid from the apex.
  result.centroid = apex + offset;
  result.second_central = second - volume * offset * offset.transpose();
  return result;
}

Eigen::Matrix3d inertia_from_second_moment(const Eigen::Matrix3d& second_central, double density) {
  return density * (second_central.trace() * Eigen::Matrix3d::Identity() - second_central);
}

MassProperties combine(std::span<const MassPiece> pieces) {
  MassProperties result;
  Eigen::Vector3d weighted_centroid = Eigen::Vector3d::Zero();
  for (const MassPiece& piece : pieces) {
    const double mass = piece.density * piece.integrals.volume;
    result.volume += piece.integrals.volume;
    result.mass += mass;
    weighted_centroid += mass * piece.integrals.centroid;
  }
  if (result.mass == 0.0) return result;
  result.center_of_mass = weighted_centroid / result.mass;
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  // Mass-weighted, about the common COM.
  for (const MassPiece& piece : pieces) {
    const double mass = piece.density * piece.integrals.volume;
    const Eigen::Vector3d d = piece.integrals.centroid - result.center_of_mass;
    second += piece.density * piece.integrals.second_central + mass * d * d.transpose();
  }
  result.inertia = inertia_from_second_moment(second, 1.0);
  // Exact symmetry: sums of outer products are symmetric up to rounding; make it bitwise.
  result.inertia = 0.5 * (result.inertia + result.inertia.transpose()).eval();
  return result;
}

}  // namespace rdtf
