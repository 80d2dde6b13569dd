// Skinned meshes: each bone's parts and their mass (docs/format.md, "Mass properties").
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

std::map<std::string, double> link_masses(const Conversion& conversion) {
  std::map<std::string, double> masses;
  for (const Link& link : conversion.robot.links) masses[link.name] = link.inertial.mass;
  return masses;
}

// Rigid parts that only touch (the same corner coordinates on the shared face, as CAD parts of an
// arm have) stay each with its own bone: welded by position alone they were one part, which went
// whole to `lower` (80 kg) and left the moving `upper` massless (s100xform D2).
TEST(Skinning, TouchingRigidPartsStayWithTheirOwnBones) {
  Diagnostics diag;
  const auto conversion = convert_file(testing::data_dir() / "skin/skin_touch.gltf", {}, diag);
  ASSERT_TRUE(conversion.has_value());
  const double w = static_cast<double>(0.2f);  // the boxes' width as stored (float32)
  const double expected = 1000.0 * w * w * 1.0;
  const auto masses = link_masses(*conversion);
  EXPECT_NEAR(masses.at("lower"), expected, 1e-9 * expected);
  EXPECT_NEAR(masses.at("upper"), expected, 1e-9 * expected);
  for (const Diagnostic& d : diag.all()) {
    EXPECT_NE(d.code, codes::SKIN_PART_SHARED) << d.message;
    EXPECT_NE(d.code, codes::LINK_NO_VOLUME) << d.message;
  }
}

// The skinned mesh node's rdtf_mass is the whole mesh's, shared by its bones as their volumes are
// (it was ignored: 2,196 kg at the default density, without a word; s100xform D3).
TEST(Skinning, TheMeshNodesMassIsSharedByItsBones) {
  Diagnostics diag;
  const auto conversion = convert_file(testing::data_dir() / "skin/skin_rdtfmass.gltf", {}, diag);
  ASSERT_TRUE(conversion.has_value());
  double total = 0, volume = 0;
  for (const Link& link : conversion->robot.links) {
    total += link.inertial.mass;
    volume += link.inertial.volume;
  }
  EXPECT_NEAR(total, 10.0, 1e-12 * 10.0);
  for (const Link& link : conversion->robot.links) {
    const double share = 10.0 * link.inertial.volume / volume;
    EXPECT_NEAR(link.inertial.mass, share, 1e-12 * 10.0) << link.name;
  }
  // The two parts are equal up to their float32 coordinates: about 5 kg each.
  const auto masses = link_masses(*conversion);
  EXPECT_NEAR(masses.at("b0"), 5.0, 1e-6 * 5.0);
  EXPECT_NEAR(masses.at("b1"), 5.0, 1e-6 * 5.0);
}

// A skin of many bones, one box on each (what a hostile file or a scanned rig brings): every bone
// keeps its own box, at the exact mass. Each vertex's weights are kept sparse and each bone holds
// only its own vertices: dense, a skin of 10,000 bones took 13 GB and 72 s (docs/security.md).
TEST(Skinning, ASkinOfManyBonesGivesEachItsOwnPart) {
  constexpr int kBones = 300;  // joints 0..300: the hub and 300 bones around it
  constexpr int kBoxes = kBones + 1;
  std::vector<float> positions;
  std::vector<std::uint32_t> indices;
  std::vector<std::uint16_t> joints;
  std::vector<float> weights;
  // Corner c = x + 2y + 4z of a 0.5 m cube at the origin; 12 outward triangles.
  const std::uint32_t faces[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                                      {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  for (int b = 0; b < kBoxes; ++b) {
    for (int c = 0; c < 8; ++c) {
      positions.insert(positions.end(), {0.5f * (c & 1), 0.5f * ((c >> 1) & 1), 0.5f * ((c >> 2) & 1)});
      joints.insert(joints.end(), {static_cast<std::uint16_t>(b), 0, 0, 0});
      weights.insert(weights.end(), {1.0f, 0.0f, 0.0f, 0.0f});
    }
    for (const auto& f : faces) {
      for (const std::uint32_t corner : f) indices.push_back(static_cast<std::uint32_t>(8 * b) + corner);
    }
  }
  std::string bin;
  const auto append = [&](const auto& values) {
    bin.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(values[0]));
  };
  append(positions);
  append(indices);
  append(joints);
  append(weights);
  const std::size_t p_bytes = positions.size() * 4, i_bytes = indices.size() * 4, j_bytes = joints.size() * 2;
  Json nodes = Json::array({{{"name", "armature"}, {"children", {1, kBoxes + 1}}}, {{"name", "hub"}}});
  Json skin_joints = Json::array({1});
  for (int b = 1; b <= kBones; ++b) {
    nodes[1]["children"].push_back(b + 1);
    skin_joints.push_back(b + 1);
    nodes.push_back({{"name", "b" + std::to_string(b)},
                     {"translation", {2.0 * b, 0, 0}},
                     {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", "z"}}}});
  }
  nodes.push_back({{"name", "rig_mesh"}, {"mesh", 0}, {"skin", 0}});
  const Json document = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", nodes},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"JOINTS_0", 2}, {"WEIGHTS_0", 3}}}, {"indices", 1}}}}}}},
      {"skins", {{{"joints", skin_joints}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8 * kBoxes}, {"type", "VEC3"}, {"min", {0, 0, 0}},
         {"max", {0.5, 0.5, 0.5}}},
        {{"bufferView", 1}, {"componentType", 5125}, {"count", indices.size()}, {"type", "SCALAR"}},
        {{"bufferView", 2}, {"componentType", 5123}, {"count", 8 * kBoxes}, {"type", "VEC4"}},
        {{"bufferView", 3}, {"componentType", 5126}, {"count", 8 * kBoxes}, {"type", "VEC4"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteLength", p_bytes}, {"target", 34962}},
        {{"buffer", 0}, {"byteOffset", p_bytes}, {"byteLength", i_bytes}, {"target", 34963}},
        {{"buffer", 0}, {"byteOffset", p_bytes + i_bytes}, {"byteLength", j_bytes}, {"target", 34962}},
        {{"buffer", 0}, {"byteOffset", p_bytes + i_bytes + j_bytes}, {"byteLength", weights.size() * 4},
         {"target", 34962}}}},
      {"buffers", {{{"byteLength", bin.size()}, {"uri", "rig.bin"}}}}};
  testing::TempDir dir;
  std::ofstream(dir.path() / "rig.bin", std::ios::binary) << bin;
  std::ofstream(dir.path() / "rig.gltf") << document.dump();

  Diagnostics diag;
  const auto conversion = convert_file(dir.path() / "rig.gltf", {}, diag);
  ASSERT_TRUE(conversion.has_value()) << (diag.all().empty() ? std::string() : format(diag.all()[0]));
  const auto masses = link_masses(*conversion);
  ASSERT_EQ(masses.size(), static_cast<std::size_t>(kBoxes) + 1);  // and the armature, which holds none
  EXPECT_EQ(masses.at("armature"), 0.0);
  const double expected = 1000.0 * 0.125;  // kg: the default density times the 0.5 m cube
  EXPECT_NEAR(masses.at("hub"), expected, 1e-9 * expected);
  for (int b = 1; b <= kBones; ++b) {
    EXPECT_NEAR(masses.at("b" + std::to_string(b)), expected, 1e-9 * expected) << b;
  }
  for (const Diagnostic& d : diag.all()) EXPECT_NE(d.code, codes::SKIN_PART_SHARED) << d.message;
}

// A part weighted 0.75 / 0.25 to two bones, the skeleton posed away from its bind pose, weighs as
// it is drawn (glTF 2.0 3.7.3.3: each vertex at sum w_j S_j v): rigid under its heaviest bone it
// was 53% heavier (1,098 kg; s100xform D1). The expected masses are the sweep's numpy integrals of
// the drawn hexahedra (d_skin_blend.py), not rdtf's.
TEST(Skinning, APartSharedByBonesWeighsAsDrawn) {
  Diagnostics diag;
  const auto conversion = convert_file(testing::data_dir() / "skin/skin_blend.gltf", {}, diag);
  ASSERT_TRUE(conversion.has_value());
  const auto masses = link_masses(*conversion);
  EXPECT_NEAR(masses.at("b0"), 1098.1666741656757, 1e-9 * 1098.1666741656757);
  EXPECT_NEAR(masses.at("b1"), 718.0320434258927, 1e-9 * 718.0320434258927);
  bool said = false;
  for (const Diagnostic& d : diag.all()) {
    if (d.code != codes::SKIN_PART_SHARED) continue;
    said = true;
    EXPECT_NE(d.message.find("weighs as drawn"), std::string::npos) << d.message;
    EXPECT_NE(d.message.find("'b1', which carries 75% of its weight"), std::string::npos) << d.message;
  }
  EXPECT_TRUE(said);
}

}  // namespace
}  // namespace rdtf
