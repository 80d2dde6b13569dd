// A rover grouped as Blender modellers group parts (tests/data/blender/make_groups.py): a body's
// meshes under an empty that carries its rdtf_density or rdtf_mass, and the frames and the axle
// parented to the part they sit on. The group is one link with the group's density or mass over
// all its meshes; what sits on a part hangs from the group's link, where Blender placed it.
// Blender's data is float32: volumes, centres and frames agree with it to about 1e-7 relative,
// so 1e-6 is the bound (as in blender_modelled_test.cc).
#include <gtest/gtest.h>

#include <algorithm>

#include "rdtf/convert.h"
#include "rdtf/write.h"
#include "support/test_support.h"
#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

constexpr double kBlenderFloat32 = 1e-6;

const Json& groups_record() {
  static const Json all = Json::parse(testing::read_file(testing::data_dir() / "blender" / "groups.json"));
  return all.at("modelled_groups");
}

Eigen::Vector3d vector_of(const Json& v) { return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()}; }

const Link* find_link(const Robot& robot, const std::string& name) {
  for (const Link& link : robot.links) {
    if (link.name == name) return &link;
  }
  return nullptr;
}

Conversion convert_rover(const std::filesystem::path& path, Diagnostics& diag) {
  auto conversion = convert_file(path, ConvertOptions{}, diag);
  for (const Diagnostic& d : diag.all()) {
    EXPECT_NE(d.severity, Severity::kError) << format(d);
    EXPECT_NE(d.severity, Severity::kWarning) << format(d);
  }
  if (!conversion) throw std::runtime_error(path.string() + " did not convert");
  return std::move(*conversion);
}

void expect_as_grouped(const Robot& robot, const Json& expected) {
  std::vector<std::string> names;
  for (const Link& link : robot.links) names.push_back(link.name);
  EXPECT_EQ(names, (std::vector<std::string>{"chassis", "imu", "wheel", "mast", "camera"}));
  for (const auto& [name, want] : expected["links"].items()) {
    const Link* link = find_link(robot, name);
    ASSERT_NE(link, nullptr) << name;
    const double mass = want["mass"].get<double>();
    EXPECT_NEAR(link->inertial.mass, mass, kBlenderFloat32 * mass) << name;
    EXPECT_NEAR(link->inertial.volume, want["volume"].get<double>(), kBlenderFloat32 * want["volume"].get<double>())
        << name;
    const Eigen::Vector3d com_scene = link->X_SL * link->inertial.center_of_mass;
    EXPECT_LE((com_scene - vector_of(want["com_scene"])).norm(), kBlenderFloat32) << name << ": " << com_scene.transpose();
  }
  for (const Json& name : expected["frame_links"]) {
    const Link* frame = find_link(robot, name.get<std::string>());
    ASSERT_NE(frame, nullptr) << name;
    EXPECT_EQ(frame->inertial.mass, 0.0) << name;
    EXPECT_TRUE(frame->meshes.empty()) << name;
  }
  ASSERT_EQ(robot.joints.size(), expected["joints"].size());
  for (const Json& want : expected["joints"]) {
    const std::string name = want["name"].get<std::string>();
    const Joint* joint = nullptr;
    for (const Joint& j : robot.joints) {
      if (j.name == name) joint = &j;
    }
    ASSERT_NE(joint, nullptr) << "no joint " << name;
    EXPECT_EQ(robot.links[joint->parent_link].name, want["parent"].get<std::string>()) << name;
    EXPECT_EQ(robot.links[joint->child_link].name, want["child"].get<std::string>()) << name;
    EXPECT_EQ(std::string(to_string(joint->kind)), want["type"].get<std::string>()) << name;
    // The joint frame where Blender has the empty: origin and all three axes.
    const Eigen::Isometry3d X_SJ = robot.links[joint->parent_link].X_SL * joint->X_PJ;
    EXPECT_LE((X_SJ.translation() - vector_of(want["pivot_scene"])).norm(), kBlenderFloat32) << name;
    EXPECT_LE((X_SJ.linear().col(0) - vector_of(want["x_scene"])).norm(), kBlenderFloat32) << name;
    EXPECT_LE((X_SJ.linear().col(1) - vector_of(want["y_scene"])).norm(), kBlenderFloat32) << name;
    EXPECT_LE((X_SJ.linear().col(2) - vector_of(want["z_scene"])).norm(), kBlenderFloat32) << name;
    // The axle turns about the empty's Z, as typed in Blender ("z").
    if (want.contains("axis_scene")) {
      EXPECT_LE((X_SJ.linear() * joint->axis - vector_of(want["axis_scene"])).norm(), kBlenderFloat32) << name;
    }
  }
}

TEST(BlenderGroups, GroupIsOneLinkWithItsDensityAndMassAndFramesSitWhereModelled) {
  Diagnostics diag;
  const Conversion conversion = convert_rover(testing::data_dir() / "blender" / "modelled_groups.glb", diag);
  expect_as_grouped(conversion.robot, groups_record());
  // Joint empties and frames parented to a part of a group: the part stays in the group's link.
  for (const Diagnostic& d : diag.all()) {
    if (d.code != "LINK_MESH_SPLIT") continue;
    EXPECT_NE(d.message.find("link 'wheel'"), std::string::npos) << "only the wheel carries its own mesh: " << format(d);
  }
}

TEST(BlenderGroups, OutputIsValidAndConvertsToTheSameRobot) {
  Diagnostics diag;
  const Conversion first = convert_rover(testing::data_dir() / "blender" / "modelled_groups.glb", diag);
  const testing::TempDir dir;
  WriteOptions options;
  options.format = OutputFormat::kGlb;
  ASSERT_TRUE(write_rdtf(first.asset, dir / "rover.rdtf.glb", options, diag));
  const auto report = testing::khronos_report(dir / "rover.rdtf.glb");
  EXPECT_EQ(report["issues"]["numErrors"].get<int>(), 0) << report.dump();
  // Every node is where it was: the nodes the frames hang from copy the parts' transforms.
  Diagnostics again_diag;
  const Conversion again = convert_rover(dir / "rover.rdtf.glb", again_diag);
  expect_as_grouped(again.robot, groups_record());
  ASSERT_EQ(again.robot.links.size(), first.robot.links.size());
  for (std::size_t l = 0; l < first.robot.links.size(); ++l) {
    const Link& a = first.robot.links[l];
    const Link& b = again.robot.links[l];
    EXPECT_EQ(b.name, a.name);
    // Same double arithmetic on the same float32 data: equal to rounding.
    EXPECT_NEAR(b.inertial.mass, a.inertial.mass, 1e-12 * std::max(1.0, a.inertial.mass)) << a.name;
    EXPECT_TRUE(b.inertial.inertia.isApprox(a.inertial.inertia, 1e-9)) << a.name;
  }
}

// my_robot (an empty) -> base_link (a box) -> shoulder (a joint empty) -> arm: the common layout of
// a robot under one root empty. Without rdtf_density or rdtf_mass the empty only holds the robot:
// base_link stays a link (URDF and TF keep its name) and the shoulder hangs from it. With
// rdtf_density on the empty, base_link is a part of its group: the shoulder hangs from my_robot,
// at the same place, and MESH_HOLDS_FRAMES says so.
Robot robot_under_root_empty(const Json& root_extras, Diagnostics& diag, const Json& part_extras = Json::object()) {
  urdf_test::GltfBuilder b;
  const int box = b.box_mesh(Eigen::Vector3f(0.2f, 0.1f, 0.2f));
  const int root = b.node("my_robot", -1, root_extras.empty() ? Json::object() : Json{{"extras", root_extras}});
  Json part = {{"mesh", box}, {"translation", {0, 0.05, 0}}};
  if (!part_extras.empty()) part["extras"] = part_extras;
  const int base = b.node("base_link", root, part);
  const int shoulder = b.node("shoulder", base, Json{{"translation", {0, 0.05, 0}},
                                                     {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", "y"},
                                                                 {"rdtf_lower", -1}, {"rdtf_upper", 1}}}});
  b.node("arm", shoulder, Json{{"mesh", box}, {"translation", {0, 0.1, 0}}});
  return b.convert(diag).robot;
}

std::vector<std::string> link_names(const Robot& robot) {
  std::vector<std::string> names;
  for (const Link& link : robot.links) names.push_back(link.name);
  return names;
}

TEST(BlenderGroups, AnEmptyWithoutDensityOrMassOnlyHoldsTheRobot) {
  Diagnostics plain;
  const Robot held = robot_under_root_empty(Json::object(), plain);
  EXPECT_EQ(link_names(held), (std::vector<std::string>{"my_robot", "base_link", "arm"}));
  EXPECT_FALSE(plain.contains("MESH_HOLDS_FRAMES"));
  ASSERT_EQ(held.joints.size(), 2u);
  for (const Joint& joint : held.joints) {
    if (joint.name == "shoulder") {
      EXPECT_EQ(held.links[joint.parent_link].name, "base_link");
    }
  }

  Diagnostics grouped;
  const Robot group = robot_under_root_empty(Json{{"rdtf_density", 2000.0}}, grouped);
  EXPECT_EQ(link_names(group), (std::vector<std::string>{"my_robot", "arm"}));
  ASSERT_EQ(group.joints.size(), 1u);
  EXPECT_EQ(group.links[group.joints[0].parent_link].name, "my_robot");
  // The pivot where the modeller put it: base_link at 0.05, the shoulder 0.05 above it.
  const Eigen::Isometry3d X_SJ = group.links[group.joints[0].parent_link].X_SL * group.joints[0].X_PJ;
  EXPECT_LE((X_SJ.translation() - Eigen::Vector3d(0, 0.1, 0)).norm(), 1e-12);
  // The group's density is the part's: 0.2 x 0.1 x 0.2 m at 2000 kg/m^3 (float32 corners).
  const double volume = double(0.2f) * double(0.1f) * double(0.2f);
  EXPECT_NEAR(group.links[0].inertial.mass, 2000 * volume, 1e-6 * 2000 * volume);
  const auto info = std::find_if(grouped.all().begin(), grouped.all().end(),
                                 [](const Diagnostic& d) { return d.code == "MESH_HOLDS_FRAMES"; });
  ASSERT_NE(info, grouped.all().end());
  EXPECT_EQ(info->severity, Severity::kInfo);
  EXPECT_NE(info->message.find("mesh node 'base_link' is a part of group 'my_robot'"), std::string::npos) << info->message;
  EXPECT_NE(info->message.find("('shoulder')"), std::string::npos) << info->message;
}

// A part with joint keys but no rdtf_joint was meant to move: it stays a link, and the missing
// type is said (JOINT_TYPE_MISSING), as anywhere else.
TEST(BlenderGroups, APartWithJointKeysStaysALink) {
  Diagnostics diag;
  const Robot robot = robot_under_root_empty(Json{{"rdtf_density", 2000.0}}, diag, Json{{"rdtf_axis", "x"}});
  EXPECT_EQ(link_names(robot), (std::vector<std::string>{"my_robot", "base_link", "arm"}));
  EXPECT_TRUE(diag.contains("JOINT_TYPE_MISSING"));
  EXPECT_FALSE(diag.contains("MESH_HOLDS_FRAMES"));
}

}  // namespace
}  // namespace rdtf
