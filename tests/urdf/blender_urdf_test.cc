// The URDF of every Blender fixture: the exact tree (links, joints, kinds, parents, children),
// accepted by check_urdf and by urdfdom's parser, and the export's warnings where URDF differs.
#include <map>
#include <set>
#include <tuple>

#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using namespace urdf_test;

struct ExpectedJoint {
  std::string type, parent, child;
  bool operator==(const ExpectedJoint&) const = default;
};

std::ostream& operator<<(std::ostream& out, const ExpectedJoint& j) {
  return out << "{" << j.type << ", " << j.parent << " -> " << j.child << "}";
}

struct ExpectedTree {
  std::string root;
  std::set<std::string> links;
  std::map<std::string, ExpectedJoint> joints;  // By joint name.
};

std::string type_name(int type) {
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

// Exports the fixture, runs check_urdf on the file and compares urdfdom's reading of it with the
// expected tree. Returns the export's diagnostics.
Diagnostics expect_tree(const std::string& fixture, const ExpectedTree& expected) {
  const Conversion conversion = convert_fixture(fixture);
  TempDir dir;
  Diagnostics diag;
  std::string text;
  EXPECT_TRUE(write_urdf(conversion, dir.path(), UrdfOptions{}, diag, &text));
  expect_check_urdf_passes(dir / "robot.urdf");
  const auto model = parse_with_urdfdom(text);
  EXPECT_EQ(model->getRoot()->name, expected.root);
  std::set<std::string> links;
  for (const auto& [name, link] : model->links_) links.insert(name);
  EXPECT_EQ(links, expected.links);
  std::map<std::string, ExpectedJoint> joints;
  for (const auto& [name, joint] : model->joints_) {
    joints[name] = {type_name(joint->type), joint->parent_link_name, joint->child_link_name};
  }
  EXPECT_EQ(joints, expected.joints);
  // Each link with a mesh has its STL beside the URDF.
  for (const auto& [name, link] : model->links_) {
    if (link->visual) {
      EXPECT_TRUE(std::filesystem::is_regular_file(dir / ("meshes/" + name + ".stl"))) << name;
    }
  }
  return diag;
}

TEST(UrdfBlender, TwoCylinderTree) {
  const Diagnostics diag = expect_tree(
      "two_cylinder.gltf", {"base", {"base", "arm"}, {{"base_arm_joint", {"fixed", "base", "arm"}}}});
  EXPECT_FALSE(diag.has_errors());
}

TEST(UrdfBlender, Arm3Tree) {
  // The elbow is revolute without limits: URDF needs limits, so it is continuous, with a warning.
  const Diagnostics diag = expect_tree("arm3.gltf", {"base_link",
                                                     {"base_link", "upper_arm", "forearm"},
                                                     {{"shoulder", {"revolute", "base_link", "upper_arm"}},
                                                      {"elbow", {"continuous", "upper_arm", "forearm"}}}});
  EXPECT_TRUE(diag.contains("URDF_REVOLUTE_WITHOUT_LIMITS"));
}

TEST(UrdfBlender, TransformsTree) {
  const Diagnostics diag = expect_tree(
      "transforms.gltf",
      {"chassis",
       {"chassis", "tilted_sensor", "wheel_l", "wheel_r_mirrored"},
       {{"chassis_tilted_sensor_joint", {"fixed", "chassis", "tilted_sensor"}},
        {"chassis_wheel_l_joint", {"fixed", "chassis", "wheel_l"}},
        {"chassis_wheel_r_mirrored_joint", {"fixed", "chassis", "wheel_r_mirrored"}}}});
  EXPECT_FALSE(diag.has_errors());
}

TEST(UrdfBlender, SkinnedArmTree) {
  const Diagnostics diag = expect_tree(
      "skinned_arm.gltf",
      {"robot_armature",
       {"robot_armature", "link0", "link1", "link2"},
       {{"robot_armature_link0_joint", {"fixed", "robot_armature", "link0"}},
        {"link0_link1_joint", {"fixed", "link0", "link1"}},
        {"link1_link2_joint", {"fixed", "link1", "link2"}}}});
  EXPECT_FALSE(diag.has_errors());
}

// The joint values of arm3 in URDF axes: the shoulder turns about glTF y, which is URDF z, with
// its limits and damping; the elbow sits 0.5 m up (glTF y), which is URDF +z.
TEST(UrdfBlender, Arm3JointValues) {
  const Conversion conversion = convert_fixture("arm3.gltf");
  TempDir dir;
  const auto model = parse_with_urdfdom(export_to(conversion, dir.path()));
  const auto shoulder = model->getJoint("shoulder");
  ASSERT_TRUE(shoulder && shoulder->limits);
  EXPECT_EQ(vector_of(shoulder->axis), Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(shoulder->limits->lower, -1.57);
  EXPECT_EQ(shoulder->limits->upper, 1.57);
  const auto elbow = model->getJoint("elbow");
  ASSERT_TRUE(elbow && elbow->dynamics);
  EXPECT_EQ(elbow->dynamics->damping, 0.4);
  const Joint& ours = conversion.robot.joints.at(1);
  const Eigen::Vector3d t = ours.X_PJ.translation();
  EXPECT_EQ(vector_of(elbow->parent_to_joint_origin_transform.position), Eigen::Vector3d(t.x(), -t.z(), t.y()));
  EXPECT_NEAR(elbow->parent_to_joint_origin_transform.position.z, 0.5, 1e-15);

  // --y-up keeps glTF's axes: the same joint turns about y.
  TempDir y_up;
  UrdfOptions options;
  options.y_up = true;
  const auto kept = parse_with_urdfdom(export_to(conversion, y_up.path(), options));
  EXPECT_EQ(vector_of(kept->getJoint("shoulder")->axis), Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(vector_of(kept->getJoint("elbow")->parent_to_joint_origin_transform.position), t);
}

}  // namespace
}  // namespace rdtf
