// Node completion (Algorithm 4) on inputs beyond the paper's example: what a hostile or merely
// large file makes of the generated names and of the animations that follow a moved mesh.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "rdtf/completion.h"
#include "rdtf/typing.h"

namespace rdtf {
namespace {

// A root link carrying a mesh and `children` child objects with meshes (Blender's layout, as in
// PaperExample.BlenderMeshWithChildrenBecomesTwoLinks): every node is a link.
Json star(const std::string& root_name, std::size_t children) {
  Json document = Json::parse(R"({"asset": {"version": "2.0"}, "scene": 0,
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]})");
  Json root = {{"name", root_name}, {"mesh", 0}, {"children", Json::array()}};
  document["nodes"] = Json::array({root});
  for (std::size_t i = 1; i <= children; ++i) {
    document["nodes"][0]["children"].push_back(i);
    document["nodes"].push_back({{"name", "child" + std::to_string(i)}, {"mesh", 0}});
  }
  document["scenes"] = Json::parse(R"([{"nodes": [0]}])");
  return document;
}

std::vector<NodeType> typed_links(const Json& document, Diagnostics& diag) {
  auto types = type_nodes(document, 0, diag);
  for (std::size_t i = 0; i < types.size(); ++i) EXPECT_EQ(types[i], NodeType::kLink) << "node " << i;
  return types;
}

// Each child link's joint is named after its parent and itself; a name of a megabyte times many
// children made the output quadratic (a 2.6 MB glTF took 9-11 GB). A long name is cut to 48 bytes
// at a character boundary and told apart by a digest of the whole; short names stay as they are.
TEST(Completion, ALongLinkNameIsCutInTheNamesOfItsJoints) {
  const std::string long_name = std::string(47, 'a') + "\xC3\xA9" + std::string(100'000, 'b');  // U+00E9 at 47.
  constexpr std::size_t kChildren = 300;
  Json document = star(long_name, kChildren);
  Diagnostics diag;
  auto types = typed_links(document, diag);
  complete_nodes(document, types, diag);
  std::set<std::string> joint_names;
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (types[i] != NodeType::kJoint) continue;
    const std::string name = document["nodes"][i]["name"].get<std::string>();
    // Cut before the two-byte character, not through it.
    EXPECT_EQ(name.substr(0, 48), std::string(47, 'a') + "~") << name.substr(0, 60);
    EXPECT_LE(name.size(), 64u + 1 + 64 + 6);
    joint_names.insert(name);
  }
  EXPECT_EQ(joint_names.size(), kChildren);  // The children's names keep them apart.
  const std::string first_joint = std::string(47, 'a') + "~" + joint_names.begin()->substr(48, 8) + "_child1_joint";
  EXPECT_TRUE(joint_names.count(first_joint)) << first_joint;

  // Names differing only past the cut keep different joint names.
  Json other = star(std::string(47, 'a') + "\xC3\xA9" + std::string(100'000, 'c'), 1);
  auto other_types = typed_links(other, diag);
  complete_nodes(other, other_types, diag);
  std::string other_joint;
  for (std::size_t i = 0; i < other_types.size(); ++i) {
    if (other_types[i] == NodeType::kJoint) other_joint = other["nodes"][i]["name"].get<std::string>();
  }
  EXPECT_EQ(other_joint.size(), first_joint.size());
  EXPECT_NE(other_joint, first_joint);

  // Up to 64 bytes a name is used whole.
  Json short_names = star(std::string(64, 'r'), 1);
  auto short_types = typed_links(short_names, diag);
  complete_nodes(short_names, short_types, diag);
  bool found = false;
  for (const Json& node : short_names["nodes"]) found |= node.value("name", "") == std::string(64, 'r') + "_child1_joint";
  EXPECT_TRUE(found) << short_names["nodes"].dump();
}

// Every link whose mesh moves to a new node takes its weight animations with it, in one walk over
// the channels (a walk per link cost links x channels: 4.9 MB took 76 s); other targets are left.
TEST(Completion, TheWeightAnimationsOfEveryMovedMeshFollowIt) {
  constexpr std::size_t kChildren = 50;
  Json document = star("base", kChildren);
  Json channels = Json::array();
  const auto pointer_target = [](const std::string& pointer) {
    return Json{{"path", "pointer"}, {"extensions", {{"KHR_animation_pointer", {{"pointer", pointer}}}}}};
  };
  for (std::size_t node = 0; node <= kChildren; ++node) {
    channels.push_back({{"sampler", 0}, {"target", {{"node", node}, {"path", "weights"}}}});
    channels.push_back({{"sampler", 0}, {"target", pointer_target("/nodes/" + std::to_string(node) + "/weights/1")}});
  }
  // Not the weights of a moved mesh: left as they are.
  const std::vector<std::string> kept = {"/nodes/1/translation", "/nodes/01/weights", "/nodes/1/weightsx",
                                         "/nodes/99999999999999999999999/weights", "/nodes//weights", "/meshes/0/weights"};
  for (const std::string& pointer : kept) channels.push_back({{"sampler", 0}, {"target", pointer_target(pointer)}});
  channels.push_back({{"sampler", 0}, {"target", {{"node", 1}, {"path", "rotation"}}}});
  document["animations"] = Json::array({{{"samplers", Json::array()}, {"channels", channels}}});

  Diagnostics diag;
  auto types = typed_links(document, diag);
  complete_nodes(document, types, diag);
  const Json& nodes = document["nodes"];
  std::vector<std::size_t> mesh_node_of(kChildren + 1, 0);
  for (std::size_t i = kChildren + 1; i < nodes.size(); ++i) {
    if (!nodes[i].contains("mesh")) continue;
    const std::string name = nodes[i]["name"].get<std::string>();
    const std::size_t link = name == "base_mesh" ? 0 : std::stoul(name.substr(5));  // "child<N>_mesh"
    mesh_node_of[link] = i;
  }
  const Json& out = document["animations"][0]["channels"];
  for (std::size_t node = 0; node <= kChildren; ++node) {
    ASSERT_NE(mesh_node_of[node], 0u) << node;
    EXPECT_EQ(out[2 * node]["target"]["node"], mesh_node_of[node]);
    EXPECT_EQ(out[2 * node + 1]["target"]["extensions"]["KHR_animation_pointer"]["pointer"],
              "/nodes/" + std::to_string(mesh_node_of[node]) + "/weights/1");
  }
  for (std::size_t k = 0; k < kept.size(); ++k) {
    EXPECT_EQ(out[2 * (kChildren + 1) + k]["target"]["extensions"]["KHR_animation_pointer"]["pointer"], kept[k]);
  }
  EXPECT_EQ(out.back()["target"]["node"], 1);
}

}  // namespace
}  // namespace rdtf
