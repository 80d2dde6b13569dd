// One name everywhere a ROS tool matches them (docs/urdf.md, "Names"): arm3 renamed as a modeller
// might (spaces, and names that are one URDF name once sanitised) publishes JOINT_STATE,
// LINK_STATE and INERTIA whose `name` is the <joint name> / <link name> of the URDF published with
// the same revision (parsed here with urdfdom) and whose `gltf_name` is the glTF node's name; a
// JOINT_COMMAND by URDF name moves the joint of that name.
#include <set>

#include <urdf_parser/urdf_parser.h>

#include <rdtf/link_state_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "safe_decode.h"

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

// A NUL in a name or a URI, which JSON allows (\u0000): LCM ends a string at its first NUL while
// sizing it whole, so quoted raw it left every message that carries it undecodable by every
// subscriber (VALIDATION, the states, the inertia table, an ERROR): the model stayed "pending" in
// rdtf-view and a refusal was never seen. Each message arrives whole, the NUL as "\x00".
TEST(RosNames, ANulInANameOrAUriReachesTheBusAsBackslashX00) {
  Session s;
  copy_fixture(s.watch, "arm3");
  Json document = Json::parse(read(s.watch / "arm3.gltf"));
  for (auto& node : document["nodes"]) {
    if (node.value("name", "") == "elbow") node["name"] = std::string("el\0bow", 6);
  }
  const std::string gltf = document.dump(1);
  ASSERT_NE(gltf.find("el\\u0000bow"), std::string::npos);
  write_in_place(s.watch / "arm3.gltf", gltf);
  const std::string hash = content_hash(gltf, {read(s.watch / "arm3.bin")});
  document["buffers"][0]["uri"] = std::string("arm3.bin\0../x", 13);
  write_in_place(s.watch / "nul_uri.gltf", document.dump(1));
  s.start(DaemonOptions().with("simulate", true).with("state_rate_hz", 100).with("validate", true).with(
      "validation_seconds", 0.5));
  ASSERT_TRUE(s.wait_revision(kArm, 1, hash));
  ASSERT_TRUE(s.wait_for([](const auto& all) {
    return last_state(all, 1).has_value() && !on_kind(all, "LINK_STATE", kArm).empty() &&
           !on_kind(all, "VALIDATION", kArm).empty() && !on_kind(all, "DELTA", kArm).empty() &&
           !on_kind(all, "ERROR", "nul_uri.gltf").empty();
  })) << ::testing::PrintToString(model_events(s.messages()));
  for (const Message& m : s.messages()) {
    EXPECT_EQ(lcm_safe::check_known(m.bytes.data(), m.bytes.size()), "") << m.channel;
  }
  const rdtf::joint_state_t joints = *last_state(s.messages(), 1);
  EXPECT_EQ(joints.name, (std::vector<std::string>{"shoulder", "el_bow"}));
  EXPECT_EQ(joints.gltf_name, (std::vector<std::string>{"shoulder", "el\\x00bow"}));
  const auto validation = decoded<rdtf::validation_report_t>(s.messages(), "VALIDATION", kArm).back();
  EXPECT_TRUE(validation.passed);
  const auto renamed = std::find_if(validation.diagnostics.begin(), validation.diagnostics.end(),
                                    [](const rdtf::diagnostic_t& d) { return d.code == "URDF_NAME_CHANGED"; });
  ASSERT_NE(renamed, validation.diagnostics.end());
  EXPECT_NE(renamed->message.find("'el\\x00bow' is named 'el_bow'"), std::string::npos) << renamed->message;
  const auto error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "nul_uri.gltf").back();
  ASSERT_FALSE(error.diagnostics.empty());
  EXPECT_EQ(error.diagnostics[0].pointer, "/buffers/0/uri");
  EXPECT_NE(error.diagnostics[0].message.find("arm3.bin\\x00../x"), std::string::npos) << error.diagnostics[0].message;
}

}  // namespace
}  // namespace rdtf::itest
