// KHR_physics_rigid_bodies out and in: the motion written gives back the exact inertia tensor, the
// written files validate, converting them again gives the same robot, an arm authored with KHR
// physics converts to the robot of its extras-authored twin, and bad KHR data is named.
#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Eigenvalues>

#include "rdtf/completion.h"
#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/geometry.h"
#include "rdtf/khr_physics.h"
#include "rdtf/write.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

using nlohmann::json;

double largest(const Eigen::Matrix3d& m) { return m.cwiseAbs().maxCoeff(); }

void expect_principal_rebuilds(const Eigen::Matrix3d& I) {
  const PrincipalInertia p = principal_inertia(I);
  const Eigen::Matrix3d R = p.rotation.toRotationMatrix();
  EXPECT_NEAR(R.determinant(), 1.0, 1e-15);
  EXPECT_NEAR(p.rotation.norm(), 1.0, 1e-15);
  EXPECT_GE(p.rotation.w(), 0.0);
  EXPECT_LE((inertia_from_principal(p.moments, p.rotation) - I).cwiseAbs().maxCoeff(), 1e-12 * largest(I))
      << "I =\n" << I;
}

TEST(KhrPrincipalInertia, RebuildsFullRepeatedAndIsotropicTensors) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) *
                             Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitX())).toRotationMatrix();
  expect_principal_rebuilds(R * Eigen::Vector3d(0.3, 1.7, 2.9).asDiagonal() * R.transpose());  // full tensor
  expect_principal_rebuilds(R * Eigen::Vector3d(2.0, 2.0, 0.5).asDiagonal() * R.transpose());  // cylinder
  expect_principal_rebuilds(R * Eigen::Vector3d(0.5, 2.0, 2.0).asDiagonal() * R.transpose());
  expect_principal_rebuilds(Eigen::Vector3d(4.0, 4.0, 4.0).asDiagonal());                     // sphere
  expect_principal_rebuilds(R * Eigen::Vector3d(1e-6, 1e-6, 1e-6).asDiagonal() * R.transpose());
}

TEST(KhrPrincipalInertia, RepeatedMomentsGiveOneBasis) {
  // The same cylinder tensor through two rotations about its axis: the same written values.
  const Eigen::Matrix3d D = Eigen::Vector3d(2.0, 2.0, 0.5).asDiagonal();
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(0.9, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const PrincipalInertia a = principal_inertia(D);
  const PrincipalInertia b = principal_inertia(Rz * D * Rz.transpose());
  EXPECT_LE((a.moments - b.moments).norm(), 1e-15);
  EXPECT_LE((a.rotation.coeffs() - b.rotation.coeffs()).norm(), 1e-12);
  EXPECT_TRUE(a.rotation.isApprox(Eigen::Quaterniond::Identity(), 0) ||
              (inertia_from_principal(a.moments, a.rotation) - D).norm() <= 1e-15);
}

// A generated arm: links with a full tensor (a box turned inside its link), repeated moments (a
// square bar: two equal moments; a cube: three) and a link node turned and uniformly scaled.
json generated_arm() {
  const std::string box = R"({"primitives":[{"attributes":{"POSITION":0},"indices":1}]})";
  // Unit cube (+-0.5) as 8 float vertices and 36 unsigned short indices, embedded.
  std::string bytes;
  for (int x : {-1, 1})
    for (int y : {-1, 1})
      for (int z : {-1, 1})
        for (float c : {0.5f * x, 0.5f * y, 0.5f * z}) bytes.append(reinterpret_cast<const char*>(&c), 4);
  const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& f : faces) {
    for (int i : {f[0], f[1], f[2], f[0], f[2], f[3]}) {
      const auto s = static_cast<unsigned short>(i);
      bytes.append(reinterpret_cast<const char*>(&s), 2);
    }
  }
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string b64;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 2]);
    b64 += kAlphabet[(v >> 18) & 63];
    b64 += kAlphabet[(v >> 12) & 63];
    b64 += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    b64 += i + 2 < bytes.size() ? kAlphabet[v & 63] : '=';
  }
  json doc = json::parse(R"({
    "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [
      {"name": "base", "children": [1, 2]},
      {"name": "base_box", "mesh": 0, "rotation": [0.2, 0.3, 0.1, 0.9273618495495703], "scale": [0.4, 0.2, 0.1],
       "translation": [0.05, 0.0, 0.02]},
      {"name": "bar", "mesh": 0, "translation": [0.0, 0.3, 0.0], "rotation": [0.0, 0.0, 0.3826834323650898, 0.9238795325112867],
       "scale": [0.1, 0.1, 0.6], "children": [3]},
      {"name": "cube", "mesh": 0, "translation": [0.0, 0.0, 0.5], "rotation": [0.5, 0.5, 0.5, 0.5], "scale": [2.0, 2.0, 2.0],
       "extras": {"rdtf_joint": "revolute", "rdtf_axis": [1, 1, 0], "rdtf_lower": -1.0, "rdtf_upper": 1.0, "rdtf_damping": 0.5}}
    ],
    "meshes": [)" + box + R"(],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]},
      {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96, "target": 34962},
                    {"buffer": 0, "byteOffset": 96, "byteLength": 72, "target": 34963}],
    "buffers": [{"byteLength": 168}]})");
  doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + b64;
  return doc;
}

std::optional<Conversion> convert_json(const testing::TempDir& dir, const std::string& name, const json& doc,
                                       Diagnostics& diag, ConvertOptions options = {}) {
  testing::write_file(dir / name, doc.dump(2));
  return convert_file(dir / name, options, diag);
}

bool has_code(const Diagnostics& diag, const std::string& code) {
  for (const auto& d : diag.all()) {
    if (d.code == code) return true;
  }
  return false;
}

std::string all_text(const Diagnostics& diag) {
  std::string out;
  for (const auto& d : diag.all()) out += format(d) + "\n";
  return out;
}

// The axes of a node with its scale removed, as the draft's node space has them for a tensor: the
// orthogonal factor of the polar decomposition, A (A^T A)^-1/2 (a mirror kept), computed here from
// the symmetric square root rather than the SVD rdtf takes.
Eigen::Matrix3d node_axes(const Eigen::Matrix3d& A) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(A.transpose() * A);
  return A * solver.operatorInverseSqrt();
}

// The tensor each link's written motion gives, back in the link frame, from the file as written.
void expect_motion_is_robot(const json& written, const Robot& robot) {
  const auto world = node_world_transforms(written);
  for (const Link& link : robot.links) {
    SCOPED_TRACE(link.name);
    const json& motion = written["nodes"][static_cast<std::size_t>(link.node)]["extensions"][kKhrPhysics]["motion"];
    ASSERT_TRUE(motion.contains("inertiaDiagonal")) << motion.dump();
    EXPECT_EQ(motion["mass"].get<double>(), link.inertial.mass);
    const auto& q = motion["inertiaOrientation"];
    const Eigen::Quaterniond rotation(q[3].get<double>(), q[0].get<double>(), q[1].get<double>(), q[2].get<double>());
    EXPECT_NEAR(rotation.norm(), 1.0, 1e-15);
    const Eigen::Vector3d moments(motion["inertiaDiagonal"][0].get<double>(), motion["inertiaDiagonal"][1].get<double>(),
                                  motion["inertiaDiagonal"][2].get<double>());
    const Eigen::Affine3d& X_SN = world[static_cast<std::size_t>(link.node)];
    const Eigen::Matrix3d R_NL = node_axes(X_SN.linear()).transpose() * link.X_SL.linear();
    const Eigen::Matrix3d I_L = R_NL.transpose() * inertia_from_principal(moments, rotation) * R_NL;
    EXPECT_LE((I_L - link.inertial.inertia).cwiseAbs().maxCoeff(), 1e-12 * largest(link.inertial.inertia))
        << "written\n" << I_L << "\nrobot\n" << link.inertial.inertia;
    const Eigen::Vector3d p_N(motion["centerOfMass"][0].get<double>(), motion["centerOfMass"][1].get<double>(),
                              motion["centerOfMass"][2].get<double>());
    const Eigen::Vector3d c_L = link.X_SL.inverse() * (X_SN * p_N);
    EXPECT_LE((c_L - link.inertial.center_of_mass).norm(), 1e-12 * std::max(1.0, link.inertial.center_of_mass.norm()));
  }
}

void expect_same_robot(const Robot& a, const Robot& b, double tolerance) {
  ASSERT_EQ(a.links.size(), b.links.size());
  ASSERT_EQ(a.joints.size(), b.joints.size());
  for (std::size_t i = 0; i < a.links.size(); ++i) {
    SCOPED_TRACE(a.links[i].name);
    EXPECT_EQ(a.links[i].name, b.links[i].name);
    const MassProperties& m = a.links[i].inertial;
    const MassProperties& n = b.links[i].inertial;
    EXPECT_LE(std::abs(m.mass - n.mass), tolerance * m.mass);
    EXPECT_LE((m.center_of_mass - n.center_of_mass).norm(), tolerance * std::max(1.0, m.center_of_mass.norm()));
    EXPECT_LE((m.inertia - n.inertia).cwiseAbs().maxCoeff(), tolerance * largest(m.inertia));
    EXPECT_LE((a.links[i].X_SL.matrix() - b.links[i].X_SL.matrix()).cwiseAbs().maxCoeff(), tolerance);
  }
  for (std::size_t j = 0; j < a.joints.size(); ++j) {
    const Joint& x = a.joints[j];
    const Joint& y = b.joints[j];
    SCOPED_TRACE(x.name);
    EXPECT_EQ(a.links[static_cast<std::size_t>(x.parent_link)].name, b.links[static_cast<std::size_t>(y.parent_link)].name);
    EXPECT_EQ(a.links[static_cast<std::size_t>(x.child_link)].name, b.links[static_cast<std::size_t>(y.child_link)].name);
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_LE((x.axis - y.axis).norm(), tolerance);
    EXPECT_LE((x.X_PJ.matrix() - y.X_PJ.matrix()).cwiseAbs().maxCoeff(), tolerance);
    ASSERT_EQ(x.limits.has_value(), y.limits.has_value());
    if (x.limits) {
      EXPECT_EQ(x.limits->position, y.limits->position);
      EXPECT_LE(std::abs(x.limits->lower - y.limits->lower), tolerance);
      EXPECT_LE(std::abs(x.limits->upper - y.limits->upper), tolerance);
      EXPECT_EQ(x.limits->effort, y.limits->effort);
      EXPECT_EQ(x.limits->velocity, y.limits->velocity);
    }
    EXPECT_LE(std::abs(x.damping - y.damping), tolerance * std::max(1.0, x.damping));
    EXPECT_LE(std::abs(x.spring_stiffness - y.spring_stiffness), tolerance * std::max(1.0, x.spring_stiffness));
  }
}

int count(const json& report, const char* what) { return report["issues"][what].get<int>(); }

// `written` passes the Khronos validator and converts again to `robot`, exactly, without a KHR
// disagreement. Returns the validator's report.
json expect_reads_back_as(const Robot& robot, const std::filesystem::path& written) {
  const json report = testing::khronos_report(written);
  EXPECT_EQ(count(report, "numErrors"), 0) << report.dump(1);
  Diagnostics again_diag;
  auto again = convert_file(written, ConvertOptions{}, again_diag);
  EXPECT_TRUE(again) << all_text(again_diag);
  if (!again) return report;
  EXPECT_FALSE(has_code(again_diag, codes::KHR_PHYSICS_IGNORED)) << all_text(again_diag);
  expect_same_robot(robot, again->robot, 0.0);
  return report;
}

TEST(KhrPhysicsWrite, MotionGivesTheExactTensorAndTheFileValidates) {
  testing::TempDir dir;
  Diagnostics diag;
  const json input = generated_arm();
  auto conversion = convert_json(dir, "arm.gltf", input, diag);
  ASSERT_TRUE(conversion) << all_text(diag);
  ASSERT_EQ(conversion->robot.links.size(), 3u);
  // The full tensor really is one: the base's box is turned inside its link.
  const Eigen::Matrix3d& I_base = conversion->robot.links[0].inertial.inertia;
  EXPECT_GT(std::abs(I_base(0, 1)), 1e-3 * largest(I_base));
  ASSERT_TRUE(write_rdtf(conversion->asset, dir / "out.gltf", OutputFormat::kGltf, diag)) << all_text(diag);
  const json written = json::parse(testing::read_file(dir / "out.gltf"));

  expect_motion_is_robot(written, conversion->robot);
  const json& used = written["extensionsUsed"];
  EXPECT_NE(std::find(used.begin(), used.end(), json(kKhrPhysics)), used.end());
  EXPECT_FALSE(written.contains("extensionsRequired"));
  // A physics joint per robot joint: base_bar fixed (all locked), bar_cube revolute; bar_cube's
  // attachment under bar, whose scale is non-uniform, still has the joint frame as its frame with
  // scale removed (checked on re-conversion: frames that disagree are an error).
  ASSERT_EQ(conversion->robot.joints.size(), 2u);
  const json& physics_joints = written["extensions"][kKhrPhysics]["physicsJoints"];
  ASSERT_EQ(physics_joints.size(), 2u);
  EXPECT_EQ(physics_joints[0]["limits"].size(), 2u);
  EXPECT_EQ(physics_joints[1]["limits"].size(), 3u);
  EXPECT_EQ(physics_joints[1]["drives"][0]["damping"].get<double>(), 0.5);

  const auto input_report = testing::khronos_report(dir / "arm.gltf");
  const auto report = testing::khronos_report(dir / "out.gltf");
  EXPECT_EQ(count(report, "numErrors"), 0) << report.dump(1);
  EXPECT_EQ(count(report, "numWarnings"), count(input_report, "numWarnings")) << report.dump(1);

  // Converted again: the same robot, exactly, and no KHR disagreement.
  Diagnostics again_diag;
  auto again = convert_file(dir / "out.gltf", ConvertOptions{}, again_diag);
  ASSERT_TRUE(again) << all_text(again_diag);
  EXPECT_FALSE(has_code(again_diag, codes::KHR_PHYSICS_IGNORED)) << all_text(again_diag);
  expect_same_robot(conversion->robot, again->robot, 0.0);
  EXPECT_EQ(again->asset.document["nodes"].size(), conversion->asset.document["nodes"].size());
}

// Under a mirror no attachment node (translation and rotation) has a proper joint frame: the joint
// of transforms.gltf's mirrored wheel gets no KHR joint, and the conversion says so by name (it was
// left out silently, and a KHR reader saw the wheel as a free body: s101fmt D3). The other joints
// keep theirs.
TEST(KhrPhysicsWrite, AJointUnderAMirrorIsNamedWhenItGetsNoKhrJoint) {
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / "transforms.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion) << all_text(diag);
  std::vector<Diagnostic> missing;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == codes::KHR_JOINT_NOT_WRITTEN) missing.push_back(d);
  }
  ASSERT_EQ(missing.size(), 1u) << all_text(diag);
  EXPECT_EQ(missing[0].severity, Severity::kWarning);
  const Robot& robot = conversion->robot;
  const auto joint = std::find_if(robot.joints.begin(), robot.joints.end(),
                                  [](const Joint& j) { return j.name == "chassis_wheel_r_mirrored_joint"; });
  ASSERT_NE(joint, robot.joints.end());
  EXPECT_EQ(missing[0].pointer, "/nodes/" + std::to_string(joint->node));
  EXPECT_NE(missing[0].message.find("joint 'chassis_wheel_r_mirrored_joint' (fixed): no KHR_physics_rigid_bodies joint"),
            std::string::npos)
      << missing[0].message;
  EXPECT_NE(missing[0].message.find("is mirrored"), std::string::npos) << missing[0].message;
  const json& physics_joints = conversion->asset.document["extensions"][kKhrPhysics]["physicsJoints"];
  EXPECT_EQ(physics_joints.size(), robot.joints.size() - 1);

  // A scale of 0 leaves no frame either, and is named as such, not as a mirror (whose advice,
  // apply the scale, would flatten the part).
  json document = json::parse(testing::read_file(testing::data_dir() / "blender" / "transforms.gltf"));
  const int wheel = conversion->robot.links[static_cast<std::size_t>(joint->child_link)].node;
  ASSERT_LT(static_cast<std::size_t>(wheel), document["nodes"].size());
  document["nodes"][static_cast<std::size_t>(wheel)]["scale"] = {1, 0, 1};
  testing::TempDir dir;
  testing::write_file(dir / "transforms.gltf", document.dump());
  std::filesystem::copy_file(testing::data_dir() / "blender" / "transforms.bin", dir / "transforms.bin");
  Diagnostics flat_diag;
  ASSERT_TRUE(convert_file(dir / "transforms.gltf", ConvertOptions{}, flat_diag)) << all_text(flat_diag);
  bool named = false;
  for (const Diagnostic& d : flat_diag.all()) {
    if (d.code != codes::KHR_JOINT_NOT_WRITTEN || d.pointer != missing[0].pointer) continue;
    named = true;
    EXPECT_NE(d.message.find("is scaled to nothing on an axis (a scale of 0 on its node or above)"), std::string::npos)
        << d.message;
    EXPECT_EQ(d.message.find("is mirrored"), std::string::npos) << d.message;
    EXPECT_NE(d.message.find("Give the node a scale other than 0"), std::string::npos) << d.message;
  }
  EXPECT_TRUE(named) << all_text(flat_diag);
}

// A mirrored link's motion (transforms.gltf's wheel_r_mirrored: scale -2, -3.3, -10 on a turned
// node) is in its node's own axes, the mirror kept, as for every other link: it was in the link
// frame's (the mirror taken out), which put the wheel's spin moment on the wrong axis (s101fmt D2).
TEST(KhrPhysicsWrite, AMirroredLinksMotionIsInItsNodesOwnAxes) {
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / "transforms.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion) << all_text(diag);
  const json& document = conversion->asset.document;
  const auto world = node_world_transforms(document);
  const auto mirrored = std::find_if(conversion->robot.links.begin(), conversion->robot.links.end(), [&](const Link& l) {
    return world[static_cast<std::size_t>(l.node)].linear().determinant() < 0;
  });
  ASSERT_NE(mirrored, conversion->robot.links.end());
  expect_motion_is_robot(document, conversion->robot);
}

// A joint that turns without end - continuous, or revolute with no lower and upper, with or
// without effort and speed limits - is written with its angular axis free, and read back as the
// same joint, without a disagreement (rdtf used to lock a continuous joint that had an effort
// limit, and to warn about its own output for a revolute joint without a range).
TEST(KhrPhysicsWrite, AJointWithoutARangeIsFreeAndReadsBackAsItself) {
  const json variants[] = {
      {{"rdtf_joint", "revolute"}, {"rdtf_axis", {1, 1, 0}}},
      {{"rdtf_joint", "revolute"}, {"rdtf_axis", {1, 1, 0}}, {"rdtf_effort", 12.5}},
      {{"rdtf_joint", "continuous"}, {"rdtf_axis", {1, 1, 0}}, {"rdtf_effort", 12.5}, {"rdtf_velocity", 30.0},
       {"rdtf_damping", 0.5}},
  };
  for (const json& extras : variants) {
    SCOPED_TRACE(extras.dump());
    testing::TempDir dir;
    json input = generated_arm();
    input["nodes"][3]["extras"] = extras;
    Diagnostics diag;
    auto conversion = convert_json(dir, "arm.gltf", input, diag);
    ASSERT_TRUE(conversion) << all_text(diag);
    const Joint& joint = conversion->robot.joints[1];
    EXPECT_FALSE(position_limited(joint));
    ASSERT_TRUE(write_rdtf(conversion->asset, dir / "out.gltf", OutputFormat::kGltf, diag)) << all_text(diag);
    const json written = json::parse(testing::read_file(dir / "out.gltf"));
    const json& limits = written["extensions"][kKhrPhysics]["physicsJoints"][1]["limits"];
    ASSERT_EQ(limits.size(), 2u) << limits.dump();  // linear 0-2 and angular 1-2 locked; angular 0 free
    for (const json& limit : limits) {
      if (limit.contains("angularAxes")) {
        EXPECT_EQ(limit["angularAxes"], json({1, 2}));
      }
    }
    expect_reads_back_as(conversion->robot, dir / "out.gltf");
  }
}

// A revolute joint given the range [0, 0] is written with every axis locked, as a fixed joint is:
// read back, the two are the same joint (rdtf warned "type fixed against revolute" about its own
// output).
TEST(KhrPhysicsWrite, ARangeOfZeroReadsBackWithoutADisagreement) {
  testing::TempDir dir;
  json input = generated_arm();
  input["nodes"][3]["extras"] = {
      {"rdtf_joint", "revolute"}, {"rdtf_axis", {1, 1, 0}}, {"rdtf_lower", 0.0}, {"rdtf_upper", 0.0}};
  Diagnostics diag;
  auto conversion = convert_json(dir, "arm.gltf", input, diag);
  ASSERT_TRUE(conversion) << all_text(diag);
  ASSERT_TRUE(write_rdtf(conversion->asset, dir / "out.gltf", OutputFormat::kGltf, diag)) << all_text(diag);
  expect_reads_back_as(conversion->robot, dir / "out.gltf");
}

TEST(KhrPhysicsWrite, OffLeavesTheExtensionOut) {
  testing::TempDir dir;
  Diagnostics diag;
  ConvertOptions options;
  options.khr_physics = false;
  auto conversion = convert_json(dir, "arm.gltf", generated_arm(), diag, options);
  ASSERT_TRUE(conversion) << all_text(diag);
  EXPECT_EQ(conversion->asset.document.dump().find(kKhrPhysics), std::string::npos);
}

std::optional<Conversion> convert_fixture(const std::string& name, Diagnostics& diag) {
  return convert_file(testing::data_dir() / "khr" / name, ConvertOptions{}, diag);
}

TEST(KhrPhysicsRead, AuthoredArmIsItsExtrasTwin) {
  Diagnostics extras_diag, khr_diag;
  auto extras = convert_fixture("arm_extras.gltf", extras_diag);
  auto khr = convert_fixture("arm_khr.gltf", khr_diag);
  ASSERT_TRUE(extras) << all_text(extras_diag);
  ASSERT_TRUE(khr) << all_text(khr_diag);
  EXPECT_FALSE(has_code(khr_diag, codes::KHR_PHYSICS_IGNORED)) << all_text(khr_diag);
  EXPECT_FALSE(has_code(khr_diag, codes::KHR_PHYSICS_UNSUPPORTED)) << all_text(khr_diag);
  ASSERT_EQ(khr->robot.joints.size(), 2u);
  EXPECT_EQ(khr->robot.joints[0].kind, JointKind::kRevolute);
  EXPECT_EQ(khr->robot.joints[1].kind, JointKind::kPrismatic);
  expect_same_robot(extras->robot, khr->robot, 1e-12);

  // And its output converts to the same robot again, exactly.
  testing::TempDir dir;
  ASSERT_TRUE(write_rdtf(khr->asset, dir / "out.gltf", OutputFormat::kGltf, khr_diag));
  const json report = expect_reads_back_as(khr->robot, dir / "out.gltf");
  EXPECT_EQ(count(report, "numWarnings"), 0) << report.dump(1);
}

json khr_twin() { return json::parse(testing::read_file(testing::data_dir() / "khr" / "arm_khr.gltf")); }

// Converts a broken twin and returns the diagnostic with `code` (fails when there is none).
Diagnostic expect_diagnostic(const json& doc, const std::string& code) {
  testing::TempDir dir;
  Diagnostics diag;
  convert_json(dir, "bad.gltf", doc, diag);
  for (const auto& d : diag.all()) {
    if (d.code == code) return d;
  }
  ADD_FAILURE() << "no " << code << " in\n" << all_text(diag);
  return Diagnostic{};
}

const std::string kMotion = std::string("/extensions/") + kKhrPhysics + "/motion";
const std::string kJoint = std::string("/extensions/") + kKhrPhysics + "/joint";

// A KHR joint whose angular axis is free and whose drive has a maxForce is a continuous joint with
// that effort limit and no range (the effort was read only on a limited axis, and lost).
TEST(KhrPhysicsRead, TheMaxForceOfAFreeAxisIsAnEffortLimitWithoutARange) {
  json doc = khr_twin();
  json& definition = doc["extensions"][kKhrPhysics]["physicsJoints"][0];
  definition["limits"].erase(2);  // angular 0: free
  definition["drives"][0]["maxForce"] = 7.5;
  testing::TempDir dir;
  Diagnostics diag;
  auto conversion = convert_json(dir, "free.gltf", doc, diag);
  ASSERT_TRUE(conversion) << all_text(diag);
  const Joint& joint = conversion->robot.joints[0];
  EXPECT_EQ(joint.kind, JointKind::kContinuous);
  ASSERT_TRUE(joint.limits);
  EXPECT_FALSE(joint.limits->position);
  EXPECT_EQ(joint.limits->effort, 7.5);
  EXPECT_EQ(joint.damping, 0.3);
}

TEST(KhrPhysicsRead, BadValuesAreNamed) {
  {
    json doc = khr_twin();
    doc["nodes"][0]["extensions"][kKhrPhysics]["motion"]["mass"] = -2.5;
    const auto d = expect_diagnostic(doc, codes::KHR_PHYSICS_INVALID);
    EXPECT_EQ(d.pointer, "/nodes/0" + kMotion + "/mass");
    EXPECT_NE(d.message.find("node 0 'base'"), std::string::npos) << d.message;
    EXPECT_NE(d.message.find("-2.5"), std::string::npos) << d.message;
  }
  {
    json doc = khr_twin();
    doc["nodes"][1]["extensions"][kKhrPhysics]["motion"]["inertiaOrientation"] = {0.0, 0.0, 0.5, 0.5};
    const auto d = expect_diagnostic(doc, codes::KHR_PHYSICS_INVALID);
    EXPECT_EQ(d.pointer, "/nodes/1" + kMotion + "/inertiaOrientation");
    EXPECT_NE(d.message.find("'arm'"), std::string::npos) << d.message;
    EXPECT_NE(d.message.find("unit quaternion"), std::string::npos) << d.message;
  }
  {
    json doc = khr_twin();
    doc["nodes"][1]["extensions"][kKhrPhysics]["motion"]["inertiaDiagonal"] = {0.1, "x", 0.2};
    const auto d = expect_diagnostic(doc, codes::KHR_PHYSICS_INVALID);
    EXPECT_EQ(d.pointer, "/nodes/1" + kMotion + "/inertiaDiagonal");
  }
  {
    json doc = khr_twin();
    doc["nodes"][3]["extensions"][kKhrPhysics]["joint"]["connectedNode"] = 99;
    const auto d = expect_diagnostic(doc, codes::KHR_PHYSICS_INVALID);
    EXPECT_EQ(d.pointer, "/nodes/3" + kJoint + "/connectedNode");
    EXPECT_NE(d.message.find("'base_arm_frame'"), std::string::npos) << d.message;
    EXPECT_NE(d.message.find("99"), std::string::npos) << d.message;
  }
  {
    json doc = khr_twin();
    doc["nodes"][3]["extensions"][kKhrPhysics]["joint"]["joint"] = 7;
    const auto d = expect_diagnostic(doc, codes::KHR_PHYSICS_INVALID);
    EXPECT_EQ(d.pointer, "/nodes/3" + kJoint + "/joint");
  }
  {
    json doc = khr_twin();
    doc["extensions"][kKhrPhysics]["physicsJoints"][0]["limits"][2]["min"] = 2.0;  // above max 1.5
    const auto d = expect_diagnostic(doc, codes::KHR_PHYSICS_INVALID);
    EXPECT_EQ(d.pointer, std::string("/extensions/") + kKhrPhysics + "/physicsJoints/0/limits/2");
  }
  {
    json doc = khr_twin();
    doc["nodes"][4]["translation"] = {0.0, 0.01, 0.0};  // the child's attachment moved off the parent's
    const auto d = expect_diagnostic(doc, codes::KHR_JOINT_FRAMES_DISAGREE);
    EXPECT_EQ(d.pointer, "/nodes/3" + kJoint);
    EXPECT_NE(d.message.find("'arm_base_frame'"), std::string::npos) << d.message;
    EXPECT_NE(d.message.find("0.01"), std::string::npos) << d.message;
  }
}

// Two attachment frames composed through different node chains round apart in proportion to
// their distance from the origin: far out they agree relative to it (the fuzzer's model, scaled
// by 5e18, came out 1024 m apart and its own output was refused), and a real offset still shows.
TEST(KhrPhysicsRead, FramesFarFromTheOriginAgreeRelativeToTheirDistance) {
  const auto frames_disagree = [](double x_base, double y_child_attachment) {
    json doc = khr_twin();
    doc["nodes"][0]["translation"] = {x_base, 0.0, 0.0};
    doc["nodes"][4]["translation"] = {0.0, y_child_attachment, 0.0};
    testing::TempDir dir;
    Diagnostics diag;
    convert_json(dir, "far.gltf", doc, diag);
    return diag.contains(codes::KHR_JOINT_FRAMES_DISAGREE);
  };
  EXPECT_FALSE(frames_disagree(1e9, 0.0));
  EXPECT_FALSE(frames_disagree(1e9, 1.0));     // 1e-9 of the distance: within float precision
  EXPECT_TRUE(frames_disagree(1e9, 1e4));      // 1e-5 of it: a real offset
  EXPECT_TRUE(frames_disagree(0.0, 1e-5));     // near the origin the tolerance is 1e-6 m
  EXPECT_FALSE(frames_disagree(0.0, 1e-7));
}

TEST(KhrPhysicsRead, RdtfTakesPrecedenceAndSaysSo) {
  {
    json doc = khr_twin();
    doc["nodes"][0]["extras"] = {{"rdtf_mass", 7.0}};  // node extras against KHR mass 5
    testing::TempDir dir;
    Diagnostics diag;
    auto conversion = convert_json(dir, "m.gltf", doc, diag);
    ASSERT_TRUE(conversion) << all_text(diag);
    EXPECT_DOUBLE_EQ(conversion->robot.links[0].inertial.mass, 7.0);
    const auto d = expect_diagnostic(doc, codes::KHR_PHYSICS_IGNORED);
    EXPECT_EQ(d.pointer, "/nodes/0" + kMotion);
    EXPECT_NE(d.message.find("'base'"), std::string::npos) << d.message;
    EXPECT_NE(d.message.find("mass 5 kg against 7 kg"), std::string::npos) << d.message;
  }
  {
    // Only the tensor differs: the message says the tensor, not two equal masses (s90urdf D10).
    json doc = khr_twin();
    json& motion = doc["nodes"][0]["extensions"][kKhrPhysics]["motion"];
    motion["inertiaDiagonal"] = {1.0, 2.0, 3.0};
    doc["nodes"][0]["extras"] = {{"rdtf_mass", motion["mass"]}};  // The same mass; the computed tensor.
    const auto d = expect_diagnostic(doc, codes::KHR_PHYSICS_IGNORED);
    EXPECT_NE(d.message.find("inertia [ixx, ixy, ixz, iyy, iyz, izz] [1.0,0.0,0.0,2.0,0.0,3.0] against ["),
              std::string::npos)
        << d.message;
    EXPECT_EQ(d.message.find(" kg against "), std::string::npos) << d.message;  // No mass compared.
  }
  {
    json doc = khr_twin();
    doc["nodes"][1]["extras"] = {{"rdtf_joint", "continuous"}, {"rdtf_axis", {0, 0, 1}}};
    const auto d = expect_diagnostic(doc, codes::KHR_PHYSICS_IGNORED);
    EXPECT_EQ(d.pointer, "/nodes/3" + kJoint);
    EXPECT_NE(d.message.find("revolute"), std::string::npos) << d.message;
  }
  {
    // The same kind locked by a [0, 0] range: the limits are named, not "revolute against
    // revolute" (s90urdf D7).
    json doc = khr_twin();
    doc["nodes"][1]["extras"] = {{"rdtf_joint", "revolute"}, {"rdtf_axis", {0, 0, 1}}, {"rdtf_lower", 0.0}, {"rdtf_upper", 0.0}};
    const auto d = expect_diagnostic(doc, codes::KHR_PHYSICS_IGNORED);
    EXPECT_NE(d.message.find("limits "), std::string::npos) << d.message;
    EXPECT_NE(d.message.find(" against [0.0, 0.0]"), std::string::npos) << d.message;
  }
  {
    json doc = khr_twin();
    doc["nodes"][0]["extensions"][kKhrPhysics]["motion"]["mass"] = 0.0;  // infinite in the draft
    expect_diagnostic(doc, codes::KHR_PHYSICS_IGNORED);
  }
}

}  // namespace
}  // namespace rdtf

namespace rdtf {
namespace {

// The command line: written by default, left out with --no-khr-physics, bad KHR data refused.
TEST(KhrPhysicsCli, WrittenByDefaultOffOnRequestBadInputRefused) {
  testing::TempDir dir;
  const std::string input = (testing::data_dir() / "blender" / "arm3.gltf").string();
  const auto on = testing::run_command(testing::cli_path() + " convert '" + input + "' -o '" + (dir / "on.gltf").string() + "'");
  ASSERT_EQ(on.exit_code, 0) << on.err;
  EXPECT_NE(testing::read_file(dir / "on.gltf").find(kKhrPhysics), std::string::npos);
  const auto off = testing::run_command(testing::cli_path() + " convert '" + input + "' --no-khr-physics -o '" +
                                        (dir / "off.gltf").string() + "'");
  ASSERT_EQ(off.exit_code, 0) << off.err;
  EXPECT_EQ(testing::read_file(dir / "off.gltf").find(kKhrPhysics), std::string::npos);

  json doc = khr_twin();
  doc["nodes"][1]["extensions"][kKhrPhysics]["motion"]["mass"] = -3;
  testing::write_file(dir / "bad.gltf", doc.dump());
  const auto bad = testing::run_command(testing::cli_path() + " convert '" + (dir / "bad.gltf").string() + "' -o '" +
                                        (dir / "bad_out.gltf").string() + "'");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("/nodes/1/extensions/KHR_physics_rigid_bodies/motion/mass: error KHR_PHYSICS_INVALID: node 1 'arm': mass -3"),
            std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad_out.gltf"));
}

}  // namespace
}  // namespace rdtf
