// Mass properties of closed triangle meshes from signed tetrahedra (RDTF paper, section 4.3),
// extended with the second moments so that the full inertia tensor comes out, and with any affine
// transform of the mesh (rotation, non-uniform or negative scale, shear).
//
// Frame naming follows Drake: p_LoC_L is the position of point C from the origin of frame L,
// expressed in L; I_C_L is an inertia tensor about point C, expressed in L.
#pragma once

#include <span>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rdtf/triangle_mesh.h"

namespace rdtf {

// The volume integrals of a solid, kept about its own centroid so that solids far from the frame
// origin (or from each other) combine without cancellation.
struct VolumeIntegrals {
  double volume = 0;                                     // m^3, signed: < 0 for inside-out
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();    // m
  Eigen::Matrix3d second_central = Eigen::Matrix3d::Zero();  // m^5: integral of (r-c)(r-c)^T dV
  // m: a length the solid spans, for judging whether its volume is 0 in earnest: the diagonal of
  // the box of the vertices sampled for the apex, times |det X|^(1/3). 0 without vertices.
  double extent = 0;
};

// Integrals over the solid bounded by the triangles of `pieces` (together one closed surface, as
// the primitives of one glTF mesh are), after mapping every vertex by X. A negative
// det(X.linear()) mirrors the solid and so flips its winding; that sign is corrected, so a valid
// mesh stays positive and an inside-out one comes out negative. Sums in the mesh's own frame
// about the centre of its vertices' bounding box, so that a mesh far from the origin (in its
// vertices or through X) keeps its precision, then maps the sums by X once (exact for affine X).
VolumeIntegrals integrate_solid(std::span<const TriangleMesh> pieces, const Eigen::Affine3d& X);

// The same on meshes read in place (the same result, bit for bit, for the same positions and
// triangles).
VolumeIntegrals integrate_solid(std::span<const TriangleMeshView> pieces, const Eigen::Affine3d& X);

namespace detail {
// Which compiled copy of the triangle loop runs. kAuto (what integrate_solid uses) picks AVX
// where the processor has it, else the baseline; tests and benchmarks force each to check that
// they agree bit for bit and to time them. Forcing one that kernel_available() says is not there
// throws std::invalid_argument.
enum class KernelIsa { kAuto, kBaseline, kAvx };
bool kernel_available(KernelIsa isa);
VolumeIntegrals integrate_solid(std::span<const TriangleMeshView> pieces, const Eigen::Affine3d& X,
                                KernelIsa isa);
}  // namespace detail

struct MassProperties {
  double volume = 0;                                         // m^3
  double mass = 0;                                           // kg
  Eigen::Vector3d center_of_mass = Eigen::Vector3d::Zero();  // p_LoLcm_L, m
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();         // I_Lcm_L, about the COM, kg m^2
};

// One solid of a body with its density (kg/m^3).
struct MassPiece {
  VolumeIntegrals integrals;
  double density = 0;
};

// Mass, centre of mass and inertia about it of a body made of solids (parallel-axis theorem about
// the common centre of mass). Volumes are taken as given (the caller decides on inside-out ones).
MassProperties combine(std::span<const MassPiece> pieces);

// The inertia about the centre of mass of a solid of uniform density: rho (tr(C) 1 - C).
Eigen::Matrix3d inertia_from_second_moment(const Eigen::Matrix3d& second_central, double density);

}  // namespace rdtf
