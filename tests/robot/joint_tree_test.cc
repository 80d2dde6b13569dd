// Which link a joint hangs from (core/robot/robot.cc, docs/format.md "Links and joints"): a joint
// node with joint properties is one moving part, so what hangs from it beside its link hangs from
// that link. The layouts are Blender's: parts parented to bones (Ctrl+P > Bone), whose bones
// chain bone to bone; an elbow empty parented to the shoulder empty; two jaws under one grip
// empty. The meshes are tests/data/khr/arm_extras.gltf's 0.4 x 0.2 x 0.2 m box.
#include <algorithm>

#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/write.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

using nlohmann::json;

json with_nodes(const json& nodes, const json& roots) {
  json doc = json::parse(testing::read_file(testing::data_dir() / "khr" / "arm_extras.gltf"));
  doc["nodes"] = nodes;
  doc["scenes"] = {{{"nodes", roots}}};
  doc["scene"] = 0;
  return doc;
}

json revolute(const char* axis) { return {{"rdtf_joint", "revolute"}, {"rdtf_axis", axis}}; }

struct Converted {
  Robot robot;
  Diagnostics diag;
  Json document;  // The output, as written and read back.
};

Converted convert_doc(const json& doc) {
  testing::TempDir dir;
  testing::write_file(dir / "robot.gltf", doc.dump());
  Converted out;
  auto conversion = convert_file(dir / "robot.gltf", {}, out.diag);
  if (!conversion) throw std::runtime_error("did not convert: " + (out.diag.first_error() ? format(*out.diag.first_error()) : ""));
  EXPECT_FALSE(out.diag.has_errors());
  out.robot = conversion->robot;
  Diagnostics write_diag;
  EXPECT_TRUE(write_rdtf(conversion->asset, dir / "out.gltf", OutputFormat::kGltf, write_diag));
  out.document = Json::parse(testing::read_file(dir / "out.gltf"));
  return out;
}

// "child <- parent by joint (kind)" for every link but the roots, in link order.
std::vector<std::string> tree(const Robot& robot) {
  std::vector<std::string> lines;
  for (const Link& link : robot.links) {
    if (link.parent_joint < 0) continue;
    const Joint& joint = robot.joints[link.parent_joint];
    lines.push_back(link.name + " <- " + robot.links[joint.parent_link].name + " by " + joint.name + " (" +
                    to_string(joint.kind) + ")");
  }
  return lines;
}

std::vector<Diagnostic> with_code(const Diagnostics& diag, const std::string& code) {
  std::vector<Diagnostic> found;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == code) found.push_back(d);
  }
  return found;
}

// Converting the output again, with its extras.RDTF and with only its node extras (what
// Blender's importer keeps), gives the same tree.
void expect_same_tree_again(const Converted& first) {
  Converted again = convert_doc(first.document);
  EXPECT_EQ(tree(again.robot), tree(first.robot));
  json node_extras_only = first.document;
  node_extras_only.erase("extras");
  Converted blender = convert_doc(node_extras_only);
  EXPECT_EQ(tree(blender.robot), tree(first.robot));
}

// An armature with bones b0 -> b1 -> b2 (Blender writes a bone's children bones first), a part
// parented to each bone, joint properties on b1 and b2. Turning b1 moves part1 and, through b2,
// part2: part2 hangs from part1.
TEST(JointTree, PartsParentedToBonesHangFromThePartOfTheBoneAbove) {
  const json nodes = {
      {{"name", "armature"}, {"children", {1}}},
      {{"name", "b0"}, {"children", {2, 4}}},
      {{"name", "b1"}, {"translation", {0, 0.5, 0}}, {"children", {3, 5}}, {"extras", revolute("x")}},
      {{"name", "b2"}, {"translation", {0, 0.5, 0}}, {"children", {6}}, {"extras", revolute("z")}},
      {{"name", "part0"}, {"mesh", 0}},
      {{"name", "part1"}, {"mesh", 0}, {"translation", {0, 0.25, 0}}},
      {{"name", "part2"}, {"mesh", 0}, {"translation", {0, 0.25, 0}}}};
  const Converted c = convert_doc(with_nodes(nodes, {0}));
  EXPECT_EQ(tree(c.robot), (std::vector<std::string>{"part1 <- b0 by b1 (revolute)", "part2 <- part1 by b2 (revolute)"}));
  EXPECT_TRUE(with_code(c.diag, codes::JOINT_CHAIN).empty());
  // b2's pivot, in part1's frame (which is b1's: the joint frame), is 0.5 m along y.
  const Joint& b2 = c.robot.joints[c.robot.links[2].parent_joint];
  EXPECT_TRUE(b2.X_PJ.translation().isApprox(Eigen::Vector3d(0, 0.5, 0), 1e-12)) << b2.X_PJ.translation().transpose();
  expect_same_tree_again(c);
}

// The elbow empty parented to the shoulder empty instead of the upper arm: the forearm still
// turns with the shoulder.
TEST(JointTree, AJointEmptyParentedToAJointEmptyHangsFromItsPart) {
  const json nodes = {
      {{"name", "base"}, {"mesh", 0}, {"children", {1}}},
      {{"name", "shoulder"}, {"translation", {0, 0.2, 0}}, {"children", {2, 3}}, {"extras", revolute("z")}},
      {{"name", "upper"}, {"mesh", 0}, {"translation", {0.2, 0, 0}}},
      {{"name", "elbow"}, {"translation", {0.4, 0, 0}}, {"children", {4}}, {"extras", revolute("y")}},
      {{"name", "fore"}, {"mesh", 0}, {"translation", {0.2, 0, 0}}}};
  const Converted c = convert_doc(with_nodes(nodes, {0}));
  EXPECT_EQ(tree(c.robot),
            (std::vector<std::string>{"upper <- base by shoulder (revolute)", "fore <- upper by elbow (revolute)"}));
  expect_same_tree_again(c);
}

// Two jaws under one grip empty move as one part: the first gets the joint, the second is fixed
// to it (one name each, so the URDF export keeps them).
TEST(JointTree, TwoPartsUnderOneJointEmptyMoveTogether) {
  const json nodes = {
      {{"name", "base"}, {"mesh", 0}, {"children", {1}}},
      {{"name", "grip"}, {"translation", {0, 0.3, 0}}, {"children", {2, 3}}, {"extras", revolute("z")}},
      {{"name", "jaw_a"}, {"mesh", 0}, {"translation", {0.1, 0, 0}}},
      {{"name", "jaw_b"}, {"mesh", 0}, {"translation", {-0.1, 0, 0}}}};
  const Converted c = convert_doc(with_nodes(nodes, {0}));
  EXPECT_EQ(tree(c.robot),
            (std::vector<std::string>{"jaw_a <- base by grip (revolute)", "jaw_b <- jaw_a by jaw_a_jaw_b_joint (fixed)"}));
  const auto info = with_code(c.diag, codes::JOINT_MOVES_SEVERAL_LINKS);
  ASSERT_EQ(info.size(), 1u);
  EXPECT_EQ(info[0].severity, Severity::kInfo);
  EXPECT_EQ(info[0].pointer, "/nodes/1");
  EXPECT_NE(info[0].message.find("'jaw_b' hangs from 'jaw_a'"), std::string::npos) << info[0].message;
  expect_same_tree_again(c);

  // Blender's importer sorts children by name: a round trip can put the second jaw first (a
  // hubcap before its tyre). The output marks it fixed on its own node, so the tree holds, and
  // that key is read, not reported as ignored.
  json resorted = c.document;
  resorted.erase("extras");
  bool reversed = false;
  for (json& node : resorted["nodes"]) {
    if (node.value("name", "") != "grip") continue;
    std::reverse(node["children"].begin(), node["children"].end());
    reversed = true;
  }
  ASSERT_TRUE(reversed);
  const Converted again = convert_doc(resorted);
  EXPECT_EQ(tree(again.robot), tree(c.robot));
  EXPECT_TRUE(with_code(again.diag, codes::RDTF_NODE_EXTRAS_IGNORED).empty());
}

// Under a wrist, a palm that fixes itself and a finger with a moving joint of its own: the palm
// is the part, the finger keeps its joint (a rule that only put 'fixed' last carried the finger
// and dropped its degree of freedom).
TEST(JointTree, ALinkWithAMovingJointOfItsOwnIsNotThePart) {
  const json nodes = {
      {{"name", "base"}, {"mesh", 0}, {"children", {1}}},
      {{"name", "wrist"}, {"translation", {0, 0.3, 0}}, {"children", {2, 3}}, {"extras", revolute("z")}},
      {{"name", "palm"}, {"mesh", 0}, {"extras", {{"rdtf_joint", "fixed"}}}},
      {{"name", "finger"}, {"mesh", 0}, {"translation", {0.1, 0, 0}}, {"extras", revolute("x")}}};
  const Converted c = convert_doc(with_nodes(nodes, {0}));
  const std::vector<std::string> lines = tree(c.robot);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "palm <- base by wrist (revolute)");
  EXPECT_EQ(lines[1].rfind("finger <- palm by ", 0), 0u) << lines[1];
  EXPECT_NE(lines[1].find("(revolute)"), std::string::npos) << lines[1];
  for (const Diagnostic& d : with_code(c.diag, codes::RDTF_NODE_EXTRAS_IGNORED)) {
    EXPECT_EQ(d.message.find("'finger'"), std::string::npos) << d.message;  // its joint is read
  }
}

// A mesh of lines (three.js's AxesHelper added to the joint empty before the part) weighs nothing
// and is no part: it took the elbow's joint, the forearm hanging from it by a fixed one.
TEST(JointTree, AMeshOfLinesIsNotThePart) {
  const json nodes = {
      {{"name", "base"}, {"mesh", 0}, {"children", {1}}},
      {{"name", "elbow"}, {"translation", {0, 0.3, 0}}, {"children", {2, 3}}, {"extras", revolute("z")}},
      {{"name", "elbow_axes"}, {"mesh", 1}},
      {{"name", "forearm"}, {"mesh", 0}}};
  json doc = with_nodes(nodes, {0});
  json lines = doc["meshes"][0];
  for (json& primitive : lines["primitives"]) primitive["mode"] = 1;  // LINES
  doc["meshes"] = {doc["meshes"][0], lines};
  const Converted c = convert_doc(doc);
  const std::vector<std::string> tree_lines = tree(c.robot);
  ASSERT_EQ(tree_lines.size(), 2u);
  EXPECT_EQ(tree_lines[0], "forearm <- base by elbow (revolute)");
  EXPECT_EQ(tree_lines[1].rfind("elbow_axes <- forearm by ", 0), 0u) << tree_lines[1];
}

// Two joint empties with properties and no part between them are two degrees of freedom one
// joint cannot have: a warning names the one whose properties are not used.
TEST(JointTree, StackedJointEmptiesWarnThatADegreeOfFreedomIsLost) {
  const json nodes = {
      {{"name", "base"}, {"mesh", 0}, {"children", {1}}},
      {{"name", "yaw"}, {"translation", {0, 0.3, 0}}, {"children", {2}}, {"extras", revolute("z")}},
      {{"name", "pitch"}, {"children", {3}}, {"extras", revolute("x")}},
      {{"name", "head"}, {"mesh", 0}}};
  const Converted c = convert_doc(with_nodes(nodes, {0}));
  EXPECT_EQ(tree(c.robot), (std::vector<std::string>{"head <- base by pitch (revolute)"}));
  const auto chain = with_code(c.diag, codes::JOINT_CHAIN);
  ASSERT_EQ(chain.size(), 1u);
  EXPECT_EQ(chain[0].severity, Severity::kWarning);
  EXPECT_EQ(chain[0].pointer, "/nodes/1");
  EXPECT_NE(chain[0].message.find("joint properties of node 1 'yaw' are not used"), std::string::npos)
      << chain[0].message;
}

// A joint node without properties (the paper's groups a link's child links) moves nothing: each
// link under it keeps its own joint to the link above.
TEST(JointTree, AJointNodeWithoutPropertiesGroupsIndependentLinks) {
  const json nodes = {
      {{"name", "base"}, {"mesh", 0}, {"children", {1}}},
      {{"name", "base_joint"}, {"children", {2, 3}}, {"extras", {{"rdtf_type", "joint"}}}},
      {{"name", "left"}, {"mesh", 0}, {"translation", {0.5, 0, 0}}, {"extras", revolute("z")}},
      {{"name", "right"}, {"mesh", 0}, {"translation", {-0.5, 0, 0}}, {"extras", revolute("z")}}};
  const Converted c = convert_doc(with_nodes(nodes, {0}));
  EXPECT_EQ(tree(c.robot), (std::vector<std::string>{"left <- base by base_joint (revolute)",
                                                      "right <- base by base_joint (revolute)"}));
  EXPECT_TRUE(with_code(c.diag, codes::JOINT_MOVES_SEVERAL_LINKS).empty());
  expect_same_tree_again(c);
  // With a transform of its own (the joints' frame) and links without properties (fixed joints,
  // whose keys rdtf writes in the output): the same again.
  json grouped = nodes;
  grouped[1]["translation"] = {0, 0.3, 0};
  grouped[2].erase("extras");
  grouped[3].erase("extras");
  const Converted g = convert_doc(with_nodes(grouped, {0}));
  EXPECT_EQ(tree(g.robot), (std::vector<std::string>{"left <- base by base_joint (fixed)",
                                                      "right <- base by base_joint (fixed)"}));
  expect_same_tree_again(g);
}

// A marker empty beside the part under a joint empty is a link (it has a mesh-bearing sibling)
// but carries nothing: the part is what the joint moves.
TEST(JointTree, TheJointMovesThePartNotAMarkerBesideIt) {
  const json nodes = {
      {{"name", "base"}, {"mesh", 0}, {"children", {1}}},
      {{"name", "elbow"}, {"translation", {0, 0.3, 0}}, {"children", {2, 3}}, {"extras", revolute("z")}},
      {{"name", "a_marker"}, {"translation", {0, 0.1, 0}}},
      {{"name", "forearm"}, {"mesh", 0}, {"translation", {0, 0.2, 0}}}};
  const Converted c = convert_doc(with_nodes(nodes, {0}));
  EXPECT_EQ(tree(c.robot),
            (std::vector<std::string>{"forearm <- base by elbow (revolute)", "a_marker <- forearm by forearm_a_marker_joint (fixed)"}));
  expect_same_tree_again(c);
}

// A mesh its author typed `mesh`, beside the part under a joint empty, is geometry of that part:
// it moves with it, so its mass is the part's, not the base's (and its density the part's).
TEST(JointTree, AMeshTypedMeshBesideThePartIsThePartsMass) {
  const json nodes = {
      {{"name", "base"}, {"mesh", 0}, {"children", {1}}},
      {{"name", "elbow"}, {"translation", {0, 0.3, 0}}, {"children", {2, 3}}, {"extras", revolute("z")}},
      {{"name", "forearm"}, {"mesh", 0}, {"translation", {0, 0.2, 0}}, {"extras", {{"rdtf_density", 500.0}}}},
      {{"name", "cover"}, {"mesh", 0}, {"translation", {0, 0.4, 0}}, {"extras", {{"rdtf_type", "mesh"}}}}};
  const Converted c = convert_doc(with_nodes(nodes, {0}));
  ASSERT_EQ(tree(c.robot), (std::vector<std::string>{"forearm <- base by elbow (revolute)"}));
  // The same box (float positions) each time: the base one at the default 1000 kg/m^3, the
  // forearm two at its 500 kg/m^3. The forearm's frame is the elbow's (the pivot), its box 0.2 m
  // and the cover's 0.4 m above it: their centre of mass 0.3 m above the pivot.
  const Link& base = c.robot.links[0];
  const Link& forearm = c.robot.links[1];
  ASSERT_EQ(forearm.name, "forearm");
  EXPECT_NEAR(forearm.inertial.mass, base.inertial.mass, 1e-12 * base.inertial.mass);
  EXPECT_NEAR(forearm.inertial.center_of_mass.y() - 0.3, base.inertial.center_of_mass.y(), 1e-12);
  EXPECT_EQ(forearm.meshes.size(), 2u);
  expect_same_tree_again(c);
}

// rdtf's output of a joint empty with properties above a pivot without (its own transform) holds
// the joint in the pivot's entry and the author's keys on the empty: one joint, no warning.
TEST(JointTree, AJointToldTwiceInTheOutputIsNoLostDegreeOfFreedom) {
  const json nodes = {
      {{"name", "base"}, {"mesh", 0}, {"children", {1}}},
      {{"name", "yaw"}, {"translation", {0, 0.3, 0}}, {"children", {2}}, {"extras", revolute("z")}},
      {{"name", "offset"}, {"translation", {0, 0.1, 0}}, {"children", {3}}, {"extras", {{"rdtf_type", "joint"}}}},
      {{"name", "head"}, {"mesh", 0}}};
  const Converted c = convert_doc(with_nodes(nodes, {0}));
  EXPECT_EQ(tree(c.robot), (std::vector<std::string>{"head <- base by offset (revolute)"}));
  const Converted again = convert_doc(c.document);
  EXPECT_EQ(tree(again.robot), tree(c.robot));
  for (const Diagnostic& d : with_code(again.diag, codes::JOINT_CHAIN)) EXPECT_EQ(d.severity, Severity::kInfo) << d.message;
}

}  // namespace
}  // namespace rdtf
