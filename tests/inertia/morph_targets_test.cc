// Morph targets (glTF 2.0 section 3.7.2.2): a mesh is drawn as its positions plus each target's
// displacements times its weight, the node's `weights` overriding the mesh's. Blender writes a
// shape key's value as such a weight, so the mass, the bounds the gate checks and the geometry
// digest are those of the drawn shape, not of the stored one.
//
// The model: a unit cube [0,1]^3 (8 vertices, 12 triangles wound outward). Target 0 moves its four
// x = 1 vertices by +1 in x (dense accessor); target 1 moves its four z = 1 vertices by +1 in z
// (sparse accessor, no bufferView of its own values). With weights (wx, wz) the drawn shape is the
// box [0, 1 + wx] x [0, 1] x [0, 1 + wz], whose mass properties are exact.

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rdtf/atomic_file.h"
#include "rdtf/convert.h"
#include "rdtf/diff.h"
#include "rdtf/dynamics.h"
#include "rdtf/write.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

using Eigen::Vector3d;
using nlohmann::json;

constexpr double kTol = 1e-9;  // Relative: exact boxes, float positions of small integers.

template <typename T>
void append(std::vector<std::uint8_t>& bytes, const std::vector<T>& values) {
  const std::size_t at = bytes.size();
  bytes.resize(at + values.size() * sizeof(T));
  std::memcpy(bytes.data() + at, values.data(), values.size() * sizeof(T));
}

// The cube's glTF document, its mesh's weights `mesh_weights` (null: none), and `nodes` as given.
json cube_document(const json& mesh_weights, const json& nodes) {
  std::vector<float> positions;
  std::vector<float> target_x;
  std::vector<std::uint8_t> top_vertices;
  for (int v = 0; v < 8; ++v) {
    const float x = static_cast<float>(v & 1), y = static_cast<float>((v >> 1) & 1), z = static_cast<float>((v >> 2) & 1);
    positions.insert(positions.end(), {x, y, z});
    target_x.insert(target_x.end(), {x, 0.0f, 0.0f});
    if (z == 1.0f) top_vertices.push_back(static_cast<std::uint8_t>(v));
  }
  // Outward faces of the cube on the vertices v = x + 2y + 4z.
  const std::vector<std::uint16_t> indices{0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                           2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  std::vector<std::uint8_t> bytes;
  append(bytes, positions);                     // 0..96
  append(bytes, target_x);                      // 96..192
  append(bytes, indices);                       // 192..264
  append(bytes, top_vertices);                  // 264..268
  append(bytes, std::vector<float>(12, 0.0f));  // 268..316, then z = 1 in each: 0 0 1 four times.
  for (int i = 0; i < 4; ++i) {
    const float one = 1.0f;
    std::memcpy(bytes.data() + 268 + 12 * i + 8, &one, sizeof(one));
  }
  json mesh = {{"primitives",
                {{{"attributes", {{"POSITION", 0}}},
                  {"indices", 2},
                  {"targets", {{{"POSITION", 1}}, {{"POSITION", 3}}}}}}}};
  if (!mesh_weights.is_null()) mesh["weights"] = mesh_weights;
  json roots = json::array();
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    bool child = false;
    for (const json& n : nodes) {
      for (const json& c : n.value("children", json::array())) child |= c.get<std::size_t>() == i;
    }
    if (!child) roots.push_back(i);
  }
  return {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", roots}}}},
      {"nodes", nodes},
      {"meshes", {mesh}},
      {"buffers", {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + testing::base64(bytes)}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}},
        {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 96}},
        {{"buffer", 0}, {"byteOffset", 192}, {"byteLength", 72}},
        {{"buffer", 0}, {"byteOffset", 264}, {"byteLength", 4}},
        {{"buffer", 0}, {"byteOffset", 268}, {"byteLength", 48}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1, 1, 1}}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1, 0, 0}}},
        {{"bufferView", 2}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}},
        {{"componentType", 5126},
         {"count", 8},
         {"type", "VEC3"},
         {"min", {0, 0, 0}},
         {"max", {0, 0, 1}},
         {"sparse",
          {{"count", 4},
           {"indices", {{"bufferView", 3}, {"componentType", 5121}}},
           {"values", {{"bufferView", 4}}}}}}}},
  };
}

Conversion converted(const json& document) {
  const std::string text = document.dump();
  Diagnostics diag;
  auto asset = load_gltf_from_memory(std::vector<std::uint8_t>(text.begin(), text.end()), "cube.gltf", {},
                                     LoadLimits{}, diag);
  EXPECT_TRUE(asset.has_value());
  for (const Diagnostic& d : diag.all()) EXPECT_NE(d.severity, Severity::kError) << format(d);
  auto conversion = convert(std::move(*asset), {}, diag);
  EXPECT_TRUE(conversion.has_value());
  for (const Diagnostic& d : diag.all()) EXPECT_NE(d.severity, Severity::kError) << format(d);
  return std::move(*conversion);
}

void expect_near_rel(double actual, double expected, const std::string& what) {
  EXPECT_NEAR(actual, expected, kTol * std::max(1.0, std::abs(expected))) << what;
}

// The box [0,a] x [0,b] x [0,c] at 1000 kg/m^3 (the default density), placed at `origin`.
void expect_box(const MassProperties& m, double a, double b, double c, const Vector3d& origin = Vector3d::Zero()) {
  const double mass = 1000.0 * a * b * c;
  expect_near_rel(m.mass, mass, "mass");
  for (int k = 0; k < 3; ++k) {
    expect_near_rel(m.center_of_mass[k], origin[k] + Vector3d(a, b, c)[k] / 2, "centre " + std::to_string(k));
  }
  const Vector3d diagonal(mass * (b * b + c * c) / 12, mass * (a * a + c * c) / 12, mass * (a * a + b * b) / 12);
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) {
      expect_near_rel(m.inertia(r, k), r == k ? diagonal[r] : 0.0, "inertia " + std::to_string(r) + std::to_string(k));
    }
  }
}

TEST(MorphTargets, TheMeshsWeightsMorphItsMass) {
  const Conversion c = converted(cube_document({0.5, 0.0}, {{{"name", "base"}, {"mesh", 0}}}));
  ASSERT_EQ(c.robot.links.size(), 1u);
  expect_box(c.robot.links[0].inertial, 1.5, 1, 1);
  // The output keeps the targets and weights: still the model the modeller drew.
  EXPECT_EQ(c.asset.document["meshes"][0]["weights"], Json({0.5, 0.0}));
  EXPECT_EQ(c.asset.document["meshes"][0]["primitives"][0]["targets"].size(), 2u);
}

TEST(MorphTargets, ANodesWeightsOverrideItsMeshsAndSparseTargetsCount) {
  const Conversion c =
      converted(cube_document({0.5, 0.0}, {{{"name", "base"}, {"mesh", 0}, {"weights", {0.5, 1.0}}}}));
  ASSERT_EQ(c.robot.links.size(), 1u);
  expect_box(c.robot.links[0].inertial, 1.5, 1, 2);
  // The gate's bounds of the link's geometry are the drawn box's too.
  const LinkBounds bounds = link_geometry_bounds(c.asset, c.robot);
  ASSERT_TRUE(bounds[0].has_value());
  EXPECT_EQ(bounds[0]->min(), Vector3d(0, 0, 0));
  EXPECT_EQ(bounds[0]->max(), Vector3d(1.5, 1, 2));
}

TEST(MorphTargets, ZeroWeightsAreTheStoredMesh) {
  for (const json& weights : {json(nullptr), json({0.0, 0.0})}) {
    const Conversion c = converted(cube_document(weights, {{{"name", "base"}, {"mesh", 0}}}));
    expect_box(c.robot.links[0].inertial, 1, 1, 1);
  }
}

// Two nodes drawing one mesh with weights of their own are two shapes, not the first one twice.
TEST(MorphTargets, NodesDrawingOneMeshWithOtherWeightsAreOtherShapes) {
  const json nodes = {{{"name", "base"}, {"mesh", 0}, {"weights", {1.0, 0.0}}, {"children", {1}}},
                      {{"name", "lid"}, {"mesh", 0}, {"weights", {0.0, 0.25}}, {"translation", {0, 0, 5}}}};
  const Conversion c = converted(cube_document(nullptr, nodes));
  ASSERT_EQ(c.robot.links.size(), 2u);  // The lid hangs from the base by a fixed joint.
  for (const Link& link : c.robot.links) {
    if (link.name == "base") {
      expect_box(link.inertial, 2, 1, 1);
    } else {
      EXPECT_EQ(link.name, "lid");
      expect_box(link.inertial, 1, 1, 1.25);  // In the lid's frame, 5 m above the base's.
    }
  }
}

// A link node's mesh moves to its new `<link>_mesh` child with its weights, and so do the
// animations of those weights: a channel's node, and a KHR_animation_pointer channel's pointer
// (which stayed at the link, a weights animation of a node without a mesh, invalid glTF). The
// output passes the Khronos validator.
TEST(MorphTargets, WeightAnimationsFollowTheMeshToItsNewNode) {
  json doc = cube_document({0.5, 0.0}, {{{"name", "base"}, {"mesh", 0}}});
  std::vector<std::uint8_t> bytes;
  append(bytes, std::vector<float>{0.0f, 1.0f});                   // times
  append(bytes, std::vector<float>{0.5f, 0.0f, 1.0f, 0.0f});       // weights at each time
  doc["buffers"].push_back({{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + testing::base64(bytes)}});
  doc["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", 8}});
  doc["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 8}, {"byteLength", 16}});
  doc["accessors"].push_back({{"bufferView", 5}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}, {"min", {0.0}}, {"max", {1.0}}});
  doc["accessors"].push_back({{"bufferView", 6}, {"componentType", 5126}, {"count", 4}, {"type", "SCALAR"}});
  const json pointer = {{"path", "pointer"}, {"extensions", {{"KHR_animation_pointer", {{"pointer", "/nodes/0/weights"}}}}}};
  doc["extensionsUsed"] = {"KHR_animation_pointer"};
  const auto animation = [](const json& target) {
    json sampler = {{"input", 4}, {"output", 5}};
    json channel = {{"sampler", 0}, {"target", target}};
    return json{{"samplers", json::array({sampler})}, {"channels", json::array({channel})}};
  };
  doc["animations"] = json::array({animation({{"node", 0}, {"path", "weights"}}), animation(pointer)});
  const Conversion c = converted(doc);
  const json& nodes = c.asset.document["nodes"];
  std::size_t mesh_node = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i].value("name", "") == "base_mesh") mesh_node = i;
  }
  ASSERT_NE(mesh_node, 0u) << nodes.dump();
  EXPECT_EQ(nodes[mesh_node]["mesh"], 0);
  const json& animations = c.asset.document["animations"];
  EXPECT_EQ(animations[0]["channels"][0]["target"]["node"], mesh_node);
  EXPECT_EQ(animations[1]["channels"][0]["target"]["extensions"]["KHR_animation_pointer"]["pointer"],
            "/nodes/" + std::to_string(mesh_node) + "/weights");
  testing::TempDir dir;
  Diagnostics diag;
  ASSERT_TRUE(write_rdtf(c.asset, dir / "out.gltf", WriteOptions{}, diag)) << diag.all().size();
  const json report = testing::khronos_report(dir / "out.gltf");
  EXPECT_EQ(report["issues"]["numErrors"], 0) << report.dump(1);
}

// A change of weights is a change of the link's geometry, as an edit of its positions would be.
TEST(MorphTargets, AChangeOfWeightsChangesTheGeometryDigest) {
  const ContentDigest identity = [](std::span<const std::uint8_t> bytes) {
    return std::string(bytes.begin(), bytes.end());
  };
  const Conversion a = converted(cube_document({0.5, 0.0}, {{{"name", "base"}, {"mesh", 0}}}));
  const Conversion b = converted(cube_document({0.25, 0.0}, {{{"name", "base"}, {"mesh", 0}}}));
  const Conversion a_again = converted(cube_document({0.5, 0.0}, {{{"name", "base"}, {"mesh", 0}}}));
  EXPECT_NE(link_geometry_digests(a.asset, a.robot, identity), link_geometry_digests(b.asset, b.robot, identity));
  EXPECT_EQ(link_geometry_digests(a.asset, a.robot, identity),
            link_geometry_digests(a_again.asset, a_again.robot, identity));
}

}  // namespace
}  // namespace rdtf
