// The physical checks (check_physics, docs/dynamics.md "Physical checks"): each broken variant of a
// good arm fails with its own code, at the glTF node of the link or joint it names, and nothing
// else is blamed. The good arm itself raises no error.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "dynamics/dynamics_models.h"

namespace rdtf {
namespace {

using dynamics_test::arm_builder;
using dynamics_test::box_inertial;
using dynamics_test::expect_one_error;
using dynamics_test::RobotBuilder;
using dynamics_test::with_code;

// Node indices of arm_builder()'s robot.
constexpr int kShoulderNode = 1;
constexpr int kUpperArmNode = 2;
constexpr int kElbowNode = 3;
constexpr int kForearmNode = 4;
constexpr int kUpperArm = 1;  // links
constexpr int kForearm = 2;
constexpr int kShoulder = 0;  // joints
constexpr int kElbow = 1;

Diagnostics checked(const Robot& robot, const PhysicalCheckOptions& options = {},
                    const LinkBounds* bounds = nullptr) {
  Diagnostics diag;
  check_physics(robot, options, bounds, diag);
  return diag;
}

TEST(PhysicsChecks, TheGoodArmHasNoError) {
  const Diagnostics diag = checked(arm_builder().robot());
  EXPECT_FALSE(diag.has_errors()) << dynamics_test::all_text(diag);
  EXPECT_TRUE(diag.all().empty()) << dynamics_test::all_text(diag);
}

TEST(PhysicsChecks, ZeroMassOnAMovingLink) {
  RobotBuilder b = arm_builder();
  b.link(kUpperArm).inertial.mass = 0;
  b.link(kUpperArm).inertial.inertia.setZero();
  const Diagnostics diag = checked(b.robot());
  expect_one_error(diag, "LINK_MASS_ZERO", kUpperArmNode, "upper_arm");
  EXPECT_EQ(diag.error_count(), 1u) << dynamics_test::all_text(diag);
}

TEST(PhysicsChecks, ZeroMassWithInertia) {
  RobotBuilder b = arm_builder();
  b.link(kForearm).inertial.mass = 0;
  expect_one_error(checked(b.robot()), "LINK_MASSLESS_WITH_INERTIA", kForearmNode, "forearm");
}

TEST(PhysicsChecks, NegativeMass) {
  RobotBuilder b = arm_builder();
  b.link(kUpperArm).inertial.mass = -1.0;
  const Diagnostics diag = checked(b.robot());
  expect_one_error(diag, "LINK_MASS_NEGATIVE", kUpperArmNode, "upper_arm");
  EXPECT_EQ(diag.error_count(), 1u) << dynamics_test::all_text(diag);
}

TEST(PhysicsChecks, MassNotFinite) {
  RobotBuilder b = arm_builder();
  b.link(kForearm).inertial.mass = std::numeric_limits<double>::quiet_NaN();
  expect_one_error(checked(b.robot()), "LINK_MASS_NOT_FINITE", kForearmNode, "forearm");
  b.link(kForearm).inertial.mass = std::numeric_limits<double>::infinity();
  expect_one_error(checked(b.robot()), "LINK_MASS_NOT_FINITE", kForearmNode, "forearm");
}

// Positive diagonal, eigenvalues 0.03, 0.01, -0.01: a diagonal-only check would accept it.
TEST(PhysicsChecks, InertiaNotPositiveDefinite) {
  RobotBuilder b = arm_builder();
  Eigen::Matrix3d I;
  I << 0.01, 0.02, 0, 0.02, 0.01, 0, 0, 0, 0.01;
  b.link(kUpperArm).inertial.inertia = I;
  const Diagnostics diag = checked(b.robot());
  expect_one_error(diag, "LINK_INERTIA_NOT_POSITIVE_DEFINITE", kUpperArmNode, "upper_arm");
  EXPECT_EQ(diag.error_count(), 1u) << dynamics_test::all_text(diag);
}

// Tensors singular in decimal, as pybullet's biped2d publishes them (an ideal thin rod each:
// determinant exactly 0 in exact arithmetic). Rounded to doubles, their smallest eigenvalue comes
// out as 2.2e-18, -6.9e-18 and 8.7e-19 (numpy): by chance on either side of 0. Each must be named,
// whichever side its rounding fell on; a thin but real rod (A / C = 1e-10) must not be.
TEST(PhysicsChecks, TensorsSingularWithinRoundingAreNotPositiveDefinite) {
  struct Case {
    const char* what;
    double ixx, ixy, ixz, iyy, iyz, izz;
  };
  for (const Case& c : {Case{"leg", 0.2125, -0.005, 0.0225, 0.205, 0.045, 0.0125},
                        Case{"torso", 0.2404, -0.01, -0.048, 0.2404, -0.048, 0.02},
                        Case{"foot", 0.0416, -0.01, -0.002, 0.0041, -0.008, 0.0425}}) {
    SCOPED_TRACE(c.what);
    RobotBuilder b = arm_builder();
    Eigen::Matrix3d I;
    I << c.ixx, c.ixy, c.ixz, c.ixy, c.iyy, c.iyz, c.ixz, c.iyz, c.izz;
    b.link(kUpperArm).inertial.inertia = I;
    const Diagnostics diag = checked(b.robot());
    expect_one_error(diag, "LINK_INERTIA_NOT_POSITIVE_DEFINITE", kUpperArmNode, "upper_arm");
    EXPECT_EQ(diag.error_count(), 1u) << dynamics_test::all_text(diag);
  }
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  for (const double ratio : {1e-10, 1e-14}) {
    const Eigen::Matrix3d I = R * Eigen::Vector3d(ratio * 0.05, 0.05, 0.05).asDiagonal() * R.transpose();
    RobotBuilder b = arm_builder();
    b.link(kUpperArm).inertial.inertia = 0.5 * (I + I.transpose());
    EXPECT_EQ(checked(b.robot()).contains("LINK_INERTIA_NOT_POSITIVE_DEFINITE"), ratio < 1e-12) << ratio;
  }
}

// Principal moments 0.001, 0.001, 0.01: positive definite, but no body has A + B < C. Rotated so
// that the check has to find the principal moments.
TEST(PhysicsChecks, TriangleInequalityViolatedThoughPositiveDefinite) {
  RobotBuilder b = arm_builder();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Matrix3d I = R * Eigen::Vector3d(0.001, 0.001, 0.01).asDiagonal() * R.transpose();
  ASSERT_EQ(Eigen::LLT<Eigen::Matrix3d>(I).info(), Eigen::Success);  // positive definite
  b.link(kForearm).inertial.inertia = 0.5 * (I + I.transpose());
  const Diagnostics diag = checked(b.robot());
  expect_one_error(diag, "LINK_INERTIA_TRIANGLE_INEQUALITY", kForearmNode, "forearm");
  EXPECT_EQ(diag.error_count(), 1u) << dynamics_test::all_text(diag);
}

// A + B >= C - tol (A + B + C), tol = 1e-6 by default. A thin plate has C = A + B exactly.
TEST(PhysicsChecks, TriangleInequalityToleranceIsRelative) {
  for (const double scale : {1e-6, 1.0, 1e6}) {
    RobotBuilder b = arm_builder();
    const auto with_c = [&](double c) {
      b.link(kForearm).inertial.inertia = scale * Eigen::Vector3d(1.0, 1.0, c).asDiagonal();
      return checked(b.robot()).contains("LINK_INERTIA_TRIANGLE_INEQUALITY");
    };
    EXPECT_FALSE(with_c(2.0)) << scale;           // equality: a plate
    EXPECT_FALSE(with_c(2.0 + 2e-6)) << scale;    // 2e-6 below the bound 4e-6
    EXPECT_TRUE(with_c(2.0 + 8e-6)) << scale;     // beyond it
  }
  // The tolerance is an option.
  RobotBuilder b = arm_builder();
  b.link(kForearm).inertial.inertia = Eigen::Vector3d(1.0, 1.0, 2.1).asDiagonal();
  PhysicalCheckOptions loose;
  loose.triangle_tolerance = 0.1;
  EXPECT_FALSE(checked(b.robot(), loose).contains("LINK_INERTIA_TRIANGLE_INEQUALITY"));
  EXPECT_TRUE(checked(b.robot()).contains("LINK_INERTIA_TRIANGLE_INEQUALITY"));
}

TEST(PhysicsChecks, InertiaNotSymmetric) {
  RobotBuilder b = arm_builder();
  b.link(kUpperArm).inertial.inertia(0, 1) = 1e-3;
  expect_one_error(checked(b.robot()), "LINK_INERTIA_NOT_SYMMETRIC", kUpperArmNode, "upper_arm");
}

TEST(PhysicsChecks, ZeroJointAxis) {
  RobotBuilder b = arm_builder();
  b.joint(kElbow).axis = Eigen::Vector3d::Zero();
  const Diagnostics diag = checked(b.robot());
  expect_one_error(diag, "JOINT_AXIS_ZERO", kElbowNode, "elbow");
  EXPECT_EQ(diag.error_count(), 1u) << dynamics_test::all_text(diag);
}

TEST(PhysicsChecks, InvertedLimits) {
  RobotBuilder b = arm_builder();
  b.joint(kShoulder).limits = JointLimits{1.0, -1.0, 0, 0};
  const Diagnostics diag = checked(b.robot());
  expect_one_error(diag, "JOINT_LIMITS_INVERTED", kShoulderNode, "shoulder");
  EXPECT_EQ(diag.error_count(), 1u) << dynamics_test::all_text(diag);
}

// forearm 1e7 times heavier than upper_arm: the elbow is named; the bound is an option.
TEST(PhysicsChecks, MassRatioAcrossAJoint) {
  RobotBuilder b = arm_builder();
  b.link(kForearm).inertial = box_inertial(0.5e7, {0.04, 0.3, 0.04}, {0, -0.15, 0});
  b.link(kUpperArm).inertial = box_inertial(0.5, {0.05, 0.4, 0.05}, {0, -0.2, 0});
  const Diagnostics diag = checked(b.robot());
  expect_one_error(diag, "JOINT_MASS_RATIO", kElbowNode, "elbow");
  EXPECT_NE(with_code(diag, "JOINT_MASS_RATIO")[0].message.find("mass ratio 1e+07"), std::string::npos);
  EXPECT_EQ(diag.error_count(), 1u) << dynamics_test::all_text(diag);
  PhysicalCheckOptions options;
  options.max_mass_ratio = 1e8;
  EXPECT_FALSE(checked(b.robot(), options).has_errors());
}

// A second root with a child of its own: two roots, and both stray links named as not connected.
TEST(PhysicsChecks, DisconnectedLinksAndTwoRoots) {
  RobotBuilder b = arm_builder();
  const int stray = b.root("stray", box_inertial(1.0, {0.1, 0.1, 0.1}), dynamics_test::translation(1, 0, 0));
  b.child(stray, "stray_joint", JointKind::kFixed, dynamics_test::translation(0, 0.2, 0), Eigen::Vector3d::UnitX(),
          "stray_child", box_inertial(1.0, {0.1, 0.1, 0.1}));
  const Diagnostics diag = checked(b.robot());
  expect_one_error(diag, "ROBOT_MULTIPLE_ROOTS", b.robot().links[stray].node, "stray");
  const auto not_connected = with_code(diag, "LINK_NOT_CONNECTED");
  ASSERT_EQ(not_connected.size(), 2u) << dynamics_test::all_text(diag);
  EXPECT_EQ(not_connected[0].pointer, "/nodes/5");
  EXPECT_NE(not_connected[0].message.find("'stray'"), std::string::npos);
  EXPECT_EQ(not_connected[1].pointer, "/nodes/7");
  EXPECT_NE(not_connected[1].message.find("'stray_child'"), std::string::npos);
  EXPECT_EQ(diag.error_count(), 3u) << dynamics_test::all_text(diag);
}

// The centre of mass against the link's geometry bounds: an error for a computed inertial (the
// mass came from that geometry), a warning for an authored one.
TEST(PhysicsChecks, CentreOfMassOutsideTheGeometry) {
  RobotBuilder b = arm_builder();
  LinkBounds bounds(3);
  bounds[kUpperArm] = Eigen::AlignedBox3d(Eigen::Vector3d(-0.025, -0.4, -0.025), Eigen::Vector3d(0.025, 0, 0.025));
  EXPECT_FALSE(checked(b.robot(), {}, &bounds).contains("LINK_COM_OUTSIDE_GEOMETRY"));
  b.link(kUpperArm).inertial.center_of_mass = Eigen::Vector3d(0, 0.3, 0);
  const auto authored = with_code(checked(b.robot(), {}, &bounds), "LINK_COM_OUTSIDE_GEOMETRY");
  ASSERT_EQ(authored.size(), 1u);
  EXPECT_EQ(authored[0].severity, Severity::kWarning);
  b.link(kUpperArm).inertial_source = InertialSource::kComputed;
  const Diagnostics diag = checked(b.robot(), {}, &bounds);
  expect_one_error(diag, "LINK_COM_OUTSIDE_GEOMETRY", kUpperArmNode, "upper_arm");
  EXPECT_NE(with_code(diag, "LINK_COM_OUTSIDE_GEOMETRY")[0].message.find("0.3 m outside"), std::string::npos);
}

// An authored inertia against the most its mass can have inside the geometry's bounds: about the
// centre of mass, tr(I)/2 <= m R^2, R the farthest corner. The upper arm is a 0.05 x 0.4 x 0.05 m
// box of 1 kg whose bounds are the box itself: a solid box's tr(I)/2 = m (a^2 + b^2 + c^2) / 12 is
// exactly a third of m R^2 = m (a^2 + b^2 + c^2) / 4 (all the mass in the corners), so up to three
// times its inertia is possible and beyond is not. The warning allows a visual smaller than the
// body: it comes beyond inertia_geometry_factor (10) times the bound, 30 times the box's inertia
// (1 to tolerate none). 1e6 times is the kg mm^2 slip. A computed inertial is an integral over that
// geometry.
TEST(PhysicsChecks, AnAuthoredInertiaBeyondWhatItsGeometryAllows) {
  RobotBuilder b = arm_builder();
  LinkBounds bounds(3);
  bounds[kUpperArm] = Eigen::AlignedBox3d(Eigen::Vector3d(-0.025, -0.4, -0.025), Eigen::Vector3d(0.025, 0, 0.025));
  const Eigen::Matrix3d solid = b.link(kUpperArm).inertial.inertia;
  PhysicalCheckOptions options;
  const auto above = [&](double scale) {
    b.link(kUpperArm).inertial.inertia = scale * solid;
    return with_code(checked(b.robot(), options, &bounds), "LINK_INERTIA_ABOVE_GEOMETRY_BOUND");
  };
  EXPECT_TRUE(above(1).empty());
  EXPECT_TRUE(above(30 * (1 - 1e-9)).empty());
  EXPECT_EQ(above(30 * (1 + 1e-9)).size(), 1u);
  options.inertia_geometry_factor = 1;  // the bound itself
  EXPECT_TRUE(above(3 * (1 - 1e-9)).empty());
  EXPECT_EQ(above(3 * (1 + 1e-9)).size(), 1u);
  options.inertia_geometry_factor = 10;
  const auto slip = above(1e6);
  ASSERT_EQ(slip.size(), 1u);
  EXPECT_EQ(slip[0].severity, Severity::kWarning);
  EXPECT_EQ(slip[0].pointer, "/nodes/" + std::to_string(kUpperArmNode));
  for (const char* part : {"link 'upper_arm': polar moment tr(I)/2 = 13750 kg m^2 is 333333 times 0.04125 kg m^2",
                           "R = 0.203101 m", "kg mm^2"}) {
    EXPECT_NE(slip[0].message.find(part), std::string::npos) << part << "\n" << slip[0].message;
  }
  EXPECT_FALSE(checked(b.robot(), {}, nullptr).contains("LINK_INERTIA_ABOVE_GEOMETRY_BOUND"));  // no geometry
  b.link(kUpperArm).inertial_source = InertialSource::kComputed;
  EXPECT_TRUE(above(1e6).empty());
}

// A massless link fixed to a body with mass is part of that body (info), not an error.
TEST(PhysicsChecks, MasslessLinkOnAFixedJointIsCarried) {
  RobotBuilder b = arm_builder();
  b.child(kForearm, "tool_mount", JointKind::kFixed, dynamics_test::translation(0, -0.3, 0), Eigen::Vector3d::UnitX(),
          "tool_frame", MassProperties{});
  const Diagnostics diag = checked(b.robot());
  EXPECT_FALSE(diag.has_errors()) << dynamics_test::all_text(diag);
  const auto carried = with_code(diag, "LINK_MASSLESS");
  ASSERT_EQ(carried.size(), 1u);
  EXPECT_EQ(carried[0].severity, Severity::kInfo);
  EXPECT_NE(carried[0].message.find("welded (fixed joints) into the body of link 'forearm' and the 1 links fixed to it"),
            std::string::npos)
      << carried[0].message;
}

}  // namespace
}  // namespace rdtf
