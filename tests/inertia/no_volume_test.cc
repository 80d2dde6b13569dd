// Links and joints that add nothing, and what is said of them.
//
// A closed, consistently wound mesh that encloses nothing: every face with a twin wound the other
// way, as a double-sided export writes a mesh. Each edge is used as often one way as the other,
// so the surface check finds it closed, and its volume is 0: MESH_ENCLOSES_NO_VOLUME says so, and
// LINK_NO_VOLUME does not claim there is no closed mesh.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

// A one-node glTF of the unit cube [0,1]^3, its 12 outward triangles and, if `doubled`, each again
// wound the other way.
// `skew` moves the corners off the unit grid (a hexahedron whose sums round).
Json cube(bool doubled, bool skew = false) {
  std::vector<float> positions;
  for (int v = 0; v < 8; ++v) {
    positions.insert(positions.end(), {static_cast<float>(v & 1), static_cast<float>((v >> 1) & 1),
                                       static_cast<float>((v >> 2) & 1)});
  }
  if (skew) {
    for (std::size_t k = 0; k < positions.size(); ++k) positions[k] += 0.1f * static_cast<float>((k * 7) % 5) - 0.13f;
  }
  std::vector<std::uint16_t> indices{0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                     2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  if (doubled) {
    for (std::size_t t = 0; t < 12; ++t) indices.insert(indices.end(), {indices[3 * t], indices[3 * t + 2], indices[3 * t + 1]});
  }
  std::vector<std::uint8_t> bytes(positions.size() * 4 + indices.size() * 2);
  std::memcpy(bytes.data(), positions.data(), positions.size() * 4);
  std::memcpy(bytes.data() + positions.size() * 4, indices.data(), indices.size() * 2);
  const std::size_t index_offset = positions.size() * 4;
  std::vector<float> lo(positions.begin(), positions.begin() + 3), hi = lo;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    lo[k % 3] = std::min(lo[k % 3], positions[k]);
    hi[k % 3] = std::max(hi[k % 3], positions[k]);
  }
  return {{"asset", {{"version", "2.0"}}},
          {"scene", 0},
          {"scenes", {{{"nodes", {0}}}}},
          {"nodes", {{{"name", "shell"}, {"mesh", 0}}}},
          {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
          {"buffers", {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + testing::base64(bytes)}}}},
          {"bufferViews",
           {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", index_offset}},
            {{"buffer", 0}, {"byteOffset", index_offset}, {"byteLength", indices.size() * 2}}}},
          {"accessors",
           {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"}, {"min", lo}, {"max", hi}},
            {{"bufferView", 1}, {"componentType", 5123}, {"count", indices.size()}, {"type", "SCALAR"}}}}};
}

// Converts `document` as a file of its own (convert_file, as the CLI and rdtfd read one).
std::optional<Conversion> convert(const Json& document, Diagnostics& diag) {
  testing::TempDir dir;
  testing::write_file(dir / "model.gltf", document.dump());
  return convert_file(dir / "model.gltf", {}, diag);
}

std::vector<Diagnostic> convert_cube(bool doubled) {
  Diagnostics diag;
  EXPECT_TRUE(convert(cube(doubled), diag).has_value());
  return diag.all();
}

TEST(NoVolume, ADoubleSidedMeshIsNamedAsEnclosingNothing) {
  bool named = false, link = false;
  for (const Diagnostic& d : convert_cube(true)) {
    if (d.code == codes::MESH_ENCLOSES_NO_VOLUME) {
      named = true;
      EXPECT_EQ(d.severity, Severity::kWarning);
      EXPECT_EQ(d.pointer, "/nodes/0");
      EXPECT_EQ(d.message.rfind("mesh of 'shell' is closed but encloses no volume (0 m^3 across 1.73 m): every face has a "
                                "twin wound the other way (a mesh exported double-sided)",
                                0),
                0u)
          << d.message;
    }
    if (d.code == codes::LINK_NO_VOLUME) {
      link = true;
      EXPECT_NE(d.message.find("its closed meshes enclose none"), std::string::npos) << d.message;
    }
    EXPECT_NE(d.code, codes::MESH_OPEN) << d.message;  // every edge is used twice each way: closed
  }
  EXPECT_TRUE(named);
  EXPECT_TRUE(link);
}

// Off the grid the twins' sums round (-8e-17 m^3): that went out as the link's mass (8e-14 kg), a
// tensor with a negative moment in every output, and a false MESH_INSIDE_OUT from its sign
// (s100xform D4). A mesh that encloses nothing weighs exactly nothing.
TEST(NoVolume, ADoubleSidedMeshWeighsExactlyNothingWhereItsSumsRound) {
  Diagnostics diag;
  const auto conversion = convert(cube(true, true), diag);
  ASSERT_TRUE(conversion.has_value());
  ASSERT_EQ(conversion->robot.links.size(), 1u);
  const MassProperties& inertial = conversion->robot.links[0].inertial;
  EXPECT_EQ(inertial.mass, 0.0);
  EXPECT_EQ(inertial.volume, 0.0);
  EXPECT_EQ(inertial.inertia, Eigen::Matrix3d::Zero());
  bool named = false, link = false;
  for (const Diagnostic& d : diag.all()) {
    EXPECT_NE(d.code, codes::MESH_INSIDE_OUT) << d.message;
    named = named || d.code == codes::MESH_ENCLOSES_NO_VOLUME;
    link = link || d.code == codes::LINK_NO_VOLUME;
  }
  EXPECT_TRUE(named);
  EXPECT_TRUE(link);
  // The single-sided hexahedron has volume: the skew keeps it a solid.
  Diagnostics single_diag;
  const auto single = convert(cube(false, true), single_diag);
  ASSERT_TRUE(single.has_value());
  EXPECT_GT(single->robot.links[0].inertial.volume, 0.5);
}

// An rdtf_mass on a link that encloses nothing cannot be given: it was dropped, and the message
// said only "its mass is zero".
TEST(NoVolume, AnRdtfMassWithNothingToFillIsNamed) {
  Json document = cube(true);
  document["nodes"][0]["extras"] = {{"rdtf_mass", 0.5}};
  Diagnostics diag;
  ASSERT_TRUE(convert(document, diag).has_value());
  bool named = false;
  for (const Diagnostic& d : diag.all()) {
    if (d.code != codes::LINK_NO_VOLUME) continue;
    named = true;
    EXPECT_NE(d.message.find("its mass is zero, and its rdtf_mass 0.5 is not applied"), std::string::npos) << d.message;
  }
  EXPECT_TRUE(named);
}

TEST(NoVolume, TheSingleSidedCubeIsSilent) {
  for (const Diagnostic& d : convert_cube(false)) {
    EXPECT_NE(d.code, codes::MESH_ENCLOSES_NO_VOLUME) << d.message;
    EXPECT_NE(d.code, codes::LINK_NO_VOLUME) << d.message;
  }
}

// The cube as the base, with `children` (nodes without meshes) under it.
std::vector<Diagnostic> convert_cube_with(const Json& children) {
  Json document = cube(false);
  for (const Json& child : children) {
    document["nodes"][0]["children"].push_back(document["nodes"].size());
    document["nodes"].push_back(child);
  }
  Diagnostics diag;
  EXPECT_TRUE(convert(document, diag).has_value());
  return diag.all();
}

std::vector<std::string> no_volume_messages(const std::vector<Diagnostic>& diagnostics) {
  std::vector<std::string> messages;
  for (const Diagnostic& d : diagnostics) {
    if (d.code == codes::LINK_NO_VOLUME) messages.push_back(d.pointer + ": " + d.message);
  }
  return messages;
}

// A scale of 0 flattens the mesh (MESH_SCALED_TO_NOTHING); the link's word then says so, not that
// faces are doubled back to back (s100xform D6).
TEST(NoVolume, AFlattenedMeshIsNamedAsSuch) {
  Json document = cube(false);
  document["nodes"][0]["scale"] = {1, 0, 1};
  Diagnostics diag;
  ASSERT_TRUE(convert(document, diag).has_value());
  const auto messages = no_volume_messages(diag.all());
  ASSERT_EQ(messages.size(), 1u);
  EXPECT_NE(messages[0].find("its meshes are scaled to nothing"), std::string::npos) << messages[0];
}

// A frame welded to a body that has mass weighs nothing by design: the armature's own object of a
// skinned robot built as docs/blender.md says (it holds the root bone by a fixed joint), or a
// sensor frame. LINK_NO_VOLUME said "its mass is zero" of every such link.
TEST(NoVolume, AFrameWeldedToABodyWithMassIsSilent) {
  Diagnostics diag;
  ASSERT_TRUE(convert_file(testing::data_dir() / "blender" / "modelled_bones.gltf", {}, diag).has_value());
  EXPECT_EQ(no_volume_messages(diag.all()), std::vector<std::string>{});
  EXPECT_EQ(no_volume_messages(convert_cube_with(
                {{{"name", "camera"}, {"translation", {0.5, 1, 0.5}}, {"extras", {{"rdtf_joint", "fixed"}}}}})),
            std::vector<std::string>{});
}

// An empty fixed where the modeller put it, with nothing below (a camera's frame, a tool's centre
// point), is a massless link on a fixed joint, placed by the empty, as URDF keeps sensor frames.
// Before, it was typed a joint node that moved nothing, and left out without a word.
TEST(NoVolume, AFixedLeafEmptyIsAFrameLink) {
  Json document = cube(false);
  document["nodes"][0]["children"] = {1};
  document["nodes"].push_back({{"name", "camera"},
                               {"translation", {0.5, 1, 0.25}},
                               {"rotation", {0, 0.70710678118654752, 0, 0.70710678118654752}},
                               {"extras", {{"rdtf_joint", "fixed"}}}});
  Diagnostics diag;
  const auto conversion = convert(document, diag);
  ASSERT_TRUE(conversion.has_value());
  for (const Diagnostic& d : diag.all()) EXPECT_NE(d.severity, Severity::kWarning) << d.code << ": " << d.message;
  const Robot& robot = conversion->robot;
  ASSERT_EQ(robot.links.size(), 2u);
  EXPECT_EQ(robot.links[1].name, "camera");
  EXPECT_EQ(robot.links[1].inertial.mass, 0.0);
  ASSERT_EQ(robot.joints.size(), 1u);
  EXPECT_EQ(robot.joints[0].kind, JointKind::kFixed);
  EXPECT_EQ(robot.joints[0].parent_link, 0);
  EXPECT_EQ(robot.joints[0].child_link, 1);
  // The frame is the empty's: 0.5, 1, 0.25 from the cube's corner, turned 90 degrees about y.
  const Eigen::Isometry3d X_PJ = robot.joints[0].X_PJ;
  EXPECT_LT((X_PJ.translation() - Eigen::Vector3d(0.5, 1, 0.25)).norm(), 1e-12);
  EXPECT_LT((X_PJ.linear() * Eigen::Vector3d::UnitX() - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
}

// A frame that hangs from empties rather than from a part keeps its own place: under a plain
// mount empty (typed a joint node), and under a mount empty that is fixed itself and holds two
// cameras. Its link frame was the empty's above it, and the 3 cm to each camera were lost in the
// URDF and on the bus (a helper's sweep of Blender exports).
TEST(NoVolume, AFrameUnderMountEmptiesKeepsItsOwnPlace) {
  for (const bool fixed_mount : {false, true}) {
    Json document = cube(false);
    document["nodes"][0]["children"] = {1};
    Json mount = {{"name", "mount"}, {"translation", {0.5, 1.1, 0.4}}, {"children", {2}}};
    if (fixed_mount) {
      mount["extras"] = {{"rdtf_joint", "fixed"}};
      mount["children"] = {2, 3};
    }
    document["nodes"].push_back(mount);
    document["nodes"].push_back({{"name", "cam_left"}, {"translation", {0.03, 0, 0}}, {"extras", {{"rdtf_joint", "fixed"}}}});
    if (fixed_mount) {
      document["nodes"].push_back({{"name", "cam_right"}, {"translation", {-0.03, 0, 0}}, {"extras", {{"rdtf_joint", "fixed"}}}});
    }
    Diagnostics diag;
    const auto conversion = convert(document, diag);
    ASSERT_TRUE(conversion.has_value());
    std::map<std::string, Eigen::Vector3d> expected{{"cam_left", {0.53, 1.1, 0.4}}};
    if (fixed_mount) expected["cam_right"] = {0.47, 1.1, 0.4};
    for (const Link& link : conversion->robot.links) {
      if (!expected.count(link.name)) continue;
      EXPECT_LT((link.X_SL.translation() - expected[link.name]).norm(), 1e-12)
          << link.name << (fixed_mount ? " under a fixed mount" : " under a plain mount") << ": "
          << link.X_SL.translation().transpose();
      expected.erase(link.name);
    }
    EXPECT_TRUE(expected.empty()) << expected.size() << " camera links missing";
  }
}

// A frame turned inside a parent's non-uniform scale is skewed like a mesh would be: NODE_SHEARED
// says so (it was said only where a mesh was at or below the node).
TEST(NoVolume, ASkewedFrameIsNamed) {
  Json document = cube(false);
  document["nodes"][0]["children"] = {1};
  document["nodes"][0]["scale"] = {1, 2, 1};
  document["nodes"].push_back({{"name", "tip"},
                               {"translation", {0.5, 1, 0.5}},
                               {"rotation", {0, 0, 0.17364817766693033, 0.98480775301220802}},
                               {"extras", {{"rdtf_joint", "fixed"}}}});
  Diagnostics diag;
  ASSERT_TRUE(convert(document, diag).has_value());
  std::vector<std::string> sheared;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == codes::NODE_SHEARED) sheared.push_back(d.pointer);
  }
  EXPECT_EQ(sheared, std::vector<std::string>{"/nodes/1"});
}

// A link that moves with nothing of mass welded to it (a hand whose fingers are empties) is still
// named: its mass is zero, and the dynamics check refuses it.
TEST(NoVolume, AMovingLinkWithoutMassIsStillNamed) {
  const Json wrist = {{"name", "wrist"},
                      {"translation", {0.5, 1, 0.5}},
                      {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", "z"}}},
                      {"children", {2}}};
  Json document = cube(false);
  document["nodes"][0]["children"] = {1};
  document["nodes"].push_back(wrist);
  document["nodes"].push_back({{"name", "hand"}, {"children", {3, 4}}});
  document["nodes"].push_back({{"name", "finger_a"}, {"translation", {0, 0.1, 0}}});
  document["nodes"].push_back({{"name", "finger_b"}, {"translation", {0, 0.2, 0}}});
  Diagnostics diag;
  ASSERT_TRUE(convert(document, diag).has_value());
  EXPECT_EQ(no_volume_messages(diag.all()),
            std::vector<std::string>{"/nodes/2: link 'hand' has no volume (no mesh): its mass is zero"});
  // Typed 'link' in its node extras (rdtf's output of a meshless link, or an author's typing):
  // nothing says it had meshes, and nothing more is said.
  document["nodes"][2]["extras"] = {{"rdtf_type", "link"}};
  Diagnostics typed;
  ASSERT_TRUE(convert(document, typed).has_value());
  EXPECT_EQ(no_volume_messages(typed.all()),
            std::vector<std::string>{"/nodes/2: link 'hand' has no volume (no mesh): its mass is zero"});
  // A link with a density of its own but no mesh had one: Blender's re-export of rdtf's output
  // drops the children of a bone-parented part, its mesh nodes among them.
  document["nodes"][2] = {{"name", "hand"}, {"extras", {{"rdtf_type", "link"}, {"rdtf_density", 1500}}}};
  Diagnostics lost;
  ASSERT_TRUE(convert(document, lost).has_value());
  EXPECT_EQ(no_volume_messages(lost.all()),
            std::vector<std::string>{"/nodes/2: link 'hand' has no volume (no mesh, though its rdtf_density says it "
                                     "had one: if this is rdtf's output exported again by Blender, Blender 3.4 drops "
                                     "the children of an object parented to a bone, its mesh among them; edit the "
                                     "original .blend, not rdtf's output): its mass is zero"});
}

// An empty root with the robot below it on a moving joint: the world's frame, as URDF's usual
// empty `world` link is (pybullet's pendulum5, imported), which the gate holds fixed. Before, it
// was warned of as a link without volume on every import, validate and export.
TEST(NoVolume, AnEmptyRootIsTheWorldsFrameAndSilent) {
  Json document = cube(false);
  const Json shell = document["nodes"][0];
  document["nodes"] = Json::array({{{"name", "world"}, {"extras", {{"rdtf_type", "link"}}}, {"children", {1}}},
                                   {{"name", "hinge"},
                                    {"translation", {0, 0, 2}},
                                    {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", "x"}}},
                                    {"children", {2}}},
                                   shell});
  Diagnostics diag;
  const auto converted = convert(document, diag);
  ASSERT_TRUE(converted.has_value());
  ASSERT_EQ(converted->robot.links.size(), 2u);
  EXPECT_EQ(converted->robot.links[0].name, "world");
  EXPECT_EQ(no_volume_messages(diag.all()), std::vector<std::string>{});
}

// A joint empty whose part was parented elsewhere makes no joint; before, it vanished without a
// word (the robot simply lacked the joint the modeller had set up).
TEST(NoVolume, AJointEmptyThatMovesNothingIsNamed) {
  const auto diagnostics = convert_cube_with(
      {{{"name", "wrist"}, {"translation", {0.5, 1, 0.5}}, {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", "z"}}}},
       {{"name", "plain"}, {"translation", {0.5, 1, 0.5}}}});
  std::vector<std::string> found;
  for (const Diagnostic& d : diagnostics) {
    if (d.code == codes::JOINT_MOVES_NOTHING) {
      EXPECT_EQ(d.severity, Severity::kWarning);
      found.push_back(d.pointer + ": " + d.message);
    }
  }
  EXPECT_EQ(found, std::vector<std::string>{
                       "/nodes/1: joint node 1 'wrist' has joint properties but no part hangs below it, so it makes "
                       "no joint: parent the part it turns to it (in Blender, select the part, then the empty, "
                       "Ctrl+P > Object)"});
}

// An empty standing for a payload, given a mass: it has no shape to give the mass a volume and an
// inertia. The mass was dropped without a word, whether the empty was a plain node (typed visual)
// or a frame fixed where it sits.
TEST(NoVolume, AMassOnAnEmptyIsNamed) {
  std::vector<std::string> ignored;
  const auto plain = convert_cube_with({{{"name", "payload"}, {"translation", {0.5, 1, 0.5}}, {"extras", {{"rdtf_mass", 2.0}}}}});
  for (const Diagnostic& d : plain) {
    if (d.code == codes::RDTF_NODE_EXTRAS_IGNORED) ignored.push_back(d.pointer + ": " + d.message);
  }
  EXPECT_EQ(ignored, std::vector<std::string>{
                         "/nodes/1/extras/rdtf_mass: node 1 'payload': rdtf_mass 2.0 is not read on a node without a "
                         "mesh (it has no shape to give the mass a volume and an inertia): count it in the rdtf_mass of "
                         "the part it rides on ('shell'), or give the node a mesh of the payload's shape"});
  EXPECT_EQ(no_volume_messages(convert_cube_with({{{"name", "payload"},
                                                   {"translation", {0.5, 1, 0.5}},
                                                   {"extras", {{"rdtf_joint", "fixed"}, {"rdtf_mass", 2.0}}}}})),
            std::vector<std::string>{
                "/nodes/1: link 'payload' has no volume (no mesh): its mass is zero, and its rdtf_mass 2.0 is not "
                "applied: a mass fills the volume its meshes enclose, and there is none (give the link a closed mesh, "
                "or give the link an inertial in extras.RDTF)"});
}

}  // namespace
}  // namespace rdtf
