// One name everywhere a ROS tool matches them (docs/urdf.md, "Names"): arm3 renamed as a modeller
// might (spaces, and names that are one URDF name once sanitised) publishes JOINT_STATE,
// LINK_STATE and INERTIA whose `name` is the <joint name> / <link name> of the URDF published with
// the same revision (parsed here with urdfdom) and whose `gltf_name` is the glTF node's name; a
// JOINT_COMMAND by URDF name moves the joint of that name.
#include <set>

#include <urdf_parser/urdf_parser.h>

#include <rdtf/link_state_t.hpp>

#include "clients/live_arm.h"

namespace rdtf::itest {
namespace {

// arm3's links base_link, upper_arm, forearm and joints shoulder (base_link -> upper_arm) and
// elbow (upper_arm -> forearm), renamed: "upper arm" and "upper_arm" are both "upper_arm" once
// sanitised, and so are "shoulder joint" and "shoulder_joint". The one valid as it is keeps it
// (though it comes second in the description), the other gets "_2".
const std::map<std::string, std::string> kRenamed = {{"base_link", "base link"},
                                                     {"upper_arm", "upper arm"},
                                                     {"forearm", "upper_arm"},
                                                     {"shoulder", "shoulder joint"},
                                                     {"elbow", "shoulder_joint"}};

std::string write_renamed_arm(const fs::path& folder) {
  copy_fixture(folder, "arm3");
  Json document = Json::parse(read(folder / "arm3.gltf"));
  int renamed = 0;
  for (auto& node : document["nodes"]) {
    const auto to = kRenamed.find(node.value("name", ""));
    if (to == kRenamed.end()) continue;
    node["name"] = to->second;
    ++renamed;
  }
  if (renamed != static_cast<int>(kRenamed.size())) throw std::runtime_error("arm3's nodes are not as expected");
  const std::string gltf = document.dump(1);
  write_in_place(folder / "arm3.gltf", gltf);
  return content_hash(gltf, {read(folder / "arm3.bin")});
}

TEST(RosNames, StatesAndInertiaCarryTheUrdfNamesAndCommandsUseThem) {
  Session s;
  const std::string hash = write_renamed_arm(s.watch);
  // The commands below are sent once and watched for a while: the longest command lifetime.
  s.start(DaemonOptions().with("simulate", true).with("state_rate_hz", 100).with("joint_command_timeout_s", 60));
  ASSERT_TRUE(s.wait_revision(kArm, 1, hash));
  ASSERT_TRUE(s.wait_for(
      [](const auto& all) { return last_state(all, 1).has_value() && !on_kind(all, "LINK_STATE", kArm).empty(); }));

  // The URDF of revision 1, as published in its description.
  const auto description = last_description(s.messages(), kArm);
  ASSERT_TRUE(description);
  ASSERT_EQ(description->num_urdf_chunks, 0) << "arm3's URDF is expected inline";
  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(description->urdf);
  ASSERT_TRUE(urdf) << description->urdf;
  std::set<std::string> urdf_links, urdf_joints;
  for (const auto& [name, link] : urdf->links_) urdf_links.insert(name);
  for (const auto& [name, joint] : urdf->joints_) urdf_joints.insert(name);
  EXPECT_EQ(urdf_links, (std::set<std::string>{"base_link", "upper_arm_2", "upper_arm"}));
  EXPECT_EQ(urdf_joints, (std::set<std::string>{"shoulder_joint_2", "shoulder_joint"}));

  const rdtf::joint_state_t joints = *last_state(s.messages(), 1);
  EXPECT_EQ(joints.name, (std::vector<std::string>{"shoulder_joint_2", "shoulder_joint"}));
  EXPECT_EQ(joints.gltf_name, (std::vector<std::string>{"shoulder joint", "shoulder_joint"}));
  const auto links = decoded<rdtf::link_state_t>(s.messages(), "LINK_STATE", kArm).back();
  EXPECT_EQ(links.name, (std::vector<std::string>{"base_link", "upper_arm_2", "upper_arm"}));
  EXPECT_EQ(links.gltf_name, (std::vector<std::string>{"base link", "upper arm", "upper_arm"}));
  // Each state name is the URDF's, and the joints join the links the states name: the second
  // joint (the elbow) holds the second link (the upper arm) and the third (the forearm).
  for (const auto& name : joints.name) EXPECT_TRUE(urdf_joints.count(name)) << name;
  for (const auto& name : links.name) EXPECT_TRUE(urdf_links.count(name)) << name;
  const auto elbow = urdf->getJoint(joints.name.at(1));
  ASSERT_TRUE(elbow);
  EXPECT_EQ(elbow->parent_link_name, links.name.at(1));
  EXPECT_EQ(elbow->child_link_name, links.name.at(2));
  EXPECT_EQ(urdf->getJoint(joints.name.at(0))->child_link_name, links.name.at(1));

  const auto inertia = last_inertia(s.messages(), kArm);
  ASSERT_TRUE(inertia);
  ASSERT_EQ(inertia->links.size(), links.name.size());
  for (std::size_t l = 0; l < inertia->links.size(); ++l) {
    EXPECT_EQ(inertia->links[l].name, links.name[l]);
    EXPECT_EQ(inertia->links[l].gltf_name, links.gltf_name[l]);
    // The URDF's inertial is the table's (the mass as written, exactly).
    const auto urdf_link = urdf->getLink(inertia->links[l].name);
    ASSERT_TRUE(urdf_link && urdf_link->inertial) << inertia->links[l].name;
    EXPECT_EQ(urdf_link->inertial->mass, inertia->links[l].mass) << inertia->links[l].name;
  }

  // A torque on the elbow by its URDF name, which is its glTF name too: the elbow turns, its
  // effort is the torque, the shoulder's none.
  const double tau = 0.1;
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND",
                       make_command(kArm, 1, hash, {{"shoulder_joint", rdtf::joint_command_t::TORQUE, tau}}));
  ASSERT_TRUE(s.wait_for(
      [](const auto& all) {
        const auto last = last_state(all, 1);
        return last && *position_of(*last, "shoulder_joint") > 0.05;
      },
      5s))
      << "the elbow did not turn";
  auto last = *last_state(s.messages(), 1);
  EXPECT_EQ(last.effort.at(1), tau);
  EXPECT_EQ(last.effort.at(0), 0.0);
  // A glTF name that only one joint has names that joint: the shoulder.
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND",
                       make_command(kArm, 1, hash, {{"shoulder joint", rdtf::joint_command_t::TORQUE, -tau}}));
  ASSERT_TRUE(s.wait_for(
      [&](const auto& all) {
        const auto state = last_state(all, 1);
        return state && state->effort.at(0) == -tau;
      },
      5s))
      << "the shoulder got no torque";
  EXPECT_TRUE(rejections(s.messages()).empty()) << ::testing::PrintToString(rejections(s.messages()));
}

// The names do not depend on the URDF being written: with "urdf": false the description has no
// URDF, and the states and the inertia table carry the same names as above.
TEST(RosNames, WithoutAUrdfTheStatesCarryTheSameNames) {
  Session s;
  const std::string hash = write_renamed_arm(s.watch);
  s.start(DaemonOptions().with("simulate", true).with("state_rate_hz", 100).with("urdf", false));
  ASSERT_TRUE(s.wait_revision(kArm, 1, hash));
  ASSERT_TRUE(s.wait_for(
      [](const auto& all) { return last_state(all, 1).has_value() && !on_kind(all, "LINK_STATE", kArm).empty(); }));
  const auto description = last_description(s.messages(), kArm);
  ASSERT_TRUE(description);
  EXPECT_EQ(description->urdf_size, 0);
  const rdtf::joint_state_t joints = *last_state(s.messages(), 1);
  EXPECT_EQ(joints.name, (std::vector<std::string>{"shoulder_joint_2", "shoulder_joint"}));
  EXPECT_EQ(joints.gltf_name, (std::vector<std::string>{"shoulder joint", "shoulder_joint"}));
  const auto links = decoded<rdtf::link_state_t>(s.messages(), "LINK_STATE", kArm).back();
  EXPECT_EQ(links.name, (std::vector<std::string>{"base_link", "upper_arm_2", "upper_arm"}));
  EXPECT_EQ(links.gltf_name, (std::vector<std::string>{"base link", "upper arm", "upper_arm"}));
  const auto inertia = last_inertia(s.messages(), kArm);
  ASSERT_TRUE(inertia);
  ASSERT_EQ(inertia->links.size(), 3u);
  for (std::size_t l = 0; l < 3; ++l) {
    EXPECT_EQ(inertia->links[l].name, links.name[l]);
    EXPECT_EQ(inertia->links[l].gltf_name, links.gltf_name[l]);
  }
}

}  // namespace
}  // namespace rdtf::itest
