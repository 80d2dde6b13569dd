// URDF -> RDTF: the ROS tutorial robots, primitives measured against closed forms, STL meshes by
// every path form, glTF that the Khronos validator accepts, and the round trip
// URDF -> RDTF -> URDF keeping tree, kinds, axes, limits, origins and inertials.
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>

#include "rdtf/write.h"
#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using namespace urdf_test;
namespace fs = std::filesystem;

constexpr double kRelative = 1e-9;  // Double maths on exact inputs.

fs::path tutorial(const std::string& name) { return testing::data_dir() / "urdf" / "urdf_tutorial" / name; }

Conversion import_or_fail(const fs::path& urdf, Diagnostics& diag, const UrdfImportOptions& options = {}) {
  auto conversion = import_urdf(urdf, options, diag);
  if (!conversion) {
    std::string all;
    for (const Diagnostic& d : diag.all()) all += format(d) + "\n";
    ADD_FAILURE() << urdf << " not imported:\n" << all;
    throw std::runtime_error("import failed");
  }
  return std::move(*conversion);
}

// Writes the import as .gltf and runs the Khronos validator on it: no errors.
void expect_valid_gltf(const Conversion& conversion, const fs::path& path) {
  Diagnostics diag;
  ASSERT_TRUE(write_rdtf(conversion.asset, path, path.extension() == ".glb" ? OutputFormat::kGlb : OutputFormat::kGltf, diag));
  const auto report = testing::khronos_report(path);
  EXPECT_EQ(report["issues"]["numErrors"].get<int>(), 0) << report["issues"].dump(1);
}

const char* kind_name(int type) {
  switch (type) {
    case urdf::Joint::FIXED: return "fixed";
    case urdf::Joint::REVOLUTE: return "revolute";
    case urdf::Joint::CONTINUOUS: return "continuous";
    case urdf::Joint::PRISMATIC: return "prismatic";
    case urdf::Joint::FLOATING: return "floating";
    case urdf::Joint::PLANAR: return "planar";
    default: return "unknown";
  }
}

TEST(UrdfImport, TutorialRobotsBecomeValidRdtf) {
  for (const char* name : {"01-myfirst.urdf", "02-multipleshapes.urdf", "03-origins.urdf", "04-materials.urdf",
                           "05-visual.urdf", "06-flexible.urdf", "07-physics.urdf"}) {
    SCOPED_TRACE(name);
    Diagnostics diag;
    const Conversion conversion = import_or_fail(tutorial(name), diag);
    const auto original = parse_with_urdfdom(testing::read_file(tutorial(name)));
    // Every link and joint, by name, with its kind, parent and child.
    ASSERT_EQ(conversion.robot.links.size(), original->links_.size());
    for (const Link& link : conversion.robot.links) EXPECT_TRUE(original->getLink(link.name)) << link.name;
    ASSERT_EQ(conversion.robot.joints.size(), original->joints_.size());
    for (const Joint& joint : conversion.robot.joints) {
      const auto theirs = original->getJoint(joint.name);
      ASSERT_TRUE(theirs) << joint.name;
      EXPECT_STREQ(to_string(joint.kind), kind_name(theirs->type)) << joint.name;
      EXPECT_EQ(conversion.robot.links[joint.parent_link].name, theirs->parent_link_name);
      EXPECT_EQ(conversion.robot.links[joint.child_link].name, theirs->child_link_name);
    }
    EXPECT_EQ(conversion.robot.links[conversion.robot.root_links.at(0)].name, original->getRoot()->name);
    TempDir dir;
    expect_valid_gltf(conversion, dir / "robot.gltf");
  }
}

// A numeric character reference is the character itself: "caf&#xE9;" and "caf&#233;" name the
// link and joint "café" (found by fuzzing: urdfdom's TinyXML made one byte of it, and import
// crashed looking up a link by the other reading).
TEST(UrdfImport, CharacterReferencesInNamesAreTheirCharacters) {
  TempDir dir;
  testing::write_file(dir / "robot.urdf",
                      "<robot name=\"r&#x1F916;\">\n<link name=\"caf&#xE9;\"/>\n<link name=\"b\"/>\n"
                      "<joint name=\"caf&#233;_j\" type=\"fixed\"><parent link=\"caf&#xE9;\"/><child link=\"b\"/></joint>\n"
                      "</robot>\n");
  Diagnostics diag;
  const Conversion conversion = import_or_fail(dir / "robot.urdf", diag);
  std::vector<std::string> names;
  for (const auto& node : conversion.asset.document["nodes"]) names.push_back(node.value("name", ""));
  EXPECT_NE(std::find(names.begin(), names.end(), "caf\xC3\xA9"), names.end()) << ::testing::PrintToString(names);
  EXPECT_NE(std::find(names.begin(), names.end(), "caf\xC3\xA9_j"), names.end()) << ::testing::PrintToString(names);
  expect_valid_gltf(conversion, dir / "robot.gltf");
}

TEST(UrdfImport, AuthoredInertialsAreKeptAndTheFingersColladaMeshesRead) {
  Diagnostics diag;
  const Conversion conversion = import_or_fail(tutorial("07-physics.urdf"), diag);
  const auto original = parse_with_urdfdom(testing::read_file(tutorial("07-physics.urdf")));
  const Eigen::Matrix3d C = gltf_to_urdf_axes();
  for (const Link& link : conversion.robot.links) {
    SCOPED_TRACE(link.name);
    const auto& in = *original->getLink(link.name)->inertial;
    EXPECT_EQ(link.inertial_source, InertialSource::kAuthored);
    EXPECT_EQ(link.inertial.mass, in.mass);
    // Diagonal tensors at the link origin: the change of axes permutes them exactly.
    EXPECT_EQ(Eigen::Matrix3d(C * link.inertial.inertia * C.transpose()), tensor_of(in));
    EXPECT_EQ(Eigen::Vector3d(C * link.inertial.center_of_mass), vector_of(in.origin.position));
  }
  // The PR2 finger meshes (COLLADA, tests/data/urdf/urdf_tutorial/meshes) are read: no mesh
  // diagnostic, and each finger and tip shows its file's 2,000 or 1,000 triangles.
  for (const Diagnostic& d : diag.all()) EXPECT_EQ(d.code.rfind("URDF_MESH", 0), std::string::npos) << format(d);
  std::map<std::string, std::size_t> triangles;
  const Json& document = conversion.asset.document;
  for (const Json& mesh : document["meshes"]) {
    std::size_t count = 0;
    for (const Json& primitive : mesh["primitives"]) {
      count += document["accessors"][primitive["indices"].get<std::size_t>()]["count"].get<std::size_t>() / 3;
    }
    triangles[mesh["name"].get<std::string>()] = count;
  }
  EXPECT_EQ(triangles["left_gripper_visual"], 2000u);
  EXPECT_EQ(triangles["right_gripper_visual"], 2000u);
  EXPECT_EQ(triangles["left_tip_visual"], 1000u);
  EXPECT_EQ(triangles["right_tip_visual"], 1000u);
}

// The root and links on moving joints without <inertial> get their mass from the generated
// primitives at the default density: the box exactly, the cylinder's polygon and the sphere's
// polyhedron scaled to the true volume. (A link on a fixed joint is massless: below.)
TEST(UrdfImport, PrimitivesHaveTheClosedFormVolumesAndBoxInertia) {
  TempDir dir;
  testing::write_file(dir / "shapes.urdf", R"(<?xml version="1.0"?>
<robot name="shapes">
  <link name="box"><visual><geometry><box size="0.6 0.1 0.2"/></geometry></visual></link>
  <link name="cylinder"><visual><geometry><cylinder radius="0.2" length="0.6"/></geometry></visual></link>
  <link name="sphere"><visual><geometry><sphere radius="0.3"/></geometry></visual></link>
  <joint name="j1" type="revolute"><parent link="box"/><child link="cylinder"/><origin xyz="1 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><parent link="box"/><child link="sphere"/><origin xyz="0 1 0"/></joint>
</robot>)");
  Diagnostics diag;
  const Conversion conversion = import_or_fail(dir / "shapes.urdf", diag);
  // The moving links' mass is a guess the URDF does not make: a warning each; the root's an info.
  std::map<std::string, Severity> said;
  for (const Diagnostic& d : diag.all()) {
    if (d.code != "URDF_NO_INERTIAL") continue;
    for (const char* name : {"box", "cylinder", "sphere"}) {
      if (d.message.find("link '" + std::string(name) + "'") != std::string::npos) said[name] = d.severity;
    }
  }
  EXPECT_EQ(said, (std::map<std::string, Severity>{
                      {"box", Severity::kInfo}, {"cylinder", Severity::kWarning}, {"sphere", Severity::kWarning}}));
  const double pi = std::numbers::pi;
  const std::map<std::string, double> volumes{
      {"box", 0.6 * 0.1 * 0.2}, {"cylinder", pi * 0.2 * 0.2 * 0.6}, {"sphere", 4.0 / 3.0 * pi * 0.3 * 0.3 * 0.3}};
  for (const Link& link : conversion.robot.links) {
    SCOPED_TRACE(link.name);
    EXPECT_EQ(link.inertial_source, InertialSource::kComputed);
    // Generated vertices are stored as float32 in the glTF: 1e-6 relative.
    EXPECT_NEAR(link.inertial.volume, volumes.at(link.name), 1e-6 * volumes.at(link.name));
    EXPECT_NEAR(link.inertial.mass, 1000 * volumes.at(link.name), 1e-6 * 1000 * volumes.at(link.name));
  }
  // The box in URDF axes: I = m/12 diag(y^2 + z^2, x^2 + z^2, x^2 + y^2).
  const Link& box = conversion.robot.links.at(0);
  ASSERT_EQ(box.name, "box");
  const Eigen::Matrix3d C = gltf_to_urdf_axes();
  const double m = box.inertial.mass;
  const Eigen::Vector3d expected = m / 12 * Eigen::Vector3d(0.01 + 0.04, 0.36 + 0.04, 0.36 + 0.01);
  EXPECT_LE(relative_error(Eigen::Matrix3d(C * box.inertial.inertia * C.transpose()), Eigen::Matrix3d(expected.asDiagonal())),
            1e-6);
  // The sphere's inertia is a ball's, 2/5 m r^2 about every axis, to the 3.2e-6 of its polyhedron
  // (an icosahedron split three times: the UV sphere it replaced was 2.1e-3 off about its poles),
  // and the cylinder's m/12 (3 r^2 + l^2) across and m r^2 / 2 along its axis, to its polygon's
  // 32 sides (9e-6).
  const auto link = [&](const std::string& name) {
    return *std::find_if(conversion.robot.links.begin(), conversion.robot.links.end(),
                         [&](const Link& l) { return l.name == name; });
  };
  const Link sphere = link("sphere");
  const double ball = 0.4 * sphere.inertial.mass * 0.3 * 0.3;
  EXPECT_LE(relative_error(sphere.inertial.inertia, Eigen::Matrix3d(ball * Eigen::Matrix3d::Identity())), 4e-6)
      << sphere.inertial.inertia;
  const Link cylinder = link("cylinder");
  const double mc = cylinder.inertial.mass;
  const Eigen::Vector3d along_z(mc / 12 * (3 * 0.04 + 0.36), mc / 12 * (3 * 0.04 + 0.36), mc * 0.04 / 2);
  EXPECT_LE(relative_error(Eigen::Matrix3d(C * cylinder.inertial.inertia * C.transpose()), Eigen::Matrix3d(along_z.asDiagonal())),
            1e-5);
  expect_valid_gltf(conversion, dir / "shapes.glb");
}


// URDF reads a link without <inertial> as massless; on a fixed joint (a sensor frame, a collision
// helper, as Unitree's *_thigh_shoulder) it stays so, whatever geometry it has, and the export
// writes no <inertial> for it: the round trip adds no mass.
TEST(UrdfImport, ALinkWithoutInertialOnAFixedJointIsMassless) {
  TempDir dir;
  testing::write_file(dir / "frames.urdf", R"(<?xml version="1.0"?>
<robot name="frames">
  <link name="trunk"><inertial><mass value="12"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.25"/></inertial>
    <visual><geometry><box size="0.4 0.2 0.1"/></geometry></visual></link>
  <link name="shoulder_helper"><collision><geometry><cylinder radius="0.05" length="0.03"/></geometry></collision></link>
  <joint name="helper_fixed" type="fixed"><parent link="trunk"/><child link="shoulder_helper"/><origin xyz="0.2 0.1 0"/></joint>
</robot>)");
  Diagnostics diag;
  const Conversion conversion = import_or_fail(dir / "frames.urdf", diag);
  ASSERT_EQ(conversion.robot.links.size(), 2u);
  const Link& helper = conversion.robot.links[1];
  ASSERT_EQ(helper.name, "shoulder_helper");
  EXPECT_EQ(helper.inertial.mass, 0.0);
  EXPECT_TRUE(helper.inertial.inertia.isZero(0));
  EXPECT_EQ(helper.inertial_source, InertialSource::kAuthored);
  bool told = false;
  for (const Diagnostic& d : diag.all()) {
    if (d.code != "URDF_NO_INERTIAL") continue;
    told = true;
    EXPECT_EQ(d.severity, Severity::kInfo);
    EXPECT_NE(d.message.find("fixed to 'trunk' by joint 'helper_fixed': it is massless"), std::string::npos) << d.message;
  }
  EXPECT_TRUE(told);
  // The export: no <inertial> on the helper, so urdfdom reads it massless, as the input.
  Diagnostics export_diag;
  ASSERT_TRUE(write_urdf(conversion, dir / "out", UrdfOptions{}, export_diag)) << export_diag.all().size();
  const auto exported = parse_with_urdfdom(testing::read_file(dir / "out" / "robot.urdf"));
  ASSERT_TRUE(exported);
  EXPECT_FALSE(exported->getLink("shoulder_helper")->inertial);
  EXPECT_DOUBLE_EQ(exported->getLink("trunk")->inertial->mass, 12.0);
}

// Clearpath's Husky keeps its base's mass in an inertial_link fixed to base_link, which has none
// (KDL ignores a root's inertia): the body they make has that mass, so base_link is massless, root
// or not, and its geometry adds nothing (from its boxes at 1000 kg/m^3 it had added 126 kg). A link
// without <inertial> whose body has no mass elsewhere still gets its geometry's.
TEST(UrdfImport, ALinkFixedToOneThatCarriesItsBodysMassIsMassless) {
  TempDir dir;
  testing::write_file(dir / "husky.urdf", R"(<?xml version="1.0"?>
<robot name="husky">
  <link name="base_link"><collision><geometry><box size="0.98 0.57 0.25"/></geometry></collision></link>
  <link name="inertial_link"><inertial><mass value="33.455"/><inertia ixx="0.6" ixy="0" ixz="0" iyy="1.7" iyz="0" izz="2.0"/></inertial></link>
  <joint name="inertial_joint" type="fixed"><parent link="base_link"/><child link="inertial_link"/><origin xyz="-0.08 0 0"/></joint>
  <link name="arm"><collision><geometry><box size="0.1 0.1 0.4"/></geometry></collision></link>
  <joint name="shoulder" type="revolute"><parent link="base_link"/><child link="arm"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <link name="forearm"><collision><geometry><box size="0.1 0.1 0.3"/></geometry></collision></link>
  <joint name="elbow" type="revolute"><parent link="arm"/><child link="forearm"/><origin xyz="0 0 0.4"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <link name="forearm_mass"><inertial><mass value="2"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="forearm_fixed" type="fixed"><parent link="forearm"/><child link="forearm_mass"/></joint>
</robot>)");
  Diagnostics diag;
  const Conversion conversion = import_or_fail(dir / "husky.urdf", diag);
  std::map<std::string, double> mass;
  for (const Link& link : conversion.robot.links) mass[link.name] = link.inertial.mass;
  EXPECT_EQ(mass.at("base_link"), 0.0);
  EXPECT_EQ(mass.at("inertial_link"), 33.455);
  EXPECT_EQ(mass.at("forearm"), 0.0);  // Moves on 'elbow' with forearm_mass, which carries 2 kg.
  EXPECT_EQ(mass.at("forearm_mass"), 2.0);
  // 'arm' moves alone: its box's mass at 1000 kg/m^3, 4 kg, with a warning; its half-edges 0.05
  // and 0.2 are float32 in the buffer, each within 2^-24 relative: the volume within 3 x 2^-24.
  EXPECT_NEAR(mass.at("arm"), 4.0, 4.0 * 3 * std::ldexp(1.0, -24));
  std::map<std::string, std::pair<Severity, std::string>> said;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == "URDF_NO_INERTIAL") said[d.pointer] = {d.severity, d.message};
  }
  ASSERT_EQ(said.count("/robot/link[@name='base_link']"), 1u);
  EXPECT_EQ(said["/robot/link[@name='base_link']"].first, Severity::kInfo);
  EXPECT_NE(said["/robot/link[@name='base_link']"].second.find(
                "root link 'base_link' has no <inertial>, and link 'inertial_link', fixed to it, carries the mass of the "
                "body they make: it is massless"),
            std::string::npos)
      << said["/robot/link[@name='base_link']"].second;
  EXPECT_EQ(said["/robot/link[@name='forearm']"].first, Severity::kInfo);
  EXPECT_NE(said["/robot/link[@name='forearm']"].second.find("link 'forearm_mass', fixed to it"), std::string::npos);
  EXPECT_EQ(said["/robot/link[@name='arm']"].first, Severity::kWarning);
}

TEST(UrdfImport, StlMeshesAreFoundByRelativeAbsoluteFileAndPackagePaths) {
  TempDir dir;
  fs::create_directories(dir / "my_pkg" / "meshes");
  fs::create_directories(dir / "my_pkg" / "urdf");
  TriangleMesh cube;
  for (int i = 0; i < 8; ++i) cube.positions.emplace_back((i & 1) ? 0.1 : -0.1, (i & 2) ? 0.1 : -0.1, (i & 4) ? 0.1 : -0.1);
  cube.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  const auto stl = stl_bytes(cube, "cube");
  testing::write_file(dir / "my_pkg" / "meshes" / "cube.stl", std::string(stl.begin(), stl.end()));
  const std::string absolute = (dir / "my_pkg" / "meshes" / "cube.stl").string();
  for (const std::string& filename : {std::string("../meshes/cube.stl"), absolute, "file://" + absolute,
                                      std::string("package://my_pkg/meshes/cube.stl")}) {
    SCOPED_TRACE(filename);
    testing::write_file(dir / "my_pkg" / "urdf" / "robot.urdf",
                        "<robot name=\"r\"><link name=\"cube\"><visual><geometry><mesh filename=\"" + filename +
                            "\" scale=\"2 1 1\"/></geometry></visual></link></robot>");
    Diagnostics diag;
    const Conversion conversion = import_or_fail(dir / "my_pkg" / "urdf" / "robot.urdf", diag);
    // 0.2 m cube, float32 corners, scaled 2x along one axis.
    EXPECT_NEAR(conversion.robot.links.at(0).inertial.volume, 0.016, 1e-6 * 0.016);
  }
  // file:// URIs as RFC 8089 has them: a percent-encoded path, and the host localhost (s90urdf D9).
  fs::create_directories(dir / "my dir");
  fs::copy_file(dir / "my_pkg" / "meshes" / "cube.stl", dir / "my dir" / "cube.stl");
  std::string encoded = (dir / "my dir" / "cube.stl").string();
  encoded.replace(encoded.find("my dir"), 6, "my%20dir");
  for (const std::string& uri : {"file://" + encoded, "file://localhost" + encoded, "file://LocalHost" + encoded,
                                 "file:" + encoded}) {
    SCOPED_TRACE(uri);
    testing::write_file(dir / "my_pkg" / "urdf" / "robot.urdf",
                        "<robot name=\"r\"><link name=\"cube\"><visual><geometry><mesh filename=\"" + uri +
                            "\"/></geometry></visual></link></robot>");
    Diagnostics diag;
    const Conversion conversion = import_or_fail(dir / "my_pkg" / "urdf" / "robot.urdf", diag);
    EXPECT_NEAR(conversion.robot.links.at(0).inertial.volume, 0.008, 1e-6 * 0.008);
  }
  // The URDF named by a path relative to the working folder, as in `cd my_pkg/urdf && rdtf import
  // robot.urdf`: the package is still found above it (the search ran out at the working folder).
  testing::write_file(dir / "my_pkg" / "urdf" / "robot.urdf",
                      "<robot name=\"r\"><link name=\"cube\"><visual><geometry><mesh filename=\""
                      "package://my_pkg/meshes/cube.stl\"/></geometry></visual></link></robot>");
  const fs::path before = fs::current_path();
  for (const auto& [folder, relative] : {std::pair<fs::path, fs::path>{dir / "my_pkg" / "urdf", "robot.urdf"},
                                         std::pair<fs::path, fs::path>{dir / "my_pkg", fs::path("urdf") / "robot.urdf"}}) {
    SCOPED_TRACE(relative.string());
    fs::current_path(folder);
    Diagnostics diag;
    const auto conversion = import_urdf(relative, {}, diag);
    fs::current_path(before);
    ASSERT_TRUE(conversion) << (diag.first_error() ? diag.first_error()->message : std::string());
    EXPECT_NEAR(conversion->robot.links.at(0).inertial.volume, 0.008, 1e-6 * 0.008);
  }
}

// ---- Round trip: URDF -> RDTF -> URDF ----

// Every joint kind URDF has but floating, rotated origins, an oblique axis, limits with effort
// and velocity, dynamics, and an inertial turned by rpy with a full tensor.
constexpr const char* kRichUrdf = R"(<?xml version="1.0"?>
<robot name="rich">
  <link name="base">
    <visual><origin xyz="0 0 0.05" rpy="0.1 0 0"/><geometry><box size="0.4 0.3 0.1"/></geometry></visual>
    <inertial><origin xyz="0.01 -0.02 0.03" rpy="0.3 -0.2 0.1"/><mass value="3.25"/>
      <inertia ixx="0.031" ixy="0.0012" ixz="-0.0007" iyy="0.045" iyz="0.0009" izz="0.052"/></inertial>
  </link>
  <link name="shoulder">
    <visual><geometry><cylinder radius="0.05" length="0.3"/></geometry></visual>
    <inertial><origin xyz="0 0 0.15"/><mass value="1.1"/>
      <inertia ixx="0.0089" ixy="0" ixz="0" iyy="0.0089" iyz="0" izz="0.0014"/></inertial>
  </link>
  <link name="slide">
    <visual><geometry><sphere radius="0.04"/></geometry></visual>
    <inertial><mass value="0.3"/><inertia ixx="0.0002" ixy="0" ixz="0" iyy="0.0002" iyz="0" izz="0.0002"/></inertial>
  </link>
  <link name="wheel">
    <inertial><origin xyz="0 0.001 0" rpy="1.5707963267948966 0 0"/><mass value="0.7"/>
      <inertia ixx="0.0011" ixy="0" ixz="0" iyy="0.0011" iyz="0" izz="0.002"/></inertial>
  </link>
  <link name="sensor">
    <inertial><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="2e-5" iyz="0" izz="2.5e-5"/></inertial>
  </link>
  <link name="puck">
    <inertial><mass value="0.2"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1.5e-4"/></inertial>
  </link>
  <joint name="shoulder_joint" type="revolute">
    <parent link="base"/><child link="shoulder"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.4 -0.5 0.6"/><axis xyz="0.6 0.8 0"/>
    <limit lower="-1.25" upper="2.5" effort="40" velocity="3.5"/>
    <dynamics damping="0.25" friction="0.125"/>
  </joint>
  <joint name="slide_joint" type="prismatic">
    <parent link="shoulder"/><child link="slide"/>
    <origin xyz="0 0 0.3" rpy="0 1.5707963267948966 0"/><axis xyz="0 0 1"/>
    <limit lower="-0.05" upper="0.1" effort="100" velocity="0.2"/>
    <dynamics damping="1.5" friction="0.5"/>
  </joint>
  <joint name="wheel_joint" type="continuous">
    <parent link="base"/><child link="wheel"/>
    <origin xyz="-0.2 0.15 0" rpy="0 0 3.0"/><axis xyz="0 1 0"/>
    <dynamics damping="0.01"/>
  </joint>
  <joint name="sensor_mount" type="fixed">
    <parent link="shoulder"/><child link="sensor"/><origin xyz="0.05 0 0.1" rpy="-1 0.5 2"/>
  </joint>
  <joint name="puck_joint" type="planar">
    <parent link="base"/><child link="puck"/><origin xyz="0 -0.15 0.05"/><axis xyz="0 0 1"/>
  </joint>
</robot>
)";

// Worst relative difference between the original URDF and its round trip, over all tests.
double& worst_round_trip() {
  static double worst = 0;
  return worst;
}

void expect_close(const std::string& what, double error, double tolerance) {
  EXPECT_LE(error, tolerance) << what;
  worst_round_trip() = std::max(worst_round_trip(), error);
}

Eigen::Matrix3d tensor_in_link_frame(const urdf::Inertial& in) {
  const Eigen::Matrix3d R = rotation_of(in.origin.rotation);
  return R * tensor_of(in) * R.transpose();
}

// Both URDFs say the same robot: tree, joint kinds, axes, limits, dynamics, origins, inertials.
void expect_same_robot(const urdf::ModelInterface& a, const urdf::ModelInterface& b) {
  EXPECT_EQ(b.getName(), a.getName());
  EXPECT_EQ(b.getRoot()->name, a.getRoot()->name);
  ASSERT_EQ(b.links_.size(), a.links_.size());
  ASSERT_EQ(b.joints_.size(), a.joints_.size());
  for (const auto& [name, theirs] : a.joints_) {
    SCOPED_TRACE("joint " + name);
    const auto ours = b.getJoint(name);
    ASSERT_TRUE(ours);
    EXPECT_EQ(ours->type, theirs->type);
    EXPECT_EQ(ours->parent_link_name, theirs->parent_link_name);
    EXPECT_EQ(ours->child_link_name, theirs->child_link_name);
    const urdf::Pose& pa = theirs->parent_to_joint_origin_transform;
    const urdf::Pose& pb = ours->parent_to_joint_origin_transform;
    expect_close(name + " origin xyz", relative_error(vector_of(pb.position), vector_of(pa.position)), kRelative);
    expect_close(name + " origin rotation", relative_error(rotation_of(pb.rotation), rotation_of(pa.rotation)), kRelative);
    if (theirs->type != urdf::Joint::FIXED && theirs->type != urdf::Joint::FLOATING) {
      const Eigen::Vector3d axis = vector_of(theirs->axis).normalized();
      expect_close(name + " axis", relative_error(vector_of(ours->axis), axis), kRelative);
    }
    ASSERT_EQ(!ours->limits, !theirs->limits);
    if (theirs->limits) {
      EXPECT_EQ(ours->limits->lower, theirs->limits->lower);
      EXPECT_EQ(ours->limits->upper, theirs->limits->upper);
      EXPECT_EQ(ours->limits->effort, theirs->limits->effort);
      EXPECT_EQ(ours->limits->velocity, theirs->limits->velocity);
    }
    if (theirs->dynamics) {
      ASSERT_TRUE(ours->dynamics);
      EXPECT_EQ(ours->dynamics->damping, theirs->dynamics->damping);
      EXPECT_EQ(ours->dynamics->friction, theirs->dynamics->friction);
    }
  }
  for (const auto& [name, theirs] : a.links_) {
    SCOPED_TRACE("link " + name);
    const auto ours = b.getLink(name);
    ASSERT_TRUE(ours);
    if (!theirs->inertial) continue;  // Computed from geometry on import.
    ASSERT_TRUE(ours->inertial);
    const urdf::Inertial& ia = *theirs->inertial;
    const urdf::Inertial& ib = *ours->inertial;
    expect_close(name + " mass", std::abs(ib.mass - ia.mass) / ia.mass, kRelative);
    // The centre of mass relative to the link's size (a zero component has no scale of its own).
    const double com_scale = std::max(vector_of(ia.origin.position).norm(), 1e-3);
    expect_close(name + " com", (vector_of(ib.origin.position) - vector_of(ia.origin.position)).norm() / com_scale, kRelative);
    expect_close(name + " inertia", relative_error(tensor_in_link_frame(ib), tensor_in_link_frame(ia)), kRelative);
  }
}

void round_trip(const fs::path& urdf) {
  Diagnostics diag;
  const Conversion conversion = import_or_fail(urdf, diag);
  TempDir dir;
  expect_valid_gltf(conversion, dir / "robot.gltf");
  const std::string text = export_to(conversion, dir / "again");
  expect_check_urdf_passes(dir / "again" / "robot.urdf");
  const auto original = parse_with_urdfdom(testing::read_file(urdf));
  expect_same_robot(*original, *parse_with_urdfdom(text));
  // And once more through the written glTF: the file keeps what the import made.
  Diagnostics again_diag;
  auto reread = convert_file(dir / "robot.gltf", ConvertOptions{}, again_diag);
  ASSERT_TRUE(reread);
  expect_same_robot(*original, *parse_with_urdfdom(export_to(*reread, dir / "third")));
  std::printf("round trip %s: worst relative difference so far %.3g\n", urdf.filename().c_str(), worst_round_trip());
}

// A wheel as published URDFs have it - a continuous joint with <limit effort velocity/> and no
// range - turns freely; a <limit> on a fixed joint (URDF allows it and reads nothing from it) is
// dropped. Both used to come out wrong: the wheel locked at [0, 0] in KHR_physics_rigid_bodies and
// in the URDF written back, the fixed joint with a range its KHR joint then disagreed with.
TEST(UrdfImport, WheelLimitsOfEffortAndSpeedAreNoRangeAndFixedJointLimitsAreDropped) {
  constexpr const char* kWheeled = R"(<?xml version="1.0"?>
<robot name="cart">
  <link name="chassis"><inertial><mass value="4"/><inertia ixx="0.05" iyy="0.06" izz="0.07" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="wheel"><inertial><mass value="0.5"/><inertia ixx="0.002" iyy="0.003" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="camera"><inertial><mass value="0.05"/><inertia ixx="1e-5" iyy="1e-5" izz="1e-5" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="wheel_joint" type="continuous">
    <parent link="chassis"/><child link="wheel"/><origin xyz="0.2 0.15 0"/><axis xyz="0 1 0"/>
    <limit effort="10" velocity="30"/>
  </joint>
  <joint name="camera_joint" type="fixed">
    <parent link="chassis"/><child link="camera"/><origin xyz="0.25 0 0.1"/>
    <limit lower="-10" upper="10" effort="1" velocity="1"/>
  </joint>
</robot>
)";
  TempDir dir;
  testing::write_file(dir / "cart.urdf", kWheeled);
  Diagnostics diag;
  const Conversion conversion = import_or_fail(dir / "cart.urdf", diag);
  const Robot& robot = conversion.robot;
  ASSERT_EQ(robot.joints.size(), 2u);
  const Joint& wheel = robot.joints[0].name == "wheel_joint" ? robot.joints[0] : robot.joints[1];
  const Joint& camera = robot.joints[0].name == "wheel_joint" ? robot.joints[1] : robot.joints[0];
  EXPECT_EQ(wheel.kind, JointKind::kContinuous);
  ASSERT_TRUE(wheel.limits);
  EXPECT_FALSE(wheel.limits->position);
  EXPECT_EQ(wheel.limits->effort, 10.0);
  EXPECT_EQ(wheel.limits->velocity, 30.0);
  EXPECT_EQ(camera.kind, JointKind::kFixed);
  EXPECT_FALSE(camera.limits);

  // The written glTF: the wheel's RDTF joint has no lower or upper, its KHR joint a free angular
  // axis 0; read again, no disagreement and the same limits.
  expect_valid_gltf(conversion, dir / "cart.gltf");
  const Json written = Json::parse(testing::read_file(dir / "cart.gltf"));
  for (const Json& node : written["nodes"]) {
    if (!node.contains("extras") || !node["extras"].contains("rdtf_joint")) continue;
    EXPECT_FALSE(node["extras"].contains("rdtf_lower")) << node.dump();
    EXPECT_FALSE(node["extras"].contains("rdtf_upper")) << node.dump();
  }
  for (const Json& joint : written["extensions"]["KHR_physics_rigid_bodies"]["physicsJoints"]) {
    for (const Json& limit : joint["limits"]) {  // Only a lock (0, 0) anywhere: no range on axis 0 either.
      EXPECT_EQ(limit["min"], 0.0) << joint.dump();
      EXPECT_EQ(limit["max"], 0.0) << joint.dump();
    }
  }
  Diagnostics again_diag;
  auto again = convert_file(dir / "cart.gltf", ConvertOptions{}, again_diag);
  ASSERT_TRUE(again);
  for (const Diagnostic& d : again_diag.all()) EXPECT_NE(d.code, "KHR_PHYSICS_IGNORED") << format(d);
  const Joint& wheel_again = again->robot.joints[0].name == "wheel_joint" ? again->robot.joints[0] : again->robot.joints[1];
  EXPECT_EQ(wheel_again.kind, JointKind::kContinuous);
  ASSERT_TRUE(wheel_again.limits);
  EXPECT_FALSE(wheel_again.limits->position);
  EXPECT_EQ(wheel_again.limits->effort, 10.0);

  // The URDF written back: the wheel's <limit> has effort and velocity, and no range.
  const std::string text = export_to(*again, dir / "back");
  expect_check_urdf_passes(dir / "back" / "robot.urdf");
  const std::size_t at = text.find("<joint name=\"wheel_joint\"");
  ASSERT_NE(at, std::string::npos) << text;
  const std::string joint_text = text.substr(at, text.find("</joint>", at) - at);
  EXPECT_NE(joint_text.find("effort=\"10\""), std::string::npos) << joint_text;
  EXPECT_EQ(joint_text.find("lower="), std::string::npos) << joint_text;
  EXPECT_EQ(joint_text.find("upper="), std::string::npos) << joint_text;
  const auto back = parse_with_urdfdom(text);
  ASSERT_TRUE(back->getJoint("wheel_joint")->limits);
  EXPECT_EQ(back->getJoint("wheel_joint")->limits->velocity, 30.0);
  EXPECT_FALSE(back->getJoint("camera_joint")->limits);
}

// Franka's second finger mimics the first: RDTF cannot couple them, and the user hears of it with
// a warning naming both joints (it was an info, hidden without -v, naming <mimic>,
// <safety_controller> and <calibration> together whichever the joint had).
TEST(UrdfImport, MimicJointIsAWarningNamingTheJointItFollows) {
  Diagnostics diag;
  import_or_fail(testing::data_dir() / "robots" / "panda.urdf", diag);
  const Diagnostic* mimic = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == "URDF_MIMIC_IGNORED") mimic = &d;
    if (d.code == "URDF_IGNORED") {
      EXPECT_EQ(d.message.find("<mimic>"), std::string::npos) << d.message;
    }
  }
  ASSERT_NE(mimic, nullptr);
  EXPECT_EQ(mimic->severity, Severity::kWarning);
  EXPECT_EQ(mimic->pointer, "/robot/joint[@name='panda_finger_joint2']/mimic");
  EXPECT_EQ(mimic->line, 173);  // Of <mimic>, where the user's editor goes.
  EXPECT_EQ(mimic->message,
            "line 173: joint 'panda_finger_joint2' mimics joint 'panda_finger_joint1' (multiplier 1, offset 0): RDTF "
            "has no "
            "coupled joints, so it is imported as a joint of its own that moves freely");
}

// A continuous joint's lower and upper mean nothing in URDF (urdfdom reads them, nothing uses
// them): lower above upper there imports, and the joint turns freely. Ignored elements are named
// at their own line.
TEST(UrdfImport, AContinuousJointsRangeIsIgnoredWhateverItSays) {
  testing::TempDir dir;
  testing::write_file(dir / "wheel.urdf", R"(<robot name="r">
<link name="a"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
<link name="b"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
<joint name="wheel" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/>
<limit lower="1" upper="-1" effort="5" velocity="3"/>
<safety_controller k_velocity="10"/>
</joint>
</robot>
)");
  Diagnostics diag;
  const auto conversion = import_urdf(dir / "wheel.urdf", UrdfImportOptions{}, diag);
  ASSERT_TRUE(conversion) << (diag.all().empty() ? "" : format(diag.all().front()));
  ASSERT_EQ(conversion->robot.joints.size(), 1u);
  const Joint& wheel = conversion->robot.joints[0];
  EXPECT_EQ(wheel.kind, JointKind::kContinuous);
  ASSERT_TRUE(wheel.limits);
  EXPECT_FALSE(wheel.limits->position);
  EXPECT_EQ(wheel.limits->effort, 5);
  const Diagnostic* ignored = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == "URDF_IGNORED") ignored = &d;
  }
  ASSERT_NE(ignored, nullptr);
  EXPECT_EQ(ignored->line, 6);  // <safety_controller>, not <joint> (line 4)
}

TEST(UrdfImport, RoundTripOfTheTutorialPhysicsRobot) { round_trip(tutorial("07-physics.urdf")); }

TEST(UrdfImport, RoundTripOfEveryJointKindAndRotatedInertial) {
  TempDir dir;
  testing::write_file(dir / "rich.urdf", kRichUrdf);
  round_trip(dir / "rich.urdf");
}

// Joint origins near gimbal lock (pitch within 1e-11 of 90 degrees, as a URDF's rounded pi/2
// gives): the export's roll and yaw used to carry rounding of 1e-16 / cos(pitch), 6e-6 rad here,
// which turned every link below the joint.
TEST(UrdfImport, RoundTripOfOriginsAtAndNearGimbalLock) {
  std::string urdf = R"(<?xml version="1.0"?>
<robot name="gimbal">
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>)";
  const char* pitches[] = {"1.5707963267920", "1.57079632679", "-1.5707963267949", "1.5707963267948966", "-1.5707963267948966",
                           "1.5707963", "0.7"};
  std::string parent = "base";
  for (std::size_t i = 0; i < std::size(pitches); ++i) {
    const std::string link = "l" + std::to_string(i);
    urdf += "<link name=\"" + link +
            "\"><inertial><mass value=\"1\"/><inertia ixx=\"0.1\" iyy=\"0.2\" izz=\"0.25\" ixy=\"0\" ixz=\"0\" "
            "iyz=\"0\"/></inertial></link><joint name=\"j" + std::to_string(i) + "\" type=\"revolute\"><parent link=\"" +
            parent + "\"/><child link=\"" + link + "\"/><origin xyz=\"0 0 0.1\" rpy=\"0.3 " + pitches[i] +
            " 0.2\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
    parent = link;
  }
  urdf += "</robot>";
  TempDir dir;
  testing::write_file(dir / "gimbal.urdf", urdf);
  round_trip(dir / "gimbal.urdf");
}

TEST(UrdfImport, ZUpOptionKeepsUrdfAxes) {
  TempDir dir;
  testing::write_file(dir / "rich.urdf", kRichUrdf);
  UrdfImportOptions options;
  options.z_up = true;
  Diagnostics diag;
  const Conversion conversion = import_or_fail(dir / "rich.urdf", diag, options);
  const Joint& shoulder = conversion.robot.joints.at(0);
  ASSERT_EQ(shoulder.name, "shoulder_joint");
  EXPECT_EQ(shoulder.X_PJ.translation(), Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_LE(relative_error(shoulder.axis, Eigen::Vector3d(0.6, 0.8, 0).normalized()), kRelative);
  UrdfOptions keep;
  keep.y_up = true;  // Export without turning either: the URDF's own numbers again.
  TempDir out;
  const auto original = parse_with_urdfdom(kRichUrdf);
  expect_same_robot(*original, *parse_with_urdfdom(export_to(conversion, out.path(), keep)));
}

// The checks of the numbers refuse only what urdfdom cannot read or what means nothing: every form
// urdfdom reads (a sign, a leading space, no digit before or after the point, an exponent, several
// spaces between numbers, a number too small for a double as 0) still imports, with its value; a
// zero mass is a massless link; a fixed joint's axis is not read (urdfdom ignores it).
TEST(UrdfImport, NumbersInEveryFormUrdfdomReadsAreImported) {
  TempDir dir;
  testing::write_file(dir / "forms.urdf", R"(<robot name="forms">
  <link name="a">
    <inertial><origin xyz="  .5   0 5. " rpy="0 0 0"/><mass value="+2.5e0"/>
      <inertia ixx=" 1" ixy="-0" ixz="0" iyy="1E0" iyz="1e-400" izz="1"/></inertial>
    <visual><geometry><box size="0.1 +0.2 3e-1"/></geometry></visual>
  </link>
  <link name="b"><inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <link name="c"/>
  <joint name="slide" type="prismatic"><parent link="a"/><child link="b"/><axis xyz="0 0 +1"/>
    <limit lower="-.25" upper="0.25" effort="1e-400" velocity="+3"/><dynamics damping="0.5"/></joint>
  <joint name="weld" type="fixed"><parent link="a"/><child link="c"/><axis xyz="0 0 0"/></joint>
</robot>
)");
  UrdfImportOptions options;
  options.z_up = true;  // The URDF's own numbers.
  Diagnostics diag;
  const Conversion conversion = import_or_fail(dir / "forms.urdf", diag, options);
  const Link& a = conversion.robot.links.at(0);
  ASSERT_EQ(a.name, "a");
  EXPECT_EQ(a.inertial.mass, 2.5);
  EXPECT_EQ(a.inertial.center_of_mass, Eigen::Vector3d(0.5, 0, 5));
  EXPECT_EQ(a.inertial.inertia, Eigen::Matrix3d::Identity());
  ASSERT_EQ(a.meshes.size(), 1u);  // The box is there.
  EXPECT_EQ(conversion.robot.links.at(1).inertial.mass, 0.0);
  const Joint& slide = conversion.robot.joints.at(0);
  ASSERT_EQ(slide.name, "slide");
  EXPECT_EQ(slide.axis, Eigen::Vector3d(0, 0, 1));
  ASSERT_TRUE(slide.limits);
  EXPECT_EQ(slide.limits->lower, -0.25);
  EXPECT_EQ(slide.limits->upper, 0.25);
  EXPECT_EQ(slide.limits->effort, 0.0);
  EXPECT_EQ(slide.limits->velocity, 3.0);
  EXPECT_EQ(slide.damping, 0.5);
  EXPECT_EQ(conversion.robot.joints.at(1).kind, JointKind::kFixed);
}

}  // namespace
}  // namespace rdtf
