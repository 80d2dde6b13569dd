#include "rdtf/mass_properties.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <stdexcept>
#include <vector>

#include "../geometry/typed_view.h"
#include "tetrahedron_sums.h"

namespace rdtf {

namespace {

// The apex of the tetrahedra: the centre of the bounding box of the corners of up to kApexSamples
// triangles spread evenly over the mesh (nothing without triangles). Any point inside the mesh's
// bounding box keeps a far mesh's precision (every vertex is then within the box's diagonal of it);
// sampling spares a whole pass, which cost 15% of the kernel on a 5M-triangle mesh. Corners, not
// the accessor's vertices: glTF lets meshes share one POSITION accessor (packers merge them), and
// a vertex no triangle uses, 10 m away, cost a 2 cm part 1e-4 of its inertia (s100xform D5).
constexpr std::size_t kApexSamples = 4096;

// The apex, and the diagonal of the sampled box.
std::optional<std::pair<Eigen::Vector3d, double>> apex_of(std::span<const TriangleMeshView> pieces) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Eigen::Vector3d lo(kInf, kInf, kInf);
  Eigen::Vector3d hi = -lo;
  std::size_t triangles = 0;
  for (const TriangleMeshView& piece : pieces) triangles += piece.triangle_count;
  const std::size_t step = std::max<std::size_t>(1, triangles / kApexSamples);
  for (const TriangleMeshView& piece : pieces) {
    internal::with_typed_view(piece, [&](const auto& view) {
      for (std::size_t t = 0; t < view.triangle_count; t += step) {
        for (std::size_t c = 0; c < 3; ++c) {
          Eigen::Vector3d p;
          view.vertex(view.index(3 * t + c), p.data());
          lo = lo.cwiseMin(p);
          hi = hi.cwiseMax(p);
        }
      }
    });
  }
  if (!(lo.array() <= hi.array()).all()) return std::nullopt;
  return std::make_pair(Eigen::Vector3d(0.5 * (lo + hi)), (hi - lo).norm());
}

// The triangle loop, compiled twice on x86-64: for the baseline (SSE2) and for AVX, chosen by the
// processor at run time. The same operations in the same order, so both give the same bits
// (tests/inertia checks it). Each is a template over the mesh's storage, with the target on the
// template itself so that every instantiation gets it (a lambda inside would not).
template <typename View>
void add_view_baseline(detail::TetrahedronSums<double>& sums, const View& view,
                       const detail::Corner<double>& apex) {
  detail::add_mesh(sums, view, apex);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define RDTF_KERNEL_AVX 1
#else
#define RDTF_KERNEL_AVX 0
#endif

#if RDTF_KERNEL_AVX
template <typename View>
[[gnu::target("avx")]] void add_view_avx(detail::TetrahedronSums<double>& sums, const View& view,
                                         const detail::Corner<double>& apex) {
  detail::add_mesh(sums, view, apex);
}

bool processor_has_avx() {
  // libgcc's and compiler-rt's check includes the operating system's support (XGETBV).
  static const bool has = __builtin_cpu_supports("avx");
  return has;
}
#endif

void add_piece(detail::TetrahedronSums<double>& sums, const TriangleMeshView& piece,
               const Eigen::Vector3d& p_MoA_M, bool avx) {
  const detail::Corner<double> apex{p_MoA_M.x(), p_MoA_M.y(), p_MoA_M.z()};
  internal::with_typed_view(piece, [&](const auto& view) {
#if RDTF_KERNEL_AVX
    if (avx) {
      add_view_avx(sums, view, apex);
      return;
    }
#else
    (void)avx;
#endif
    add_view_baseline(sums, view, apex);
  });
}

}  // namespace

namespace detail {

bool kernel_available(KernelIsa isa) {
  switch (isa) {
    case KernelIsa::kAuto:
    case KernelIsa::kBaseline:
      return true;
    case KernelIsa::kAvx:
#if RDTF_KERNEL_AVX
      return processor_has_avx();
#else
      return false;
#endif
  }
  return false;
}

VolumeIntegrals integrate_solid(std::span<const TriangleMeshView> pieces, const Eigen::Affine3d& X,
                                KernelIsa isa) {
  // Sums in the mesh's own frame about a point inside its bounding box (p_MoA_M, the apex of
  // every tetrahedron), so that a mesh far from the origin keeps its precision.
  VolumeIntegrals result;
  const auto sampled = apex_of(pieces);
  if (!sampled) return result;  // No vertices at all.
  const Eigen::Vector3d* const p_MoA_M = &sampled->first;
  if (!kernel_available(isa)) throw std::invalid_argument("integrate_solid: no AVX on this processor");
  const bool avx = isa == KernelIsa::kAvx || (isa == KernelIsa::kAuto && kernel_available(KernelIsa::kAvx));
  detail::TetrahedronSums<double> sums;
  for (const TriangleMeshView& piece : pieces) {
    add_piece(sums, piece, *p_MoA_M, avx);
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
  result.extent = std::cbrt(scale) * sampled->second;
  if (volume == 0.0) {
    result.centroid = apex;
    return result;
  }
  const Eigen::Vector3d offset = first / volume;  // Centroid from the apex.
  result.centroid = apex + offset;
  result.second_central = second - volume * offset * offset.transpose();
  return result;
}

}  // namespace detail

VolumeIntegrals integrate_solid(std::span<const TriangleMeshView> pieces, const Eigen::Affine3d& X) {
  return detail::integrate_solid(pieces, X, detail::KernelIsa::kAuto);
}

VolumeIntegrals integrate_solid(std::span<const TriangleMesh> pieces, const Eigen::Affine3d& X) {
  std::vector<TriangleMeshView> views;
  views.reserve(pieces.size());
  for (const TriangleMesh& piece : pieces) views.push_back(TriangleMeshView::of(piece));
  return integrate_solid(views, X);
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
