// Closed-form checks of integrate_solid + combine (volume, centroid and the full inertia tensor
// about the centre of mass), and of analyze_surface on small hand-built meshes.
//
// Every mesh is built here, from exact inputs, and every expected value comes from a closed form
// derived in a comment next to it. The tolerance is a relative 1e-9 throughout: these are double
// computations on exact (or correctly rounded) inputs, so any larger error is a bug.

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "rdtf/mass_properties.h"
#include "rdtf/mesh_checks.h"
#include "rdtf/triangle_mesh.h"

namespace rdtf {
namespace {

constexpr double kRel = 1e-9;
constexpr double kPi = std::numbers::pi;

using Eigen::Affine3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// ------------------------------------------------------------------------------------------------
// Meshes.

using Triangle = std::array<std::uint32_t, 3>;

// Axis-aligned box [lo, hi]: 8 shared vertices (index = x + 2y + 4z, bit set = hi on that axis)
// and 12 triangles, counter-clockwise seen from outside.
TriangleMesh make_box(const Vector3d& lo, const Vector3d& hi) {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.positions.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                                (i & 4) ? hi.z() : lo.z());
  }
  mesh.triangles = {
      {0, 2, 3}, {0, 3, 1},  // -z
      {4, 5, 7}, {4, 7, 6},  // +z
      {0, 1, 5}, {0, 5, 4},  // -y
      {2, 6, 7}, {2, 7, 3},  // +y
      {0, 4, 6}, {0, 6, 2},  // -x
      {1, 3, 7}, {1, 7, 5},  // +x
  };
  return mesh;
}

TriangleMesh make_box(double a, double b, double c) {
  return make_box(Vector3d(-a / 2, -b / 2, -c / 2), Vector3d(a / 2, b / 2, c / 2));
}

// The same box with every face's vertices duplicated (24 vertices, as an exporter splitting normals
// writes it): the same surface once welded by position.
TriangleMesh make_box_split_faces(const Vector3d& lo, const Vector3d& hi) {
  const TriangleMesh shared = make_box(lo, hi);
  TriangleMesh mesh;
  for (std::size_t face = 0; face < 6; ++face) {
    const Triangle& t0 = shared.triangles[2 * face];
    const Triangle& t1 = shared.triangles[2 * face + 1];
    // The face's quad is t0 = (p, q, r), t1 = (p, r, s).
    const std::uint32_t base = static_cast<std::uint32_t>(mesh.positions.size());
    for (std::uint32_t v : {t0[0], t0[1], t0[2], t1[2]}) mesh.positions.push_back(shared.positions[v]);
    mesh.triangles.push_back({base, base + 1, base + 2});
    mesh.triangles.push_back({base, base + 2, base + 3});
  }
  return mesh;
}

// Regular n-gon prism: base polygon of circumradius r centred on (cx, cy) in the plane z = z0,
// first vertex at angle `phase`, extruded to z0 + h. Caps are fans from vertex 0.
TriangleMesh make_prism(int n, double r, double h, double phase, const Vector3d& base_center) {
  TriangleMesh mesh;
  for (int level = 0; level < 2; ++level) {
    for (int k = 0; k < n; ++k) {
      const double angle = phase + 2 * kPi * k / n;
      mesh.positions.push_back(base_center +
                               Vector3d(r * std::cos(angle), r * std::sin(angle), level * h));
    }
  }
  const auto b = [](int k) { return static_cast<std::uint32_t>(k); };
  const auto t = [n](int k) { return static_cast<std::uint32_t>(n + k); };
  for (int k = 1; k + 1 < n; ++k) {
    mesh.triangles.push_back({b(0), b(k + 1), b(k)});  // Bottom, seen from -z.
    mesh.triangles.push_back({t(0), t(k), t(k + 1)});  // Top, seen from +z.
  }
  for (int k = 0; k < n; ++k) {
    const int next = (k + 1) % n;
    mesh.triangles.push_back({b(k), b(next), t(next)});
    mesh.triangles.push_back({b(k), t(next), t(k)});
  }
  return mesh;
}

// Tetrahedron (0,0,0), (a,0,0), (0,b,0), (0,0,c), faces counter-clockwise from outside.
TriangleMesh make_tetrahedron(double a, double b, double c) {
  TriangleMesh mesh;
  mesh.positions = {Vector3d(0, 0, 0), Vector3d(a, 0, 0), Vector3d(0, b, 0), Vector3d(0, 0, c)};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

TriangleMesh reversed(TriangleMesh mesh) {
  for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
  return mesh;
}

TriangleMesh translated(TriangleMesh mesh, const Vector3d& offset) {
  for (Vector3d& p : mesh.positions) p += offset;
  return mesh;
}

// The fixtures are checked independently of the code under test: for a convex solid every
// triangle's normal (b - a) x (c - a) must point away from an interior point.
void expect_outward(const TriangleMesh& mesh, const Vector3d& interior) {
  for (const Triangle& t : mesh.triangles) {
    const Vector3d& a = mesh.positions[t[0]];
    const Vector3d& b = mesh.positions[t[1]];
    const Vector3d& c = mesh.positions[t[2]];
    const Vector3d normal = (b - a).cross(c - a);
    EXPECT_GT(normal.dot((a + b + c) / 3 - interior), 0.0) << "fixture triangle wound inward";
  }
}

// ------------------------------------------------------------------------------------------------
// Comparisons, all relative.

::testing::AssertionResult RelNear(double actual, double expected, double rel = kRel) {
  const double error = std::abs(actual - expected);
  if (error <= rel * std::abs(expected)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "actual " << actual << " expected " << expected << " relative error "
         << error / std::abs(expected) << " > " << rel;
}

// Vectors: error relative to `scale` (a length of the problem, e.g. the body's size), since a
// centroid may be at or near the origin.
::testing::AssertionResult VecNear(const Vector3d& actual, const Vector3d& expected, double scale,
                                   double rel = kRel) {
  const double error = (actual - expected).cwiseAbs().maxCoeff();
  if (error <= rel * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "actual [" << actual.transpose() << "] expected [" << expected.transpose()
         << "] error " << error << " > " << rel << " * " << scale;
}

// Matrices: every entry within rel * (largest entry of the expected matrix), so that zero
// products of inertia are checked against the tensor's size.
::testing::AssertionResult MatNear(const Matrix3d& actual, const Matrix3d& expected,
                                   double rel = kRel) {
  const double scale = expected.cwiseAbs().maxCoeff();
  const double error = (actual - expected).cwiseAbs().maxCoeff();
  if (error <= rel * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\nactual\n"
                                       << actual << "\nexpected\n"
                                       << expected << "\nmax error " << error
                                       << " relative " << error / scale << " > " << rel;
}

// Inertia about the COM of a solid box of mass m and edge lengths (a, b, c) along its axes.
Matrix3d box_inertia(double m, double a, double b, double c) {
  return Vector3d(m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12)
      .asDiagonal();
}

// One solid of uniform density through the public pipeline.
MassProperties solid(const TriangleMesh& mesh, const Affine3d& X, double density) {
  const std::vector<TriangleMesh> pieces{mesh};
  const std::vector<MassPiece> parts{{integrate_solid(pieces, X), density}};
  return combine(parts);
}

VolumeIntegrals integrals(const TriangleMesh& mesh, const Affine3d& X = Affine3d::Identity()) {
  const std::vector<TriangleMesh> pieces{mesh};
  return integrate_solid(pieces, X);
}

Affine3d translation(const Vector3d& t) {
  Affine3d X = Affine3d::Identity();
  X.translation() = t;
  return X;
}

Eigen::Quaterniond test_rotation() {
  return Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
}

// ------------------------------------------------------------------------------------------------
// integrate_solid + combine.

TEST(MassProperties, FixturesAreWoundOutward) {
  expect_outward(make_box(Vector3d(0, 0, 0), Vector3d(1, 2, 3)), Vector3d(0.5, 1, 1.5));
  expect_outward(make_box_split_faces(Vector3d(0, 0, 0), Vector3d(1, 2, 3)), Vector3d(0.5, 1, 1.5));
  for (int n : {3, 6, 17}) expect_outward(make_prism(n, 1.0, 2.0, 0.3, Vector3d(1, 2, 3)), Vector3d(1, 2, 4));
  expect_outward(make_tetrahedron(1, 2, 3), Vector3d(0.25, 0.5, 0.75));
}

// Unit cube: V = 1, centroid at its centre, I = m/6 * identity (m (1 + 1) / 12 on each axis).
TEST(MassProperties, UnitCubeAtOrigin) {
  const double density = 1000;
  const auto mp = solid(make_box(1, 1, 1), Affine3d::Identity(), density);
  EXPECT_TRUE(RelNear(mp.volume, 1.0));
  EXPECT_TRUE(RelNear(mp.mass, 1000.0));
  EXPECT_TRUE(VecNear(mp.center_of_mass, Vector3d::Zero(), 1.0));
  EXPECT_TRUE(MatNear(mp.inertia, Matrix3d::Identity() * 1000.0 / 6));
}

TEST(MassProperties, UnitCubeOffsetInVerticesAndByTransform) {
  const double density = 7.5;
  const Vector3d offset(3, -2, 5);
  // The cube [0,1]^3 moved by `offset`, once in its vertices and once by X.
  const TriangleMesh cube = make_box(Vector3d(0, 0, 0), Vector3d(1, 1, 1));
  const Vector3d expected_com = offset + Vector3d(0.5, 0.5, 0.5);
  for (const auto& mp : {solid(translated(cube, offset), Affine3d::Identity(), density),
                         solid(cube, translation(offset), density)}) {
    EXPECT_TRUE(RelNear(mp.volume, 1.0));
    EXPECT_TRUE(RelNear(mp.mass, 7.5));
    EXPECT_TRUE(VecNear(mp.center_of_mass, expected_com, 1.0));
    EXPECT_TRUE(MatNear(mp.inertia, Matrix3d::Identity() * 7.5 / 6));
  }
}

// X = T * R * S maps the box a x b x c (centred at p0 in its own frame) to a box of edges
// (sx a, sy b, sz c) along the columns of R, centred at t + R S p0: I = R diag(...) R^T.
TEST(MassProperties, RotatedAndScaledBox) {
  const double a = 0.4, b = 1.5, c = 2.25;
  const Vector3d p0(0.1, -0.3, 0.7);
  const TriangleMesh box = make_box(p0 - Vector3d(a, b, c) / 2, p0 + Vector3d(a, b, c) / 2);
  const Vector3d s(1.5, 0.25, 3.0);
  const Vector3d t(0.5, -1.25, 2.0);
  const Matrix3d R = test_rotation().toRotationMatrix();
  const Affine3d X = Eigen::Translation3d(t) * test_rotation() * Eigen::Scaling(s);
  const double density = 2700;
  const auto mp = solid(box, X, density);

  const double A = s.x() * a, B = s.y() * b, C = s.z() * c;
  const double volume = A * B * C;
  const double m = density * volume;
  EXPECT_TRUE(RelNear(mp.volume, volume));
  EXPECT_TRUE(RelNear(mp.mass, m));
  EXPECT_TRUE(VecNear(mp.center_of_mass, t + R * s.cwiseProduct(p0), C));
  EXPECT_TRUE(MatNear(mp.inertia, R * box_inertia(m, A, B, C) * R.transpose()));
}

// A negative scale mirrors the box. The mirror image of a box is a box with the absolute edge
// lengths, centred at the mirrored centre; its volume must stay positive.
TEST(MassProperties, MirroredBox) {
  const double a = 0.4, b = 1.5, c = 2.25;
  const Vector3d p0(0.1, -0.3, 0.7);
  const TriangleMesh box = make_box(p0 - Vector3d(a, b, c) / 2, p0 + Vector3d(a, b, c) / 2);
  const Vector3d t(0.5, -1.25, 2.0);
  const Matrix3d R = test_rotation().toRotationMatrix();
  const double density = 1000;
  for (const Vector3d& s : {Vector3d(-1.5, 0.25, 3.0), Vector3d(-1.5, -0.25, -3.0)}) {
    SCOPED_TRACE(::testing::Message() << "scale " << s.transpose());
    const Affine3d X = Eigen::Translation3d(t) * test_rotation() * Eigen::Scaling(s);
    ASSERT_LT(X.linear().determinant(), 0);
    const auto mp = solid(box, X, density);
    const double A = std::abs(s.x()) * a, B = std::abs(s.y()) * b, C = std::abs(s.z()) * c;
    const double m = density * A * B * C;
    EXPECT_GT(mp.volume, 0);
    EXPECT_TRUE(RelNear(mp.volume, A * B * C));
    EXPECT_TRUE(RelNear(mp.mass, m));
    EXPECT_TRUE(VecNear(mp.center_of_mass, t + R * s.cwiseProduct(p0), C));
    EXPECT_TRUE(MatNear(mp.inertia, R * box_inertia(m, A, B, C) * R.transpose()));
  }
}

// A mirrored tetrahedron, whose products of inertia change sign with the mirror: for the mirror
// M = diag(-1, 1, 1) the mirrored solid has centroid M c and inertia M I M (x-y and x-z products
// flip, y-z stays).
TEST(MassProperties, MirroredTetrahedron) {
  const double a = 1.0, b = 2.0, c = 3.0;
  const TriangleMesh tet = make_tetrahedron(a, b, c);
  const auto original = solid(tet, Affine3d::Identity(), 1.0);
  Affine3d X = Affine3d::Identity();
  const Matrix3d M = Vector3d(-1, 1, 1).asDiagonal();
  X.linear() = M;
  const auto mirrored = solid(tet, X, 1.0);
  EXPECT_TRUE(RelNear(mirrored.volume, a * b * c / 6));
  EXPECT_TRUE(VecNear(mirrored.center_of_mass, M * original.center_of_mass, 1.0));
  EXPECT_TRUE(MatNear(mirrored.inertia, M * original.inertia * M));
  EXPECT_LT(mirrored.inertia(0, 1) * original.inertia(0, 1), 0);  // The product did flip.
}

// Regular n-gon prism, circumradius r, height h, axis z.
//
// Area: n isosceles triangles of legs r and apex angle th = 2 pi / n, so
//   A = (n / 2) r^2 sin(th),   V = A h.
// Centroid: the polygon's centre (it is invariant under the rotation by th), at mid-height.
// Polar second moment of the polygon about its centre: for a triangle (0, p, q) of area At,
//   integral of x x^T dA = At / 12 (p p^T + q q^T + (p + q)(p + q)^T),
// whose trace is At / 12 (r^2 + r^2 + |p + q|^2) = At / 12 (2 r^2 + 2 r^2 (1 + cos th))
//                                                 = At r^2 (2 + cos th) / 6.
// Summing the n triangles: J = integral of (x^2 + y^2) dA = A r^2 (2 + cos th) / 6, hence
//   Izz = rho h J = m r^2 (2 + cos th) / 6          (n -> infinity: m r^2 / 2, the cylinder).
// In-plane isotropy: the 2x2 second moment S of the polygon is invariant under the rotation Q by
// th (S = Q S Q^T); for n >= 3, Q is not +-1, and a symmetric 2x2 matrix commuting with such a
// rotation is a multiple of the identity. So integral of x^2 dA = integral of y^2 dA = J / 2 and
// integral of x y dA = 0, whatever the phase of the first vertex. With the z extent h:
//   Ixx = Iyy = rho (h J / 2 + A h^3 / 12) = m r^2 (2 + cos th) / 12 + m h^2 / 12,
// and every product of inertia is zero.
TEST(MassProperties, RegularPrism) {
  const double r = 0.75, h = 1.25, density = 1200;
  const Vector3d base(1.5, -0.5, 2.0);
  for (int n : {3, 6, 17}) {
    SCOPED_TRACE(::testing::Message() << "n = " << n);
    const auto mp = solid(make_prism(n, r, h, 0.3, base), Affine3d::Identity(), density);
    const double th = 2 * kPi / n;
    const double area = 0.5 * n * r * r * std::sin(th);
    const double volume = area * h;
    const double m = density * volume;
    const double izz = m * r * r * (2 + std::cos(th)) / 6;
    const double ixx = m * r * r * (2 + std::cos(th)) / 12 + m * h * h / 12;
    EXPECT_TRUE(RelNear(mp.volume, volume));
    EXPECT_TRUE(RelNear(mp.mass, m));
    EXPECT_TRUE(VecNear(mp.center_of_mass, base + Vector3d(0, 0, h / 2), r));
    EXPECT_TRUE(MatNear(mp.inertia, Vector3d(ixx, ixx, izz).asDiagonal().toDenseMatrix()));
  }
}

// Tetrahedron O, a e_x, b e_y, c e_z. With x = a u, y = b v, z = c w it is the image of the
// canonical simplex u, v, w >= 0, u + v + w <= 1 (volume 1/6) with Jacobian abc, and over the
// canonical simplex the Dirichlet integrals are
//   integral of u^2 = 2! / 5! = 1/60,   integral of u v = 1! 1! / 5! = 1/120,
//   integral of u = 1/24.
// So V = abc/6, centroid (a, b, c)/4, integral of x^2 = abc a^2 / 60, of x y = abc a b / 120.
// About the centroid (C = integral - V c c^T):
//   Cxx = abc a^2 (1/60 - 1/96) = abc a^2 / 160,
//   Cxy = abc a b (1/120 - 1/96) = -abc a b / 480.
// With m = rho abc / 6, I = rho (tr(C) 1 - C):
//   Ixx = 3 m (b^2 + c^2) / 80 (and cyclic),  Ixy = -rho Cxy = m a b / 80 (and cyclic).
TEST(MassProperties, Tetrahedron) {
  const double a = 0.5, b = 1.25, c = 2.0, density = 800;
  const Vector3d offset(-4, 2, 1);
  const TriangleMesh tet = make_tetrahedron(a, b, c);
  const double m = density * a * b * c / 6;
  Matrix3d expected;
  expected << 3 * m * (b * b + c * c) / 80, m * a * b / 80, m * a * c / 80,  //
      m * a * b / 80, 3 * m * (a * a + c * c) / 80, m * b * c / 80,         //
      m * a * c / 80, m * b * c / 80, 3 * m * (a * a + b * b) / 80;
  const Vector3d centroid = Vector3d(a, b, c) / 4;
  const std::vector<std::pair<MassProperties, Vector3d>> cases{
      {solid(tet, Affine3d::Identity(), density), Vector3d::Zero()},
      {solid(translated(tet, offset), Affine3d::Identity(), density), offset},
      {solid(tet, translation(offset), density), offset}};
  for (const auto& [mp, moved_by] : cases) {
    SCOPED_TRACE(::testing::Message() << "moved by " << moved_by.transpose());
    EXPECT_TRUE(RelNear(mp.volume, a * b * c / 6));
    EXPECT_TRUE(RelNear(mp.mass, m));
    EXPECT_TRUE(VecNear(mp.center_of_mass, moved_by + centroid, c));
    EXPECT_TRUE(MatNear(mp.inertia, expected));
  }
  // The raw integrals as well: the covariance C stated above.
  const auto vi = integrals(tet);
  const double abc = a * b * c;
  Matrix3d C;
  C << abc * a * a / 160, -abc * a * b / 480, -abc * a * c / 480,  //
      -abc * a * b / 480, abc * b * b / 160, -abc * b * c / 480,   //
      -abc * a * c / 480, -abc * b * c / 480, abc * c * c / 160;
  EXPECT_TRUE(MatNear(vi.second_central, C));
  EXPECT_TRUE(MatNear(inertia_from_second_moment(C, density), expected));
}

// Under x -> A x + t the second moment about the centroid transforms as |det A| A C A^T, the
// volume as |det A| V and the centroid as A c + t.
TEST(MassProperties, ShearedBox) {
  const double a = 1.0, b = 2.0, c = 0.5, k = 0.75;
  const Vector3d p0(0.25, 0.5, -1.0);
  const TriangleMesh box = make_box(p0 - Vector3d(a, b, c) / 2, p0 + Vector3d(a, b, c) / 2);
  Affine3d X = Affine3d::Identity();
  X.linear() << 1, k, 0, 0, 1, 0, 0, 0, 1;
  X.translation() = Vector3d(2, 3, -1);
  const double V0 = a * b * c;
  const Matrix3d C0 = Vector3d(V0 * a * a / 12, V0 * b * b / 12, V0 * c * c / 12).asDiagonal();
  const Matrix3d A = X.linear();
  const auto vi = integrals(box, X);
  EXPECT_TRUE(RelNear(vi.volume, V0));
  EXPECT_TRUE(VecNear(vi.centroid, X * p0, b));
  EXPECT_TRUE(MatNear(vi.second_central, A * C0 * A.transpose()));
  const double density = 3;
  const auto mp = solid(box, X, density);
  EXPECT_TRUE(MatNear(mp.inertia, inertia_from_second_moment(A * C0 * A.transpose(), density)));
  // Written out: C = [[Cxx + k^2 Cyy, k Cyy, 0], [k Cyy, Cyy, 0], [0, 0, Czz]].
  const double cxx = V0 * a * a / 12, cyy = V0 * b * b / 12, czz = V0 * c * c / 12;
  Matrix3d C;
  C << cxx + k * k * cyy, k * cyy, 0, k * cyy, cyy, 0, 0, 0, czz;
  EXPECT_TRUE(MatNear(vi.second_central, C));
}

// A general affine map with det != 1, mirroring or not.
TEST(MassProperties, GeneralAffineBox) {
  const double a = 1.0, b = 2.0, c = 0.5;
  const Vector3d p0(0.25, 0.5, -1.0);
  const TriangleMesh box = make_box(p0 - Vector3d(a, b, c) / 2, p0 + Vector3d(a, b, c) / 2);
  const double V0 = a * b * c;
  const Matrix3d C0 = Vector3d(V0 * a * a / 12, V0 * b * b / 12, V0 * c * c / 12).asDiagonal();
  Matrix3d A;
  A << 1.2, 0.3, -0.1, 0.2, 0.9, 0.4, -0.3, 0.1, 1.5;
  for (const Matrix3d& linear : {Matrix3d(A), Matrix3d(-A)}) {
    Affine3d X = Affine3d::Identity();
    X.linear() = linear;
    X.translation() = Vector3d(-1, 0.5, 4);
    const double det = linear.determinant();
    SCOPED_TRACE(::testing::Message() << "det " << det);
    const auto vi = integrals(box, X);
    EXPECT_TRUE(RelNear(vi.volume, std::abs(det) * V0));
    EXPECT_TRUE(VecNear(vi.centroid, X * p0, b));
    EXPECT_TRUE(MatNear(vi.second_central, std::abs(det) * linear * C0 * linear.transpose()));
  }
}

// Far from the origin (in the vertices themselves, or through X's translation) the inertia about
// the COM must be that of the same solid at the origin, to 1e-9 relative.
TEST(MassProperties, FarFromOriginKeepsPrecision) {
  const double a = 0.3, b = 1.1, c = 0.7, density = 1000;
  const TriangleMesh box = make_box(a, b, c);
  const Matrix3d R = test_rotation().toRotationMatrix();
  Affine3d X_rot = Affine3d::Identity();
  X_rot.linear() = R;
  const auto reference = solid(box, X_rot, density);
  const double m = density * a * b * c;
  ASSERT_TRUE(MatNear(reference.inertia, R * box_inertia(m, a, b, c) * R.transpose()));
  for (double distance : {1e4, 1e6}) {
    const Vector3d far = Vector3d(1, -0.6, 0.8) * distance;
    SCOPED_TRACE(::testing::Message() << "distance " << distance);
    // Translated by X (after a rotation, so the mapped vertices are rounded).
    const auto by_transform = solid(box, Eigen::Translation3d(far) * X_rot, density);
    EXPECT_TRUE(RelNear(by_transform.volume, a * b * c));
    EXPECT_TRUE(VecNear(by_transform.center_of_mass, far, b));
    EXPECT_TRUE(MatNear(by_transform.inertia, reference.inertia));
    // Translated in the vertices (rotated first, then moved, then integrated as is).
    TriangleMesh moved = box;
    for (Vector3d& p : moved.positions) p = R * p + far;
    const auto in_vertices = solid(moved, Affine3d::Identity(), density);
    EXPECT_TRUE(RelNear(in_vertices.volume, a * b * c));
    EXPECT_TRUE(VecNear(in_vertices.center_of_mass, far, b));
    EXPECT_TRUE(MatNear(in_vertices.inertia, reference.inertia));
    // A tetrahedron far away: a solid whose centroid is not the centre of its bounding box.
    const TriangleMesh tet = make_tetrahedron(a, b, c);
    const auto tet_near = solid(tet, Affine3d::Identity(), density);
    const auto tet_far = solid(tet, translation(far), density);
    EXPECT_TRUE(VecNear(tet_far.center_of_mass, far + tet_near.center_of_mass, b));
    EXPECT_TRUE(MatNear(tet_far.inertia, tet_near.inertia));
  }
}

// Vertices no triangle uses change nothing: glTF lets meshes share one POSITION accessor (packers
// merge them), so a 2 cm part's accessor can hold another part's vertices metres away. They moved
// the tetrahedra's apex (1e-4 of the part's inertia at 10 m, negative moments at 1e4 m, 1.4e10 kg
// at 1e8 m), and the weld of an open surface closed a 1 mm gap (s100xform D5).
TEST(MassProperties, UnusedVerticesChangeNothing) {
  const TriangleMesh part = make_box(Vector3d(0.1, 0.2, 0.3), Vector3d(0.12, 0.23, 0.31));
  const VolumeIntegrals alone = integrals(part);
  for (double distance : {10.0, 1e4, 1e8}) {
    SCOPED_TRACE(::testing::Message() << "unused vertex at " << distance << " m");
    TriangleMesh shared = part;
    shared.positions.insert(shared.positions.begin(), Vector3d(distance, -distance, distance));
    for (auto& t : shared.triangles) t = {t[0] + 1, t[1] + 1, t[2] + 1};
    const VolumeIntegrals got = integrals(shared);
    EXPECT_EQ(got.volume, alone.volume);
    EXPECT_EQ(got.centroid, alone.centroid);
    EXPECT_EQ(got.second_central, alone.second_central);
    EXPECT_EQ(got.extent, alone.extent);
    // Open: one face of a 1 m cube left out, its edge 1 mm from the next face's; the weld's
    // tolerance follows the surface's own coordinates only.
    TriangleMesh open = make_box(Vector3d(0, 0, 0), Vector3d(1, 1, 1));
    open.positions.push_back(Vector3d(1.001, 0, 0));
    open.triangles[10] = {8, 3, 7};  // +x face: vertex 1 moved 1 mm out, a gap along two edges
    open.positions.push_back(Vector3d(distance, distance, -distance));
    EXPECT_GT(analyze_surface(std::vector<TriangleMesh>{open}).boundary_edges, 0u);
  }
}

// Reversed triangles: the same solid inside out. The volume is negative; the centroid is the same
// (first moment and volume both change sign) and the second moment changes sign with the volume.
TEST(MassProperties, InsideOutMeshHasNegativeVolume) {
  const Vector3d p0(1, 2, 3);
  const TriangleMesh box = make_box(p0 - Vector3d(1, 2, 3) / 2, p0 + Vector3d(1, 2, 3) / 2);
  const auto outward = integrals(box);
  const auto inside_out = integrals(reversed(box));
  EXPECT_TRUE(RelNear(outward.volume, 6.0));
  EXPECT_TRUE(RelNear(inside_out.volume, -6.0));
  EXPECT_TRUE(VecNear(inside_out.centroid, p0, 3.0));
  EXPECT_TRUE(MatNear(inside_out.second_central, -outward.second_central));
  // A mirroring X applied to an inside-out mesh still gives a negative volume.
  Affine3d X = Affine3d::Identity();
  X.linear() = Vector3d(1, -1, 1).asDiagonal();
  EXPECT_TRUE(RelNear(integrals(reversed(box), X).volume, -6.0));
  EXPECT_TRUE(RelNear(integrals(box, X).volume, 6.0));
}

// Several pieces form one surface: a box with a box-shaped cavity (the inner surface wound
// inward) is the outer box minus the inner one. Both are centred on p0, so
//   V = V_out - V_in,  I = I_out - I_in (each about p0) with m = rho V.
TEST(MassProperties, PiecesFormOneSurfaceHollowBox) {
  const Vector3d p0(-1, 0.5, 2);
  const Vector3d outer(2, 3, 4), inner(1, 1.5, 2.5);
  const std::vector<TriangleMesh> pieces{make_box(p0 - outer / 2, p0 + outer / 2),
                                         reversed(make_box(p0 - inner / 2, p0 + inner / 2))};
  const double density = 10;
  const std::vector<MassPiece> parts{{integrate_solid(pieces, Affine3d::Identity()), density}};
  const auto mp = combine(parts);
  const double v_out = outer.prod(), v_in = inner.prod();
  EXPECT_TRUE(RelNear(mp.volume, v_out - v_in));
  EXPECT_TRUE(VecNear(mp.center_of_mass, p0, 4.0));
  const Matrix3d expected = box_inertia(density * v_out, outer.x(), outer.y(), outer.z()) -
                            box_inertia(density * v_in, inner.x(), inner.y(), inner.z());
  EXPECT_TRUE(MatNear(mp.inertia, expected));
  const SurfaceTopology topology = analyze_surface(pieces);
  EXPECT_TRUE(topology.closed());
  EXPECT_TRUE(topology.consistently_oriented());
}

// Two boxes of different densities, by hand:
//   box 1: [0,1]^3, rho 1000 -> m1 = 1000, c1 = (0.5, 0.5, 0.5), own I = diag(500/3, 500/3, 500/3)
//   box 2: [1,3] x [1,2] x [-1,0] (2 x 1 x 1), rho 250 -> m2 = 500, c2 = (2, 1.5, -0.5),
//          own I = 500/12 diag(1+1, 4+1, 4+1) = diag(250/3, 625/3, 625/3)
//   COM = (1000 c1 + 500 c2) / 1500 = (1, 5/6, 1/6)
//   d1 = c1 - COM = (-1/2, -1/3, 1/3), d2 = c2 - COM = (1, 2/3, -2/3)
//   S = m1 d1 d1^T + m2 d2 d2^T = [[750, 500, -500], [500, 1000/3, -1000/3],
//                                 [-500, -1000/3, 1000/3]],  tr S = 4250/3
//   parallel-axis term tr(S) 1 - S = [[2000/3, -500, 500], [-500, 3250/3, 1000/3],
//                                     [500, 1000/3, 3250/3]]
//   I = own1 + own2 + that = [[2750/3, -500, 500], [-500, 4375/3, 1000/3],
//                             [500, 1000/3, 4375/3]].
TEST(MassProperties, CombineTwoBoxesParallelAxis) {
  const std::vector<MassPiece> parts{
      {integrals(make_box(Vector3d(0, 0, 0), Vector3d(1, 1, 1))), 1000},
      {integrals(make_box(Vector3d(1, 1, -1), Vector3d(3, 2, 0))), 250}};
  const auto mp = combine(parts);
  EXPECT_TRUE(RelNear(mp.volume, 3.0));
  EXPECT_TRUE(RelNear(mp.mass, 1500.0));
  EXPECT_TRUE(VecNear(mp.center_of_mass, Vector3d(1, 5.0 / 6, 1.0 / 6), 1.0));
  Matrix3d expected;
  expected << 2750.0 / 3, -500, 500, -500, 4375.0 / 3, 1000.0 / 3, 500, 1000.0 / 3, 4375.0 / 3;
  EXPECT_TRUE(MatNear(mp.inertia, expected));
  EXPECT_EQ(mp.inertia, mp.inertia.transpose());  // Bitwise symmetric.
  // Order of the pieces does not matter.
  const std::vector<MassPiece> swapped{parts[1], parts[0]};
  EXPECT_TRUE(MatNear(combine(swapped).inertia, expected));
}

// Two halves of one box, as two solids of the same density, combine to the whole box.
TEST(MassProperties, CombineHalvesEqualsWhole) {
  const double density = 4;
  const std::vector<MassPiece> halves{
      {integrals(make_box(Vector3d(0, 0, 0), Vector3d(1, 2, 3))), density},
      {integrals(make_box(Vector3d(1, 0, 0), Vector3d(2, 2, 3))), density}};
  const auto mp = combine(halves);
  const double m = density * 12;
  EXPECT_TRUE(RelNear(mp.mass, m));
  EXPECT_TRUE(VecNear(mp.center_of_mass, Vector3d(1, 1, 1.5), 3.0));
  EXPECT_TRUE(MatNear(mp.inertia, box_inertia(m, 2, 2, 3)));
}

TEST(MassProperties, InertiaFromSecondMoment) {
  Matrix3d C;
  C << 2, 0.5, -0.25, 0.5, 3, 0.125, -0.25, 0.125, 5;
  Matrix3d expected;  // rho (tr C 1 - C), tr C = 10.
  expected << 8, -0.5, 0.25, -0.5, 7, -0.125, 0.25, -0.125, 5;
  EXPECT_TRUE(MatNear(inertia_from_second_moment(C, 2.0), 2.0 * expected));
}

TEST(MassProperties, EmptyInputGivesZero) {
  const std::vector<TriangleMesh> none;
  const auto vi = integrate_solid(none, Affine3d::Identity());
  EXPECT_EQ(vi.volume, 0.0);
  const std::vector<MassPiece> no_parts;
  const auto mp = combine(no_parts);
  EXPECT_EQ(mp.mass, 0.0);
  EXPECT_EQ(mp.inertia, Matrix3d::Zero());
}

// ------------------------------------------------------------------------------------------------
// analyze_surface.

SurfaceTopology topology_of(const TriangleMesh& mesh) {
  const std::vector<TriangleMesh> pieces{mesh};
  return analyze_surface(pieces);
}

TEST(SurfaceTopology, ClosedBox) {
  const auto topology = topology_of(make_box(1, 2, 3));
  EXPECT_EQ(topology.triangles, 12u);
  EXPECT_EQ(topology.degenerate_triangles, 0u);
  EXPECT_EQ(topology.boundary_edges, 0u);
  EXPECT_EQ(topology.misoriented_edges, 0u);
  EXPECT_EQ(topology.nonmanifold_edges, 0u);
  EXPECT_TRUE(topology.closed());
  EXPECT_TRUE(topology.consistently_oriented());
}

TEST(SurfaceTopology, ClosedPrismsAndTetrahedron) {
  for (int n : {3, 6, 17}) {
    const auto topology = topology_of(make_prism(n, 1, 1, 0, Vector3d::Zero()));
    EXPECT_EQ(topology.triangles, static_cast<std::size_t>(4 * n - 4));
    EXPECT_TRUE(topology.closed());
    EXPECT_TRUE(topology.consistently_oriented());
  }
  const auto tet = topology_of(make_tetrahedron(1, 1, 1));
  EXPECT_TRUE(tet.closed());
  EXPECT_TRUE(tet.consistently_oriented());
}

// Removing one face (its 2 triangles) leaves the face's 4 sides each used once; its diagonal is
// gone entirely.
TEST(SurfaceTopology, BoxWithOneFaceRemoved) {
  TriangleMesh box = make_box(1, 2, 3);
  box.triangles.erase(box.triangles.begin() + 2, box.triangles.begin() + 4);  // +z
  const auto topology = topology_of(box);
  EXPECT_EQ(topology.triangles, 10u);
  EXPECT_EQ(topology.boundary_edges, 4u);
  EXPECT_EQ(topology.misoriented_edges, 0u);
  EXPECT_EQ(topology.nonmanifold_edges, 0u);
  EXPECT_FALSE(topology.closed());
  EXPECT_TRUE(topology.consistently_oriented());
}

// One triangle flipped: each of its 3 edges is now used twice in the same direction.
TEST(SurfaceTopology, BoxWithOneTriangleFlipped) {
  TriangleMesh box = make_box(1, 2, 3);
  std::swap(box.triangles[5][1], box.triangles[5][2]);
  const auto topology = topology_of(box);
  EXPECT_EQ(topology.boundary_edges, 0u);
  EXPECT_EQ(topology.misoriented_edges, 3u);
  EXPECT_EQ(topology.nonmanifold_edges, 0u);
  EXPECT_TRUE(topology.closed());
  EXPECT_FALSE(topology.consistently_oriented());
}

// Vertices duplicated per face (split normals, UV seams) are welded by position.
TEST(SurfaceTopology, SplitVerticesStillClosed) {
  const TriangleMesh box = make_box_split_faces(Vector3d(0, 0, 0), Vector3d(1, 2, 3));
  ASSERT_EQ(box.positions.size(), 24u);
  const auto topology = topology_of(box);
  EXPECT_EQ(topology.triangles, 12u);
  EXPECT_EQ(topology.boundary_edges, 0u);
  EXPECT_EQ(topology.misoriented_edges, 0u);
  EXPECT_TRUE(topology.closed());
  EXPECT_TRUE(topology.consistently_oriented());
  // And its integrals are those of the shared-vertex box.
  const auto split = integrals(box);
  const auto shared = integrals(make_box(Vector3d(0, 0, 0), Vector3d(1, 2, 3)));
  EXPECT_TRUE(RelNear(split.volume, shared.volume));
  EXPECT_TRUE(MatNear(split.second_central, shared.second_central));
}

// A seam whose split vertices are a rounding apart (three.js writes sin(2 pi) r, 1e-17, where the
// seam's other side has 0) still closes the surface: welded within 2^-30 of the extent when the
// exact weld leaves it open (s90tools D3). A gap a modeller could make (1e-6 of the extent) stays
// open, as does a face taken away.
TEST(SurfaceTopology, SplitVerticesARoundingApartStillClosed) {
  const TriangleMesh box = make_box_split_faces(Vector3d(0, 0, 0), Vector3d(1, 2, 3));
  // Move the zero coordinates of one face's copies of its corners off zero: the other faces keep
  // them exact.
  const auto moved = [&](double by) {
    TriangleMesh mesh = box;
    for (std::size_t k = 0; k < 4; ++k) {
      for (int c = 0; c < 3; ++c) {
        if (mesh.positions[k][c] == 0) mesh.positions[k][c] = by;
      }
    }
    return mesh;
  };
  const TriangleMesh nudged = moved(1e-17);
  ASSERT_NE(nudged.positions, box.positions);
  EXPECT_TRUE(topology_of(nudged).closed());
  EXPECT_EQ(topology_of(nudged).boundary_edges, 0u);
  const TriangleMesh gap = moved(3e-6);
  EXPECT_FALSE(topology_of(gap).closed());
  EXPECT_GT(topology_of(gap).boundary_edges, 0u);
}

// A box given as two pieces (faces split between two meshes, each with its own vertices).
TEST(SurfaceTopology, BoxSplitIntoTwoPieces) {
  const TriangleMesh box = make_box_split_faces(Vector3d(0, 0, 0), Vector3d(1, 2, 3));
  TriangleMesh first, second;
  first.positions = box.positions;
  second.positions = box.positions;
  first.triangles.assign(box.triangles.begin(), box.triangles.begin() + 6);
  second.triangles.assign(box.triangles.begin() + 6, box.triangles.end());
  const std::vector<TriangleMesh> pieces{first, second};
  const auto topology = analyze_surface(pieces);
  EXPECT_EQ(topology.triangles, 12u);
  EXPECT_TRUE(topology.closed());
  EXPECT_TRUE(topology.consistently_oriented());
  EXPECT_TRUE(RelNear(integrate_solid(pieces, Affine3d::Identity()).volume, 6.0));
  // Either piece alone is open.
  EXPECT_FALSE(topology_of(first).closed());
}

// An inside-out surface is consistently (if wrongly) oriented: topology cannot see it, the sign
// of the volume does.
TEST(SurfaceTopology, InsideOutIsConsistent) {
  const auto topology = topology_of(reversed(make_box(1, 2, 3)));
  EXPECT_TRUE(topology.closed());
  EXPECT_TRUE(topology.consistently_oriented());
}

TEST(SurfaceTopology, DegenerateTriangles) {
  TriangleMesh box = make_box_split_faces(Vector3d(0, 0, 0), Vector3d(1, 1, 1));
  box.triangles.push_back({0, 0, 1});  // Repeated index.
  // Distinct indices at one position: vertex 0 of face 0 is also a corner of other faces.
  std::uint32_t twin = 0;
  for (std::uint32_t i = 4; i < box.positions.size(); ++i) {
    if (box.positions[i] == box.positions[0]) twin = i;
  }
  ASSERT_NE(twin, 0u);
  box.triangles.push_back({0, twin, 2});
  const auto topology = topology_of(box);
  EXPECT_EQ(topology.triangles, 14u);
  EXPECT_EQ(topology.degenerate_triangles, 2u);
  EXPECT_TRUE(topology.closed());
  EXPECT_TRUE(topology.consistently_oriented());
}

// Two cubes sharing one edge: that edge has four triangles, two each way. The surface is closed
// (as a chain: every edge cancels), and its volume the two cubes'.
TEST(SurfaceTopology, EdgeSharedByTwoPartsKeepsTheSurfaceClosed) {
  const std::vector<TriangleMesh> pieces{make_box(Vector3d(0, 0, 0), Vector3d(1, 1, 1)),
                                         make_box(Vector3d(1, 1, 0), Vector3d(2, 2, 1))};
  const auto topology = analyze_surface(pieces);
  EXPECT_EQ(topology.shared_edges, 1u);
  EXPECT_EQ(topology.nonmanifold_edges, 0u);
  EXPECT_EQ(topology.boundary_edges, 0u);
  EXPECT_TRUE(topology.closed());
  EXPECT_TRUE(topology.consistently_oriented());
  EXPECT_NEAR(integrate_solid(pieces, Affine3d::Identity()).volume, 2.0, 1e-12);
}

// A fin on a cube: one more triangle on a cube's edge gives it three uses, which no set of solids
// has: non-manifold, and the surface open.
TEST(SurfaceTopology, NonManifoldEdge) {
  TriangleMesh box = make_box(Vector3d(0, 0, 0), Vector3d(1, 1, 1));
  box.positions.emplace_back(2, 0, 0.5);
  box.triangles.push_back({1, 5, static_cast<std::uint32_t>(box.positions.size() - 1)});  // on the edge x = 1, y = 0
  const auto topology = analyze_surface(std::vector<TriangleMesh>{box});
  EXPECT_EQ(topology.nonmanifold_edges, 1u);
  EXPECT_EQ(topology.shared_edges, 0u);
  EXPECT_EQ(topology.boundary_edges, 2u);
  EXPECT_FALSE(topology.closed());
}

}  // namespace
}  // namespace rdtf
