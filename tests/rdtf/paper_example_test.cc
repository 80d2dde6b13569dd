// The paper's own example: List 1 in, List 5 out (section 4.2).
#include <gtest/gtest.h>

#include "rdtf/completion.h"
#include "rdtf/typing.h"

namespace rdtf {
namespace {

// List 1, with the elided parts filled in minimally.
Json list1() {
  return Json::parse(R"({
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [
      {"children": [1, 2]},
      {"mesh": 0, "translation": [0.0, 0.0, 0.0]},
      {"children": [3]},
      {"mesh": 1, "scale": [1.0, 1.0, 1.0]}
    ],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]},
               {"primitives": [{"attributes": {"POSITION": 0}}]}]
  })");
}

TEST(PaperExample, List1TypesFollowAlgorithms2And3) {
  const Json document = list1();
  Diagnostics diag;
  const auto types = type_nodes(document, 0, diag);
  EXPECT_FALSE(diag.has_errors());
  EXPECT_EQ(types, (std::vector<NodeType>{NodeType::kLink, NodeType::kMesh, NodeType::kLink,
                                          NodeType::kMesh}));
}

TEST(PaperExample, List1CompletesToList5) {
  Json document = list1();
  Diagnostics diag;
  auto types = type_nodes(document, 0, diag);
  complete_nodes(document, types, diag);
  EXPECT_FALSE(diag.has_errors());

  // List 5, except node 2: the paper prints its children unchanged as [3] while node 7 also
  // lists 3, giving node 3 two parents, which glTF forbids. Algorithm 4's last step
  // (node.children <- nChildren) gives [7, 8]; docs/format.md records this.
  const Json list5 = Json::parse(R"([
    {"children": [4, 5, 6]},
    {"mesh": 0, "translation": [0.0, 0.0, 0.0]},
    {"children": [7, 8]},
    {"mesh": 1, "scale": [1.0, 1.0, 1.0]},
    {"name": "node0_visual", "children": [1]},
    {"name": "node0_node2_joint", "children": [2]},
    {"name": "node0_inertial"},
    {"name": "node2_visual", "children": [3]},
    {"name": "node2_inertial"}
  ])");
  EXPECT_EQ(document["nodes"], list5) << document["nodes"].dump(2);
  EXPECT_EQ(types, (std::vector<NodeType>{NodeType::kLink, NodeType::kMesh, NodeType::kLink,
                                          NodeType::kMesh, NodeType::kVisual, NodeType::kJoint,
                                          NodeType::kInertial, NodeType::kVisual,
                                          NodeType::kInertial}));
}

TEST(PaperExample, CompletingTwiceChangesNothing) {
  Json document = list1();
  Diagnostics diag;
  auto types = type_nodes(document, 0, diag);
  complete_nodes(document, types, diag);
  const Json once = document;
  const auto types_once = types;
  complete_nodes(document, types, diag);
  EXPECT_EQ(document, once);
  EXPECT_EQ(types, types_once);
}

TEST(PaperExample, BlenderMeshWithChildrenBecomesTwoLinks) {
  // two_cylinder's shape: the parent object carries a mesh and the child object.
  Json document = Json::parse(R"({
    "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [1]}],
    "nodes": [{"mesh": 0, "name": "arm"}, {"children": [0], "mesh": 0, "name": "base"}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]
  })");
  Diagnostics diag;
  auto types = type_nodes(document, 0, diag);
  EXPECT_EQ(types, (std::vector<NodeType>{NodeType::kLink, NodeType::kLink}));
  complete_nodes(document, types, diag);
  const Json& nodes = document["nodes"];
  // Node order: arm (link 0) is completed first: 2 arm_mesh, 3 arm_visual, 4 arm_inertial; then
  // base: 5 base_mesh, 6 base_visual, 7 base_arm_joint, 8 base_inertial.
  ASSERT_EQ(nodes.size(), 9u);
  EXPECT_FALSE(nodes[0].contains("mesh"));
  EXPECT_FALSE(nodes[1].contains("mesh"));
  EXPECT_EQ(nodes[2]["name"], "arm_mesh");
  EXPECT_EQ(nodes[2]["mesh"], 0);
  EXPECT_EQ(nodes[1]["children"], Json::parse("[6, 7, 8]"));
  EXPECT_EQ(nodes[5]["name"], "base_mesh");
  EXPECT_EQ(nodes[6]["children"], Json::parse("[5]"));
  EXPECT_EQ(nodes[7]["name"], "base_arm_joint");
  EXPECT_EQ(nodes[7]["children"], Json::parse("[0]"));
  EXPECT_TRUE(diag.contains("LINK_MESH_SPLIT"));
}

TEST(PaperExample, AuthoredTypesWin) {
  Json document = list1();
  document["extras"]["RDTF"]["nodes"] = Json::parse(R"([{"node": 2, "type": "visual"}])");
  Diagnostics diag;
  const auto types = type_nodes(document, 0, diag);
  EXPECT_EQ(types[2], NodeType::kVisual);
}

TEST(PaperExample, InvalidAuthoredTypeIsAnErrorWithItsPointer) {
  Json document = list1();
  document["extras"]["RDTF"]["nodes"] = Json::parse(R"([{"node": 2, "type": "wheel"}])");
  Diagnostics diag("model.gltf");
  type_nodes(document, 0, diag);
  ASSERT_TRUE(diag.has_errors());
  EXPECT_EQ(diag.all().front().pointer, "/extras/RDTF/nodes/0/type");
  EXPECT_EQ(diag.all().front().file, "model.gltf");
}

}  // namespace
}  // namespace rdtf
