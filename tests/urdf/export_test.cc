// URDF export against closed forms: a box's inertia permuted to Z up, an authored full tensor
// written digit for digit, a thin plate whose A + B >= C survives only at full precision, joints
// with every URDF field, names, meshes in the link frame, and what URDF cannot say.
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <set>

#include "conversion.h"  // rdtfd's output_digest: the SHA-256 the daemon names its files with.
#include "rdtf/mass_properties.h"
#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using namespace urdf_test;

// float32 corner coordinates that are exact, so the closed form is exact too.
constexpr double kA = 0.5, kB = 0.25, kC = 2.0;  // Box edges along glTF x, y, z (m).
constexpr double kDensity = 1000.0;              // The default density (kg/m^3).
// Double maths on exact inputs (the project's standard).
constexpr double kRelative = 1e-9;

// One box link, centred at `center` in a root link node translated to (1, 2, 3).
Conversion box_model(const Eigen::Vector3f& center, Diagnostics& diag) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(kA, kB, kC), center);
  b.node("box", -1, Json{{"mesh", mesh}, {"translation", {1.0, 2.0, 3.0}}});
  return b.convert(diag);
}

const urdf::Inertial& inertial_of(const urdf::ModelInterface& model, const std::string& link) {
  const auto found = model.getLink(link);
  if (!found || !found->inertial) throw std::runtime_error("no inertial on link " + link);
  return *found->inertial;
}

TEST(UrdfExport, BoxInertiaIsTheClosedFormPermutedToZUp) {
  Diagnostics diag;
  const Conversion conversion = box_model(Eigen::Vector3f(0.125f, 0.25f, -0.5f), diag);
  const MassProperties& ours = conversion.robot.links.at(0).inertial;
  const double m = kDensity * kA * kB * kC;
  // Closed form in glTF axes, then in URDF axes: (x, y, z) -> (x, -z, y) swaps the y and z
  // extents, so the URDF's iyy is the glTF izz and the other way round.
  const Eigen::Vector3d I_gltf = m / 12 * Eigen::Vector3d(kB * kB + kC * kC, kA * kA + kC * kC, kA * kA + kB * kB);
  ASSERT_NEAR(ours.mass, m, kRelative * m);
  EXPECT_LE(relative_error(ours.inertia, Eigen::Matrix3d(I_gltf.asDiagonal())), kRelative);

  TempDir dir;
  const auto model = parse_with_urdfdom(export_to(conversion, dir.path()));
  expect_check_urdf_passes(dir / "robot.urdf");
  const urdf::Inertial& in = inertial_of(*model, "box");
  // Every number is ours, permuted and negated exactly (a change of axes by 0 and +-1).
  EXPECT_EQ(in.mass, ours.mass);
  EXPECT_EQ(in.origin.position.x, ours.center_of_mass.x());
  EXPECT_EQ(in.origin.position.y, -ours.center_of_mass.z());
  EXPECT_EQ(in.origin.position.z, ours.center_of_mass.y());
  EXPECT_EQ(in.ixx, ours.inertia(0, 0));
  EXPECT_EQ(in.iyy, ours.inertia(2, 2));
  EXPECT_EQ(in.izz, ours.inertia(1, 1));
  EXPECT_EQ(in.ixy, -ours.inertia(0, 2));
  EXPECT_EQ(in.ixz, ours.inertia(0, 1));
  EXPECT_EQ(in.iyz, -ours.inertia(1, 2));
  EXPECT_EQ(rotation_of(in.origin.rotation), Eigen::Matrix3d::Identity());
  // And against the closed form in URDF axes: the centroid (0.125, 0.25, -0.5) is (0.125, 0.5, 0.25).
  EXPECT_NEAR(in.ixx, I_gltf.x(), kRelative * I_gltf.x());
  EXPECT_NEAR(in.iyy, I_gltf.z(), kRelative * I_gltf.z());
  EXPECT_NEAR(in.izz, I_gltf.y(), kRelative * I_gltf.y());
  EXPECT_LE(relative_error(vector_of(in.origin.position), Eigen::Vector3d(0.125, 0.5, 0.25)), kRelative);
}

TEST(UrdfExport, AuthoredFullTensorIsWrittenDigitForDigit) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(0.5f, 0.5f, 0.5f));
  const int link = b.node("body", -1, Json{{"mesh", mesh}});
  const int inertial = b.node("body_inertial", link);
  b.rdtf_entry(Json{{"node", link}, {"type", "link"}});
  b.rdtf_entry(Json{{"node", inertial},
                    {"type", "inertial"},
                    {"inertial",
                     {{"mass", 1.2345678901234567},
                      {"gravityCenter", {0.1, 0.2, 0.3}},
                      {"inertia", {0.5, 0.01, 0.02, 0.4, 0.03, 0.3}},
                      {"frame", "link"}}}});
  Diagnostics diag;
  const Conversion conversion = b.convert(diag);
  ASSERT_EQ(conversion.robot.links.at(0).inertial_source, InertialSource::kAuthored);
  TempDir dir;
  const std::string text = export_to(conversion, dir.path());
  // urdfdom alone would print mass 1.23457. Z up: ixy' = -ixz, ixz' = ixy, iyz' = -iyz, and
  // iyy and izz swap.
  EXPECT_NE(text.find(R"(<mass value="1.2345678901234567")"), std::string::npos) << text;
  EXPECT_NE(text.find(R"(<origin xyz="0.1 -0.3 0.2" rpy="0 0 0")"), std::string::npos) << text;
  EXPECT_NE(text.find(R"(<inertia ixx="0.5" ixy="-0.02" ixz="0.01" iyy="0.3" iyz="-0.03" izz="0.4")"),
            std::string::npos)
      << text;
  expect_check_urdf_passes(dir / "robot.urdf");

  // With Y kept up, the authored numbers come out as given.
  TempDir y_up;
  UrdfOptions options;
  options.y_up = true;
  const std::string kept = export_to(conversion, y_up.path(), options);
  EXPECT_NE(kept.find(R"(<origin xyz="0.1 0.2 0.3" rpy="0 0 0")"), std::string::npos) << kept;
  EXPECT_NE(kept.find(R"(<inertia ixx="0.5" ixy="0.01" ixz="0.02" iyy="0.4" iyz="0.03" izz="0.3")"),
            std::string::npos)
      << kept;
}

// A plate 1 m x 1 m, 0.1 mm thick: principal moments A = B = m/12 (1 + t^2), C = m/12 * 2, so
// A + B - C = m t^2 / 6, 1e-8 of C: six significant digits (urdfdom's own printing) lose it.
TEST(UrdfExport, ThinPlateKeepsTriangleInequalityOnlyAtFullPrecision) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(1.0f, 1e-4f, 1.0f));
  b.node("plate", -1, Json{{"mesh", mesh}});
  Diagnostics diag;
  const Conversion conversion = b.convert(diag);
  TempDir dir;
  const auto model = parse_with_urdfdom(export_to(conversion, dir.path()));
  expect_check_urdf_passes(dir / "robot.urdf");
  const urdf::Inertial& in = inertial_of(*model, "plate");
  // Thin along glTF y, so along URDF z.
  EXPECT_GE(in.ixx + in.iyy, in.izz);
  const double t = static_cast<double>(1e-4f);
  EXPECT_NEAR(in.ixx + in.iyy - in.izz, in.mass * t * t / 6, 1e-6 * in.mass * t * t / 6);
  auto six_digits = [](double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", value);
    return std::strtod(text, nullptr);
  };
  EXPECT_LT(six_digits(in.ixx) + six_digits(in.iyy), six_digits(in.izz))
      << "six digits would have broken A + B >= C";
}

// base -> (joint node "slider", turned 90 degrees about glTF y) -> arm, every joint key set.
Conversion slider_model(Diagnostics& diag) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.2f));
  const int base = b.node("base", -1, Json{{"mesh", mesh}});
  const double h = std::sqrt(0.5);
  const int slider = b.node("slider", base,
                            Json{{"translation", {0.1, 0.2, 0.3}},
                                 {"rotation", {0.0, h, 0.0, h}},
                                 {"extras",
                                  {{"rdtf_joint", "prismatic"}, {"rdtf_axis", {0, 0, 1}},
                                   {"rdtf_lower", -0.1}, {"rdtf_upper", 0.2}, {"rdtf_effort", 50.0},
                                   {"rdtf_velocity", 1.5}, {"rdtf_damping", 0.7}, {"rdtf_friction", 0.3}}}});
  b.link_with_mesh("arm", slider, mesh);
  return b.convert(diag);
}

TEST(UrdfExport, JointHasOriginAxisLimitsAndDynamicsInZUpAxes) {
  Diagnostics diag;
  const Conversion conversion = slider_model(diag);
  ASSERT_EQ(conversion.robot.joints.size(), 1u);
  const Joint& ours = conversion.robot.joints[0];
  ASSERT_EQ(ours.kind, JointKind::kPrismatic);
  TempDir dir;
  const auto model = parse_with_urdfdom(export_to(conversion, dir.path()));
  expect_check_urdf_passes(dir / "robot.urdf");
  const auto joint = model->getJoint("slider");
  ASSERT_TRUE(joint);
  EXPECT_EQ(joint->type, urdf::Joint::PRISMATIC);
  EXPECT_EQ(joint->parent_link_name, "base");
  EXPECT_EQ(joint->child_link_name, "arm");
  const Eigen::Matrix3d C = gltf_to_urdf_axes();
  // Translation and axis: exact (entries 0 and +-1). glTF (0.1, 0.2, 0.3) is (0.1, -0.3, 0.2).
  EXPECT_EQ(vector_of(joint->parent_to_joint_origin_transform.position), Eigen::Vector3d(0.1, -0.3, 0.2));
  EXPECT_EQ(vector_of(joint->axis), Eigen::Vector3d(C * ours.axis));
  // The axis is the joint node's z, which the 90 degree turn about y made the parent's x; in the
  // child frame (the joint node's frame) it stays z: (0, 0, 1) in glTF, (0, -1, 0) in URDF.
  EXPECT_EQ(vector_of(joint->axis), Eigen::Vector3d(0, -1, 0));
  // Rotation: through roll-pitch-yaw and a quaternion, a few ulps of sin and cos.
  const Eigen::Matrix3d R = rotation_of(joint->parent_to_joint_origin_transform.rotation);
  EXPECT_LE(relative_error(R, Eigen::Matrix3d(C * ours.X_PJ.linear() * C.transpose())), 1e-15);
  ASSERT_TRUE(joint->limits);
  EXPECT_EQ(joint->limits->lower, -0.1);
  EXPECT_EQ(joint->limits->upper, 0.2);
  EXPECT_EQ(joint->limits->effort, 50.0);
  EXPECT_EQ(joint->limits->velocity, 1.5);
  ASSERT_TRUE(joint->dynamics);
  EXPECT_EQ(joint->dynamics->damping, 0.7);
  EXPECT_EQ(joint->dynamics->friction, 0.3);
}

std::vector<Diagnostic> with_code(const Diagnostics& diag, const std::string& code) {
  std::vector<Diagnostic> found;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == code) found.push_back(d);
  }
  return found;
}

TEST(UrdfExport, NamesAreMadeValidAndUniqueAndEveryChangeIsReported) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.2f));
  const int base = b.node("base/link", -1, Json{{"mesh", mesh}});
  b.node("arm link", base, Json{{"mesh", mesh}, {"translation", {0.0, 1.0, 0.0}}});
  b.node("arm_link", base, Json{{"mesh", mesh}, {"translation", {0.0, 2.0, 0.0}}});
  Diagnostics diag;
  const Conversion conversion = b.convert(diag);
  Diagnostics export_diag;
  const auto exported = export_urdf(conversion, UrdfOptions{}, export_diag);
  ASSERT_TRUE(exported);
  EXPECT_EQ(exported->link_names, (std::vector<std::string>{"base_link", "arm_link_2", "arm_link"}));
  EXPECT_EQ(exported->joint_names,
            (std::vector<std::string>{"base_link_arm_link_joint", "base_link_arm_link_joint_2"}));
  const auto changed = with_code(export_diag, "URDF_NAME_CHANGED");
  ASSERT_EQ(changed.size(), 4u);  // Two links ('arm_link' keeps its valid name) and both joints.
  EXPECT_EQ(changed[0].severity, Severity::kWarning);
  EXPECT_EQ(changed[0].pointer, "/nodes/0");
  EXPECT_NE(changed[0].message.find("'base/link' is named 'base_link'"), std::string::npos) << changed[0].message;
  EXPECT_EQ(changed[1].pointer, "/nodes/1");
  EXPECT_NE(changed[1].message.find("'arm link' is named 'arm_link_2'"), std::string::npos) << changed[1].message;
  const auto model = parse_with_urdfdom(exported->text);
  EXPECT_EQ(model->links_.size(), 3u);
  EXPECT_EQ(model->getRoot()->name, "base_link");
  // Each mesh file carries its link's URDF name.
  ASSERT_EQ(exported->meshes.size(), 3u);
  EXPECT_EQ(exported->meshes[1].path, "meshes/arm_link_2.stl");
}

// A robot name with control characters is written without them (XML 1.0 cannot carry them: expat
// and libxml2 refused "arm&#x01;", urdfdom cut a name at a newline), and fixed joints carry no
// <axis> (urdfdom's writer gave each one "0 0 0"): s90urdf D2, D5.
TEST(UrdfExport, TheRobotNameIsXmlAndFixedJointsHaveNoAxis) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.2f));
  const int base = b.node("base", -1, Json{{"mesh", mesh}});
  b.node("arm", base, Json{{"mesh", mesh}, {"translation", {0.0, 1.0, 0.0}}});
  Diagnostics diag;
  Conversion conversion = b.convert(diag);
  conversion.robot.name = std::string("arm\x01 one\ntwo");
  Diagnostics export_diag;
  const auto exported = export_urdf(conversion, UrdfOptions{}, export_diag);
  ASSERT_TRUE(exported);
  EXPECT_NE(exported->text.find("<robot name=\"arm_ one_two\">"), std::string::npos) << exported->text;
  const auto changed = with_code(export_diag, "URDF_NAME_CHANGED");
  ASSERT_EQ(changed.size(), 1u);
  EXPECT_EQ(changed[0].pointer, "/extras/RDTF/name");
  EXPECT_NE(changed[0].message.find("byte 0x01 at position 3"), std::string::npos) << changed[0].message;
  EXPECT_EQ(parse_with_urdfdom(exported->text)->getName(), "arm_ one_two");
  ASSERT_EQ(conversion.robot.joints.size(), 1u);
  ASSERT_EQ(conversion.robot.joints[0].kind, JointKind::kFixed);
  EXPECT_EQ(exported->text.find("<axis"), std::string::npos) << exported->text;
}

// Mesh files are one per link on any file system: links whose names differ only in case get
// distinct files there, and a name starting with '.' no hidden file (s90urdf D13).
TEST(UrdfExport, MeshFilesAreDistinctWithoutRegardToCaseAndNoneIsHidden) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.2f));
  const int base = b.node("arm", -1, Json{{"mesh", mesh}});
  b.node("Arm", base, Json{{"mesh", mesh}, {"translation", {0.0, 1.0, 0.0}}});
  b.node("ARM", base, Json{{"mesh", mesh}, {"translation", {0.0, 2.0, 0.0}}});
  b.node("..", base, Json{{"mesh", mesh}, {"translation", {0.0, 3.0, 0.0}}});
  Diagnostics diag;
  const Conversion conversion = b.convert(diag);
  Diagnostics export_diag;
  const auto exported = export_urdf(conversion, UrdfOptions{}, export_diag);
  ASSERT_TRUE(exported);
  std::set<std::string> folded;
  for (const auto& m : exported->meshes) {
    std::string name = std::filesystem::path(m.path).filename().string();
    EXPECT_NE(name[0], '.') << m.path;
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    EXPECT_TRUE(folded.insert(name).second) << m.path;
  }
  EXPECT_EQ(folded.size(), 4u);
  EXPECT_EQ(exported->meshes[0].path, "meshes/arm.stl");  // The first keeps its name.
}

// Each link's STL holds its solids in the link frame with URDF's axes: their volume is the link's
// and their centroid its centre of mass (uniform density). STL stores float32, so they agree to
// float32 precision (1e-6 relative), not bit for bit.
// In the URDF's (Z-up) link frame: the solid's centroid is the <inertial> origin. arm3's links have
// their centres of mass away from their origins (transforms.gltf's do not), so a mesh written in
// glTF's Y-up frame, 90 degrees off, is caught (review s70rev D2).
TEST(UrdfExport, MeshesAreOutwardStlInTheLinkFrame) {
  for (const char* fixture : {"transforms.gltf", "arm3.gltf"}) {
  SCOPED_TRACE(fixture);
  const Conversion conversion = convert_fixture(fixture);
  TempDir dir;
  const auto model = parse_with_urdfdom(export_to(conversion, dir.path()));
  const Eigen::Matrix3d C = gltf_to_urdf_axes();
  for (const Link& link : conversion.robot.links) {
    SCOPED_TRACE(link.name);
    const auto urdf_link = model->getLink(link.name);
    ASSERT_TRUE(urdf_link && urdf_link->visual && urdf_link->collision);
    const auto& visual = static_cast<const urdf::Mesh&>(*urdf_link->visual->geometry);
    const auto& collision = static_cast<const urdf::Mesh&>(*urdf_link->collision->geometry);
    EXPECT_EQ(visual.filename, "meshes/" + link.name + ".stl");
    EXPECT_EQ(collision.filename, visual.filename);
    const std::string bytes = testing::read_file(dir / visual.filename);
    std::string why;
    const auto mesh = parse_stl(std::vector<std::uint8_t>(bytes.begin(), bytes.end()), why);
    ASSERT_TRUE(mesh) << why;
    const VolumeIntegrals solid = integrate_solid(std::span<const TriangleMesh>(&*mesh, 1), Eigen::Affine3d::Identity());
    EXPECT_NEAR(solid.volume, link.inertial.volume, 1e-6 * link.inertial.volume);
    const Eigen::Vector3d com = C * link.inertial.center_of_mass;
    EXPECT_LE((solid.centroid - com).norm(), 1e-6 * std::cbrt(link.inertial.volume)) << solid.centroid.transpose();
    EXPECT_LE((solid.centroid - vector_of(urdf_link->inertial->origin.position)).norm(),
              1e-6 * std::cbrt(link.inertial.volume));
  }
  }
}

TEST(UrdfExport, MeshPathsAndMujocoElementFollowTheOptions) {
  const Conversion conversion = convert_fixture("two_cylinder.gltf");
  TempDir plain;
  const std::string text = export_to(conversion, plain.path());
  EXPECT_NE(text.find(R"(<compiler meshdir="meshes" fusestatic="false" inertiafromgeom="false")"), std::string::npos) << text;
  EXPECT_NE(text.find(R"(<mesh filename="meshes/base.stl")"), std::string::npos) << text;

  TempDir ros;
  UrdfOptions options;
  options.mesh_uri_prefix = "package://my_robot/urdf/";
  options.mujoco_compiler = false;
  const std::string ros_text = export_to(conversion, ros.path(), options);
  EXPECT_EQ(ros_text.find("<mujoco"), std::string::npos) << ros_text;
  EXPECT_NE(ros_text.find(R"(<mesh filename="package://my_robot/urdf/meshes/base.stl")"), std::string::npos) << ros_text;
  EXPECT_TRUE(std::filesystem::is_regular_file(ros / "meshes/base.stl"));
  EXPECT_TRUE(std::filesystem::is_regular_file(ros / "meshes/arm.stl"));
  expect_check_urdf_passes(ros / "robot.urdf");

  // The prefix is a folder whether or not it ends in '/'.
  TempDir no_slash;
  options.mesh_uri_prefix = "package://my_robot/urdf";
  const std::string no_slash_text = export_to(conversion, no_slash.path(), options);
  EXPECT_NE(no_slash_text.find(R"(<mesh filename="package://my_robot/urdf/meshes/base.stl")"), std::string::npos)
      << no_slash_text;
}

TEST(UrdfExport, BallJointAndPrismaticWithoutLimitsAreRefusedAndNothingIsWritten) {
  for (const char* kind : {"ball", "prismatic"}) {
    SCOPED_TRACE(kind);
    GltfBuilder b;
    const int mesh = b.box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.2f));
    const int base = b.node("base", -1, Json{{"mesh", mesh}});
    const int joint = b.node("hip", base, Json{{"extras", {{"rdtf_joint", kind}}}});
    b.link_with_mesh("leg", joint, mesh);
    Diagnostics diag;
    const Conversion conversion = b.convert(diag);
    TempDir dir;
    Diagnostics export_diag;
    EXPECT_FALSE(write_urdf(conversion, dir / "out", UrdfOptions{}, export_diag));
    const auto errors = with_code(export_diag, std::string(kind) == "ball" ? "URDF_BALL_JOINT" : "URDF_PRISMATIC_WITHOUT_LIMITS");
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_EQ(errors[0].pointer, "/nodes/" + std::to_string(joint));
    EXPECT_NE(errors[0].message.find("'hip'"), std::string::npos) << errors[0].message;
    EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  }
}

// ---- Content-addressed mesh names (the daemon's URDF: docs/urdf.md, "Mesh files in rdtfd") ----

UrdfOptions content_addressed() {
  UrdfOptions options;
  options.mesh_digest = daemon::output_digest;
  return options;
}

// "<link>.<first 16 hex digits of SHA-256(stl)>.stl", computed here from the bytes.
std::string addressed(const std::string& link, const std::vector<std::uint8_t>& stl) {
  return link + "." + daemon::output_digest(stl).substr(0, 16) + ".stl";
}

std::set<std::string> names_in(const std::filesystem::path& folder) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) names.insert(entry.path().filename().string());
  return names;
}

std::set<std::string> file_names(const std::vector<std::string>& paths) {
  std::set<std::string> names;
  for (const auto& path : paths) names.insert(std::filesystem::path(path).filename().string());
  return names;
}

std::set<std::string> mesh_names(const UrdfExport& exported) {
  std::vector<std::string> paths;
  for (const UrdfMeshFile& mesh : exported.meshes) paths.push_back(mesh.path);
  return file_names(paths);
}

// base -> continuous "hinge" -> arm, both boxes of edge `size`.
Conversion two_boxes(float size) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(size, size, size));
  const int base = b.node("base", -1, Json{{"mesh", mesh}});
  const int hinge = b.node("hinge", base, Json{{"translation", {0.0, 1.0, 0.0}},
                                               {"extras", {{"rdtf_joint", "continuous"}, {"rdtf_axis", {1, 0, 0}}}}});
  b.link_with_mesh("arm", hinge, mesh);
  Diagnostics diag;
  return b.convert(diag);
}

TEST(UrdfExport, ContentAddressedMeshesAreNamedAfterLinkAndContentAndTheUrdfRefersToThem) {
  const Conversion conversion = convert_fixture("two_cylinder.gltf");
  Diagnostics diag;
  const auto exported = export_urdf(conversion, content_addressed(), diag);
  ASSERT_TRUE(exported);
  ASSERT_EQ(exported->meshes.size(), conversion.robot.links.size());  // Every link has a mesh.
  std::set<std::string> expected;
  for (std::size_t l = 0; l < exported->meshes.size(); ++l) {
    const UrdfMeshFile& mesh = exported->meshes[l];
    EXPECT_EQ(mesh.path, "meshes/" + addressed(exported->link_names[l], mesh.bytes));
    EXPECT_NE(exported->text.find("<mesh filename=\"" + mesh.path + "\""), std::string::npos) << exported->text;
    expected.insert(addressed(exported->link_names[l], mesh.bytes));
  }
  // <visual> and <collision> of each link name its one file, and nothing else is named.
  EXPECT_EQ(urdf_mesh_filenames(exported->text).size(), 2 * expected.size());
  EXPECT_EQ(file_names(urdf_mesh_filenames(exported->text)), expected);

  TempDir dir;
  EXPECT_EQ(export_to(conversion, dir.path(), content_addressed()), exported->text);
  EXPECT_EQ(testing::read_file(dir / "robot.urdf"), exported->text);
  EXPECT_EQ(names_in(dir / "meshes"), expected);
  for (const UrdfMeshFile& mesh : exported->meshes) {
    const std::string written = testing::read_file(dir / mesh.path);
    EXPECT_EQ(std::vector<std::uint8_t>(written.begin(), written.end()), mesh.bytes) << mesh.path;
  }
  expect_check_urdf_passes(dir / "robot.urdf");
}

// MuJoCo looks a URDF mesh up by its file name in meshdir and names the mesh after the file
// without its last extension: "<link>.<digest>" is a mesh name like any other.
TEST(UrdfExport, MujocoFindsContentAddressedMeshesInItsMeshdir) {
  const Conversion conversion = convert_fixture("arm3.gltf");
  Diagnostics diag;
  const auto exported = export_urdf(conversion, content_addressed(), diag);
  ASSERT_TRUE(exported);
  TempDir dir;
  export_to(conversion, dir.path(), content_addressed());
  char error[1000] = "";
  const std::unique_ptr<mjModel, void (*)(mjModel*)> m(
      mj_loadXML((dir / "robot.urdf").c_str(), nullptr, error, sizeof error), mj_deleteModel);
  ASSERT_TRUE(m) << "MuJoCo refused the export: " << error;
  EXPECT_STREQ(error, "");
  EXPECT_EQ(m->nbody, static_cast<int>(conversion.robot.links.size()) + 1);
  ASSERT_EQ(m->nmesh, static_cast<int>(exported->meshes.size()));
  for (const UrdfMeshFile& mesh : exported->meshes) {
    const std::string name = std::filesystem::path(mesh.path).stem().string();
    const int id = mj_name2id(m.get(), mjOBJ_MESH, name.c_str());
    ASSERT_GE(id, 0) << name;
    std::string why;
    const auto ours = parse_stl(mesh.bytes, why);
    ASSERT_TRUE(ours) << why;
    EXPECT_EQ(m->mesh_facenum[id], static_cast<int>(ours->triangles.size())) << name;
  }
}

TEST(UrdfExport, ContentAddressedWritesKeepThePreviousGenerationOfMeshesAndRemoveOlderOnes) {
  TempDir dir;
  const auto meshes = dir / "meshes";
  std::filesystem::create_directories(meshes);
  // Left by a write that never committed (a killed daemon), and a file that is no one's to remove.
  testing::write_file(meshes / "base.0123456789abcdef.stl", "left by a killed write");
  testing::write_file(meshes / "base.stl", "not content-addressed");
  std::vector<std::set<std::string>> generations;
  for (float size : {0.2f, 0.3f, 0.4f}) {
    SCOPED_TRACE(size);
    const Conversion conversion = two_boxes(size);
    Diagnostics diag;
    const auto exported = export_urdf(conversion, content_addressed(), diag);
    ASSERT_TRUE(exported);
    generations.push_back(mesh_names(*exported));
    ASSERT_EQ(generations.back().size(), 2u);
    export_to(conversion, dir.path(), content_addressed());
    std::set<std::string> expected = generations.back();
    expected.insert("base.stl");
    if (generations.size() > 1) {
      const auto& before = generations[generations.size() - 2];
      expected.insert(before.begin(), before.end());
    }
    EXPECT_EQ(names_in(meshes), expected);
    EXPECT_EQ(file_names(urdf_mesh_filenames(testing::read_file(dir / "robot.urdf"))), generations.back());
  }
}

TEST(UrdfExport, FailedContentAddressedWriteLeavesNoMeshItCreated) {
  TempDir dir;
  export_to(two_boxes(0.2f), dir.path(), content_addressed());
  const auto committed = names_in(dir / "meshes");
  // robot.urdf cannot be replaced (a directory took its place): the new meshes go again.
  std::filesystem::rename(dir / "robot.urdf", dir / "saved.urdf");
  std::filesystem::create_directories(dir / "robot.urdf" / "occupied");
  Diagnostics diag;
  EXPECT_FALSE(write_urdf(two_boxes(0.3f), dir.path(), content_addressed(), diag));
  const auto errors = with_code(diag, "WRITE_FAILED");
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].message.find((dir / "robot.urdf").string()), std::string::npos) << errors[0].message;
  EXPECT_EQ(names_in(dir / "meshes"), committed);
}

TEST(UrdfExport, MeshFilenamesOfAnUrdfText) {
  EXPECT_EQ(urdf_mesh_filenames(R"(<robot name="r"><link name="a"><visual><geometry><mesh filename="meshes/a.stl"/>)"
                                R"(</geometry></visual><collision><geometry>)"
                                R"(<mesh filename="package://p/b.stl" scale="1 1 1"/></geometry></collision></link>)"
                                R"(<link name="c"><visual><geometry><box size="1 1 1"/></geometry></visual></link></robot>)"),
            (std::vector<std::string>{"meshes/a.stl", "package://p/b.stl"}));
  EXPECT_TRUE(urdf_mesh_filenames("not XML <").empty());
}

// A link name longer than a file name may be (valid glTF: 200 accented letters, 400 bytes) names
// its mesh file by its first 120 bytes, cut between characters, and a digest of the whole name;
// two such names that start alike name two files. The URDF is written (it failed: "File name
// too long").
TEST(UrdfExport, LongLinkNamesMakeShortMeshFileNames) {
  std::string accented;
  for (int i = 0; i < 200; ++i) accented += "\xc3\xa9";  // U+00E9
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.2f));
  const int base = b.node(accented + "a", -1, Json{{"mesh", mesh}});
  b.node(accented + "b", base, Json{{"mesh", mesh}, {"translation", {0.0, 1.0, 0.0}}});
  Diagnostics diag;
  const Conversion conversion = b.convert(diag);
  TempDir dir;
  const auto model = parse_with_urdfdom(export_to(conversion, dir.path()));
  std::set<std::string> files = names_in(dir / "meshes");
  ASSERT_EQ(files.size(), 2u);
  for (const std::string& file : files) EXPECT_LE(file.size(), 160u) << file;
  EXPECT_EQ(model->links_.size(), 2u);
}

}  // namespace
}  // namespace rdtf
