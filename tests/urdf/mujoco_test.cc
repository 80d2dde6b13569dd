// Every export compiles in MuJoCo (mj_loadXML reads URDF and checks masses, inertias, A + B >= C
// and meshes), and the masses and inertias MuJoCo reports are ours.
//
// MuJoCo keeps a body's inertia as principal moments (body_inertia) about the centre of mass
// (body_ipos) along axes body_iquat, all in the body frame, which for a URDF is the link frame.
// Masses, centres of mass and body poses are read as doubles from the URDF's text and must equal
// ours to kMujocoRelative = 1e-12 (rounding only; measured: exactly equal).
//
// A full tensor goes through MuJoCo's eigen decomposition (mjuu_eig3, user_util.cc), a Jacobi
// iteration that stops when the next rotation's cosine exceeds 1 - 1e-12 (kEigEPS), i.e. when
// the largest off-diagonal term d of the tensor in its current axes is below
// sqrt(2e-12) |D_cc - D_rr| = 1.41e-6 times the difference of the two moments it couples; the
// remaining off-diagonal terms are dropped. So the tensor rebuilt as R diag(I) R^T differs from
// ours by up to about 1e-7 relative for an oblique tensor (measured: 1.2e-7 on the transforms
// fixture's wheel), which is MuJoCo's own approximation, not a loss in the URDF. The test
// therefore checks exactly what MuJoCo keeps and what it drops: ours expressed in MuJoCo's
// principal axes, D = R^T I R, has MuJoCo's principal moments on its diagonal (to 1e-12), and its
// largest off-diagonal term meets MuJoCo's stopping rule. Axis-aligned tensors need no rotation
// and come back to 1e-12.
#include <mujoco/mujoco.h>

#include <cstdio>
#include <fstream>
#include <memory>

#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using namespace urdf_test;

constexpr double kMujocoRelative = 1e-12;

// Worst relative differences seen over every test of this program, printed at the end of each.
struct Worst {
  double mass = 0, moments = 0, tensor = 0, com = 0, pose = 0;
};
Worst& worst() {
  static Worst w;
  return w;
}

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using MujocoModel = std::unique_ptr<mjModel, ModelDeleter>;

MujocoModel load_in_mujoco(const std::filesystem::path& urdf, std::string& error) {
  char text[1000] = "";
  MujocoModel model(mj_loadXML(urdf.c_str(), nullptr, text, sizeof text));
  error = text;
  return model;
}

Eigen::Matrix3d rotation_of_wxyz(const mjtNum* q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

// MuJoCo's Jacobi stops (mjuu_eig3, kEigEPS = 1e-12) when the largest off-diagonal term d at
// (r, c) is below 1e-12 or when the rotation that would cancel it has a cosine above 1 - 1e-12.
// The same rule on our tensor in MuJoCo's axes: what MuJoCo dropped is what its rule allows.
void expect_mujoco_stopping_rule(const Eigen::Matrix3d& D) {
  constexpr double kEigEps = 1e-12;
  int r = 0, c = 1;
  if (std::abs(D(0, 2)) > std::abs(D(r, c))) r = 0, c = 2;
  if (std::abs(D(1, 2)) > std::abs(D(r, c))) r = 1, c = 2;
  const double d = D(r, c);
  if (std::abs(d) < kEigEps) return;
  const double tau = (D(c, c) - D(r, r)) / (2 * d);
  const double t = (tau >= 0 ? 1.0 : -1.0) / (std::abs(tau) + std::sqrt(1 + tau * tau));
  const double cosine = 1 / std::sqrt(1 + t * t);
  // Our D and MuJoCo's differ by rounding (1e-16 relative), which moves the cosine by ~1e-16.
  EXPECT_GT(cosine, 1 - kEigEps - 1e-15) << "MuJoCo dropped an off-diagonal term its rule keeps:\n" << D;
}

// Compares each link's mass, centre of mass and inertia tensor as MuJoCo has them with ours
// (turned to URDF axes by C), and each joint's pose with the URDF's origin.
void expect_mujoco_agrees(const Conversion& conversion, const UrdfOptions& options = {}) {
  TempDir dir;
  Diagnostics diag;
  const auto exported = export_urdf(conversion, options, diag);
  ASSERT_TRUE(exported);
  ASSERT_TRUE(write_urdf(conversion, dir.path(), options, diag));
  expect_check_urdf_passes(dir / "robot.urdf");
  std::string error;
  const MujocoModel m = load_in_mujoco(dir / "robot.urdf", error);
  ASSERT_TRUE(m) << "MuJoCo refused the export: " << error << "\n" << exported->text;
  EXPECT_EQ(error, "") << "MuJoCo warned";

  // One MuJoCo body per link (fusestatic off), plus the world body.
  EXPECT_EQ(m->nbody, static_cast<int>(conversion.robot.links.size()) + 1);
  const Eigen::Matrix3d C = options.y_up ? Eigen::Matrix3d::Identity() : gltf_to_urdf_axes();
  for (std::size_t l = 0; l < conversion.robot.links.size(); ++l) {
    const Link& link = conversion.robot.links[l];
    const std::string& name = exported->link_names[l];
    SCOPED_TRACE("link " + name);
    const int b = mj_name2id(m.get(), mjOBJ_BODY, name.c_str());
    ASSERT_GE(b, 0);
    const MassProperties& ours = link.inertial;
    EXPECT_NEAR(m->body_mass[b], ours.mass, kMujocoRelative * ours.mass);
    worst().mass = std::max(worst().mass, std::abs(m->body_mass[b] - ours.mass) / ours.mass);

    const Eigen::Matrix3d R = rotation_of_wxyz(m->body_iquat + 4 * b);
    const Eigen::Vector3d principal(m->body_inertia[3 * b], m->body_inertia[3 * b + 1], m->body_inertia[3 * b + 2]);
    const Eigen::Matrix3d I_ours = C * ours.inertia * C.transpose();
    const Eigen::Matrix3d D = R.transpose() * I_ours * R;
    const double scale = std::max(I_ours.cwiseAbs().maxCoeff(), 1e-300);
    const double moment_error = (D.diagonal() - principal).cwiseAbs().maxCoeff() / scale;
    EXPECT_LE(moment_error, kMujocoRelative) << "MuJoCo: " << principal.transpose() << "\nours in its axes:\n" << D;
    expect_mujoco_stopping_rule(D);
    worst().moments = std::max(worst().moments, moment_error);
    const Eigen::Matrix3d I_mujoco = R * principal.asDiagonal() * R.transpose();
    worst().tensor = std::max(worst().tensor, relative_error(I_mujoco, I_ours));

    const Eigen::Vector3d p_mujoco(m->body_ipos[3 * b], m->body_ipos[3 * b + 1], m->body_ipos[3 * b + 2]);
    const Eigen::Vector3d p_ours = C * ours.center_of_mass;
    const double com_error = (p_mujoco - p_ours).norm() / std::max(1.0, p_ours.norm());
    EXPECT_LE(com_error, kMujocoRelative) << p_mujoco.transpose() << " vs " << p_ours.transpose();
    worst().com = std::max(worst().com, com_error);
  }
  // Each child body sits where its joint's origin puts it in the parent's frame.
  for (std::size_t j = 0; j < conversion.robot.joints.size(); ++j) {
    const Joint& joint = conversion.robot.joints[j];
    const int b = mj_name2id(m.get(), mjOBJ_BODY, exported->link_names[joint.child_link].c_str());
    ASSERT_GE(b, 0);
    EXPECT_EQ(m->body_parentid[b], mj_name2id(m.get(), mjOBJ_BODY, exported->link_names[joint.parent_link].c_str()));
    const Eigen::Vector3d p(m->body_pos[3 * b], m->body_pos[3 * b + 1], m->body_pos[3 * b + 2]);
    const double pose_error = std::max((p - C * joint.X_PJ.translation()).norm() / std::max(1.0, p.norm()),
                                       relative_error(rotation_of_wxyz(m->body_quat + 4 * b),
                                                      Eigen::Matrix3d(C * joint.X_PJ.linear() * C.transpose())));
    EXPECT_LE(pose_error, kMujocoRelative) << exported->joint_names[j];
    worst().pose = std::max(worst().pose, pose_error);
  }
  // And it simulates: one forward pass and a few steps without MuJoCo's warnings.
  std::unique_ptr<mjData, DataDeleter> d(mj_makeData(m.get()));
  ASSERT_TRUE(d);
  for (int step = 0; step < 10; ++step) mj_step(m.get(), d.get());
  for (int w = 0; w < mjNWARNING; ++w) EXPECT_EQ(d->warning[w].number, 0) << "MuJoCo warning " << w;
  std::printf("worst relative differences so far (MuJoCo vs ours): mass %.3g, principal moments %.3g, "
              "rebuilt tensor %.3g (MuJoCo's dropped off-diagonal terms), com %.3g, pose %.3g\n",
              worst().mass, worst().moments, worst().tensor, worst().com, worst().pose);
}

TEST(UrdfMujoco, TwoCylinder) { expect_mujoco_agrees(convert_fixture("two_cylinder.gltf")); }
TEST(UrdfMujoco, Arm3) { expect_mujoco_agrees(convert_fixture("arm3.gltf")); }
TEST(UrdfMujoco, Arm3YUp) {
  UrdfOptions options;
  options.y_up = true;
  expect_mujoco_agrees(convert_fixture("arm3.gltf"), options);
}
TEST(UrdfMujoco, Transforms) { expect_mujoco_agrees(convert_fixture("transforms.gltf")); }
TEST(UrdfMujoco, SkinnedArm) { expect_mujoco_agrees(convert_fixture("skinned_arm.gltf")); }

// A box turned about an oblique axis inside its link: a full tensor, which MuJoCo diagonalises.
TEST(UrdfMujoco, RotatedBoxFullTensor) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(0.5f, 0.25f, 2.0f));
  const int base = b.node("base", -1, Json{{"mesh", mesh}});
  const int joint = b.node("hinge", base,
                           Json{{"translation", {0.0, 1.0, 0.0}},
                                {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", {1, 0, 0}},
                                            {"rdtf_lower", -1.0}, {"rdtf_upper", 1.0}}}});
  const int arm = b.node("arm", joint);
  b.node("arm_geometry", arm,
         Json{{"mesh", mesh}, {"rotation", {0.2, 0.3, 0.1, std::sqrt(1 - 0.04 - 0.09 - 0.01)}},
              {"translation", {0.1, 0.2, 0.3}}});
  Diagnostics diag;
  const Conversion conversion = b.convert(diag);
  const Eigen::Matrix3d& I = conversion.robot.links.at(1).inertial.inertia;
  ASSERT_GT(std::abs(I(0, 1)) + std::abs(I(0, 2)) + std::abs(I(1, 2)), 1e-3 * I.trace());
  expect_mujoco_agrees(conversion);
}

// A floating joint 'free' below a root link `root` (a box, or an empty typed link) carrying a box
// 'drone', written as URDF into `dir`: the URDF_FLOATING_JOINT warnings of the export.
std::vector<Diagnostic> floating_joint_below(const std::string& root, bool root_has_mesh, const TempDir& dir,
                                             int* joint_node = nullptr) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.2f));
  const int base = b.node(root, -1, root_has_mesh ? Json{{"mesh", mesh}} : Json{{"extras", {{"rdtf_type", "link"}}}});
  const int joint = b.node("free", base, Json{{"extras", {{"rdtf_joint", "floating"}}}});
  if (joint_node != nullptr) *joint_node = joint;
  b.link_with_mesh("drone", joint, mesh);
  Diagnostics diag;
  const Conversion conversion = b.convert(diag);
  Diagnostics export_diag;
  EXPECT_TRUE(write_urdf(conversion, dir.path(), UrdfOptions{}, export_diag));
  std::vector<Diagnostic> warnings;
  for (const Diagnostic& d : export_diag.all()) {
    if (d.code == "URDF_FLOATING_JOINT") warnings.push_back(d);
  }
  return warnings;
}

// A URDF imported (the ROS tutorial robot: fixed, continuous, prismatic and revolute joints,
// authored inertials) and exported again loads in MuJoCo with its inertials.
// A floating joint is valid URDF (check_urdf passes) that MuJoCo refuses, as the warning says.
TEST(UrdfMujoco, FloatingJointIsWrittenWithAWarningThatMujocoRefusesIt) {
  TempDir dir;
  int joint = -1;
  const auto warnings = floating_joint_below("base", true, dir, &joint);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].severity, Severity::kWarning);
  EXPECT_EQ(warnings[0].pointer, "/nodes/" + std::to_string(joint));
  EXPECT_NE(warnings[0].message.find("floating joint 'free'"), std::string::npos) << warnings[0].message;
  EXPECT_NE(warnings[0].message.find("name the root link 'world'"), std::string::npos) << warnings[0].message;
  expect_check_urdf_passes(dir / "robot.urdf");
  std::string error;
  EXPECT_FALSE(load_in_mujoco(dir / "robot.urdf", error));
  EXPECT_NE(error.find("free joint can only be used on top level"), std::string::npos) << error;
}

// Below a massless root named "world" (URDF's usual world link) MuJoCo takes the floating joint's
// child as a top-level body with a free joint and loads the file: the warning says only what
// robot_state_publisher does.
TEST(UrdfMujoco, FloatingJointBelowARootNamedWorldLoads) {
  TempDir dir;
  const auto warnings = floating_joint_below("world", false, dir);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].message.find("robot_state_publisher ignores it"), std::string::npos) << warnings[0].message;
  EXPECT_EQ(warnings[0].message.find("MuJoCo refuses"), std::string::npos) << warnings[0].message;
  expect_check_urdf_passes(dir / "robot.urdf");
  std::string error;
  EXPECT_TRUE(load_in_mujoco(dir / "robot.urdf", error)) << error;
}

TEST(UrdfMujoco, ImportedTutorialRobot) {
  Diagnostics diag;
  auto conversion = import_urdf(testing::data_dir() / "urdf/urdf_tutorial/07-physics.urdf", UrdfImportOptions{}, diag);
  ASSERT_TRUE(conversion);
  expect_mujoco_agrees(*conversion);
}

// The thin plate loads at full precision, and MuJoCo refuses the same model printed as urdfdom
// prints it (six significant digits): that is why the export prints every digit.
TEST(UrdfMujoco, ThinPlateOnlyAtFullPrecision) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(1.0f, 1e-4f, 1.0f));
  const int base = b.node("base", -1, Json{{"mesh", mesh}});
  const int joint = b.node("hinge", base, Json{{"extras", {{"rdtf_joint", "continuous"}, {"rdtf_axis", {0, 1, 0}}}}});
  b.link_with_mesh("plate", joint, mesh);
  Diagnostics diag;
  const Conversion conversion = b.convert(diag);
  expect_mujoco_agrees(conversion);

  TempDir dir;
  const auto model = parse_with_urdfdom(export_to(conversion, dir.path()));
  std::unique_ptr<TiXmlDocument> six_digits(urdf::exportURDF(*model));
  ASSERT_TRUE(six_digits && six_digits->RootElement());
  // The same <mujoco> element as the export's, so that only the numbers differ.
  TiXmlElement mujoco("mujoco");
  TiXmlElement compiler("compiler");
  compiler.SetAttribute("meshdir", "meshes");
  compiler.SetAttribute("fusestatic", "false");
  compiler.SetAttribute("inertiafromgeom", "false");
  mujoco.InsertEndChild(compiler);
  six_digits->RootElement()->InsertEndChild(mujoco);
  TiXmlPrinter printer;
  six_digits->Accept(&printer);
  testing::write_file(dir / "six_digits.urdf", printer.Str());
  std::string error;
  const MujocoModel refused = load_in_mujoco(dir / "six_digits.urdf", error);
  EXPECT_FALSE(refused);
  EXPECT_NE(error.find("A + B >= C"), std::string::npos) << error;
}

}  // namespace
}  // namespace rdtf
