// A rover grouped as Blender modellers group parts (tests/data/blender/make_groups.py): a body's
// meshes under an empty that carries its rdtf_density or rdtf_mass, and the frames and the axle
// parented to the part they sit on. The group is one link with the group's density or mass over
// all its meshes; what sits on a part hangs from the group's link, where Blender placed it.
// Blender's data is float32: volumes, centres and frames agree with it to about 1e-7 relative,
// so 1e-6 is the bound (as in blender_modelled_test.cc).
#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/write.h"
#include "support/test_support.h"

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

}  // namespace
}  // namespace rdtf
