#include "rdtf/mass_properties.h"

#include <limits>

namespace rdtf {

VolumeIntegrals integrate_solid(std::span<const TriangleMesh> pieces, const Eigen::Affine3d& X) {
  // Bounding box of the mapped vertices: its centre is the reference point of the sums.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const TriangleMesh& piece : pieces) {
    for (const Eigen::Vector3d& p : piece.positions) {
      const Eigen::Vector3d q = X * p;
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
  }
  VolumeIntegrals result;
  if (!(lo.array() <= hi.array()).all()) return result;  // No vertices at all.
  const Eigen::Vector3d reference = 0.5 * (lo + hi);

  // Tetrahedron (0, a, b, c) with D = a.(b x c): volume D/6, first moment D(a+b+c)/24,
  // second moment D/120 ((a+b+c)(a+b+c)^T + aa^T + bb^T + cc^T).
  double six_volume = 0;
  Eigen::Vector3d first24 = Eigen::Vector3d::Zero();
  // The six distinct entries of the symmetric second moment, times 120: xx yy zz xy yz zx.
  double s_xx = 0, s_yy = 0, s_zz = 0, s_xy = 0, s_yz = 0, s_zx = 0;
  std::vector<Eigen::Vector3d> mapped;
  for (const TriangleMesh& piece : pieces) {
    mapped.resize(piece.positions.size());
    for (std::size_t i = 0; i < mapped.size(); ++i) mapped[i] = X * piece.positions[i] - reference;
    for (const auto& t : piece.triangles) {
      const Eigen::Vector3d& a = mapped[t[0]];
      const Eigen::Vector3d& b = mapped[t[1]];
      const Eigen::Vector3d& c = mapped[t[2]];
      const double D = a.dot(b.cross(c));
      const Eigen::Vector3d s = a + b + c;
      six_volume += D;
      first24 += D * s;
      s_xx += D * (s.x() * s.x() + a.x() * a.x() + b.x() * b.x() + c.x() * c.x());
      s_yy += D * (s.y() * s.y() + a.y() * a.y() + b.y() * b.y() + c.y() * c.y());
      s_zz += D * (s.z() * s.z() + a.z() * a.z() + b.z() * b.z() + c.z() * c.z());
      s_xy += D * (s.x() * s.y() + a.x() * a.y() + b.x() * b.y() + c.x() * c.y());
      s_yz += D * (s.y() * s.z() + a.y() * a.z() + b.y() * b.z() + c.y() * c.z());
      s_zx += D * (s.z() * s.x() + a.z() * a.x() + b.z() * b.x() + c.z() * c.x());
    }
  }
  Eigen::Matrix3d second120;
  second120 << s_xx, s_xy, s_zx, s_xy, s_yy, s_yz, s_zx, s_yz, s_zz;
  // A mirroring map turns counter-clockwise triangles clockwise: undo the sign it introduced.
  const double orientation = X.linear().determinant() < 0 ? -1.0 : 1.0;
  const double volume = orientation * six_volume / 6.0;
  const Eigen::Vector3d first = orientation * first24 / 24.0;  // About the reference point.
  const Eigen::Matrix3d second = orientation * second120 / 120.0;
  result.volume = volume;
  if (volume == 0.0) {
    result.centroid = reference;
    return result;
  }
  const Eigen::Vector3d offset = first / volume;  // Centroid from the reference point.
  result.centroid = reference + offset;
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
