// Checks on the modelled robot (core/robot/checks.cc, docs/format.md "Checks on the modelled
// robot"): a model that converts but was typed in other units, or with a misspelt custom
// property, or with an object the modeller did not mean to export, gets a warning that names the
// node and what to do. The same model typed right gets none. The base model is
// tests/data/khr/arm_extras.gltf: base (5 kg by rdtf_mass, a 0.016 m^3 box), arm (revolute,
// [-1, 1.5] rad, authored inertial), slider (prismatic, [0, 0.2] m, a 0.016 m^3 box at 1000 kg/m^3).
#include <gtest/gtest.h>

#include <map>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

using nlohmann::json;

json arm() { return json::parse(testing::read_file(testing::data_dir() / "khr" / "arm_extras.gltf")); }

std::vector<Diagnostic> convert_and_find(const json& doc, const std::string& code) {
  testing::TempDir dir;
  testing::write_file(dir / "arm.gltf", doc.dump());
  Diagnostics diag;
  const auto conversion = convert_file(dir / "arm.gltf", {}, diag);
  EXPECT_TRUE(conversion.has_value());
  EXPECT_FALSE(diag.has_errors());
  std::vector<Diagnostic> found;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == code) found.push_back(d);
  }
  return found;
}

void expect_one(const std::vector<Diagnostic>& found, const std::string& pointer,
                const std::vector<std::string>& phrases) {
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].severity, Severity::kWarning);
  EXPECT_EQ(found[0].pointer, pointer);
  for (const std::string& phrase : phrases) {
    EXPECT_NE(found[0].message.find(phrase), std::string::npos) << "no \"" << phrase << "\" in: " << found[0].message;
  }
}

TEST(Plausibility, TheArmAsTypedGetsNoneOfTheWarnings) {
  for (const char* code : {codes::JOINT_LIMITS_IMPLAUSIBLE, codes::DENSITY_IMPLAUSIBLE, codes::UNITS_IMPLAUSIBLE,
                           codes::RDTF_UNKNOWN_KEY, codes::MULTIPLE_ROOT_LINKS}) {
    EXPECT_TRUE(convert_and_find(arm(), code).empty()) << code;
  }
}

TEST(Plausibility, RevoluteLimitsTypedInDegreesAreNamedWithTheirRadians) {
  json doc = arm();
  doc["nodes"][1]["extras"]["rdtf_lower"] = -90;
  doc["nodes"][1]["extras"]["rdtf_upper"] = 90;
  expect_one(convert_and_find(doc, codes::JOINT_LIMITS_IMPLAUSIBLE), "/nodes/1/extras",
             {"node 1 'arm'", "[-90, 90] rad reach beyond a full turn", "[-1.57, 1.57] rad"});
  // A full turn each way, typed as modellers do, is no mistake.
  for (const double turn : {6.283185307179586, 6.2832}) {
    doc["nodes"][1]["extras"]["rdtf_lower"] = -turn;
    doc["nodes"][1]["extras"]["rdtf_upper"] = turn;
    EXPECT_TRUE(convert_and_find(doc, codes::JOINT_LIMITS_IMPLAUSIBLE).empty()) << turn;
  }
}

TEST(Plausibility, LimitsFromExtrasRdtfAreNotJudged) {
  // rdtf's output of a URDF with a multi-turn joint: the limits are in extras.RDTF (and, agreeing,
  // in node extras that the entry takes precedence over).
  testing::TempDir dir;
  Diagnostics diag;
  json doc = arm();
  doc["nodes"][1]["extras"]["rdtf_lower"] = -20.0;
  doc["nodes"][1]["extras"]["rdtf_upper"] = 20.0;
  testing::write_file(dir / "in.gltf", doc.dump());
  const auto first = convert_file(dir / "in.gltf", {}, diag);
  ASSERT_TRUE(first);
  EXPECT_TRUE(convert_and_find(first->asset.document, codes::JOINT_LIMITS_IMPLAUSIBLE).empty());
  // Nor after a trip through Blender, which keeps only the node extras rdtf wrote beside them.
  json stripped = first->asset.document;
  stripped.erase("extras");
  EXPECT_TRUE(convert_and_find(stripped, codes::JOINT_LIMITS_IMPLAUSIBLE).empty());
}

TEST(Plausibility, SlideTypedInMillimetresIsNamedWithItsMetres) {
  json doc = arm();
  doc["nodes"][2]["extras"]["rdtf_upper"] = 200;
  expect_one(convert_and_find(doc, codes::JOINT_LIMITS_IMPLAUSIBLE), "/nodes/2/extras",
             {"node 2 'slider'", "limits [0, 200] m reach", "[0, 0.2] m"});
}

TEST(Plausibility, DensityInGramsPerCubicCentimetreAndMassInGrams) {
  json doc = arm();
  doc["nodes"][2]["extras"]["rdtf_density"] = 2.7;
  expect_one(convert_and_find(doc, codes::DENSITY_IMPLAUSIBLE), "/nodes/2",
             {"node 2 'slider'", "2.7 kg/m^3, lighter than any solid", "2700 kg/m^3"});
  doc = arm();
  doc["nodes"][0]["extras"]["rdtf_mass"] = 5000.0;  // 5 kg typed in grams, over 0.016 m^3
  expect_one(convert_and_find(doc, codes::DENSITY_IMPLAUSIBLE), "/nodes/0",
             {"node 0 'base'", "3.12e+05 kg/m^3, denser than any material"});
  // Steel is steel.
  doc = arm();
  doc["nodes"][2]["extras"]["rdtf_density"] = 7850.0;
  EXPECT_TRUE(convert_and_find(doc, codes::DENSITY_IMPLAUSIBLE).empty());
}

TEST(Plausibility, MisspeltCustomPropertiesAreNamedWithTheNearestKey) {
  json doc = arm();
  json& extras = doc["nodes"][1]["extras"];
  extras["rdft_damping"] = 0.2;  // two letters swapped
  extras["RDTF_MASS"] = 1.0;     // the wrong case
  extras["rdtf_colour"] = "red";  // no rdtf key at all
  extras["note"] = "made by hand";  // somebody else's property: no word
  const auto found = convert_and_find(doc, codes::RDTF_UNKNOWN_KEY);
  ASSERT_EQ(found.size(), 3u);
  std::map<std::string, std::string> by_pointer;
  for (const Diagnostic& d : found) by_pointer[d.pointer] = d.message;
  EXPECT_NE(by_pointer["/nodes/1/extras/rdft_damping"].find("did you mean 'rdtf_damping'?"), std::string::npos);
  EXPECT_NE(by_pointer["/nodes/1/extras/RDTF_MASS"].find("did you mean 'rdtf_mass'?"), std::string::npos);
  EXPECT_NE(by_pointer["/nodes/1/extras/rdtf_colour"].find("node 1 'arm': custom property 'rdtf_colour' is no property"),
            std::string::npos)
      << by_pointer["/nodes/1/extras/rdtf_colour"];
}

TEST(Plausibility, ASecondRootLinkIsNamedWithTheUsualBlenderCauses) {
  json doc = arm();
  doc["nodes"].push_back({{"name", "cutter"}, {"mesh", 0}, {"translation", {2.0, 0.0, 0.0}}});
  doc["scenes"][0]["nodes"].push_back(doc["nodes"].size() - 1);
  expect_one(convert_and_find(doc, codes::MULTIPLE_ROOT_LINKS), "/nodes/4",
             {"2 root links ('base', 'cutter')", "Blender exports hidden objects"});
}

TEST(Plausibility, TooLargeAndHeavyForAMachineAndScaledToAMillimetre) {
  // 30 times too large: 18 m and 600 t (the base keeps its 5 kg), within the bounds of 100 m and
  // 1000 t but beyond a 10 m, 100 t machine.
  json doc = arm();
  doc["nodes"][0]["scale"] = {30.0, 30.0, 30.0};
  expect_one(convert_and_find(doc, codes::UNITS_IMPLAUSIBLE), "/nodes/2",
             {"the robot spans ", " m (link frames and centres of mass)", "implausible in metres", "0.001"});
  // A thousandth: the arm's authored inertial (its centre of mass 0.2 m out) goes, so that its
  // mass comes from its scaled mesh as the others' do.
  doc["nodes"][0]["scale"] = {0.001, 0.001, 0.001};
  doc["nodes"].erase(3);
  doc["nodes"][1]["children"] = json::array({2});
  expect_one(convert_and_find(doc, codes::UNITS_IMPLAUSIBLE), "/nodes/0", {"implausibly small in metres"});
}

// Heavy beyond any robot at a size plausible in metres: the masses are off, not the lengths (a URDF
// whose masses were typed in grams). Scaling the model, as the millimetre advice says, would not help.
TEST(Plausibility, HeavyAtAPlausibleSizeBlamesTheMassesNotTheLengths) {
  json doc = arm();
  doc["nodes"][0]["extras"]["rdtf_mass"] = 5e6;
  const auto found = convert_and_find(doc, codes::UNITS_IMPLAUSIBLE);
  expect_one(found, "/nodes/0", {"its size is plausible in metres but its mass is not", "grams"});
  EXPECT_EQ(found.front().message.find("millimetres"), std::string::npos) << found.front().message;
}

// A robot of one link has no span between frames: its size is its part's volume, and the message
// says so rather than quoting the cube's edge as the robot's breadth.
TEST(Plausibility, OneLinkTooLargeIsSizedByItsPartsVolume) {
  json doc = arm();
  doc["nodes"][0].erase("children");
  doc["nodes"][0]["scale"] = {500.0, 500.0, 500.0};  // 0.016 m^3 -> 2.0e6 m^3, a cube 126 m on a side
  expect_one(convert_and_find(doc, codes::UNITS_IMPLAUSIBLE), "/nodes/0",
             {"the robot has a part of 2e+06 m^3 (a cube 126 m on a side)", "implausible in metres"});
}

// Blender exports the Object Data tab's custom properties on the mesh, where rdtf reads nothing.
TEST(Plausibility, RdtfKeysOnMeshDataAreNamed) {
  json doc = arm();
  doc["meshes"][0]["name"] = "Cube.001";
  doc["meshes"][0]["extras"] = {{"rdtf_density", 2700}, {"colour", "red"}};
  expect_one(convert_and_find(doc, codes::RDTF_UNKNOWN_KEY), "/meshes/0/extras/rdtf_density",
             {"mesh 0 'Cube.001'", "on the mesh data", "set it on the object"});
}

// Exported from Blender with only the meshes selected: the joint empties are gone, every joint is
// fixed, and nothing else would say so.
TEST(Plausibility, PartsParentedToPartsFromBlenderWithoutPropertiesAreNamed) {
  json doc = arm();
  for (json& node : doc["nodes"]) node.erase("extras");
  doc["asset"]["generator"] = "Khronos glTF Blender I/O v3.4.50";
  expect_one(convert_and_find(doc, codes::NO_RDTF_PROPERTIES), "/nodes",
             {"every joint is fixed", "parented to one another", "Selected Objects"});
  // Densities and masses set on the parts (as docs/blender.md's arm has them) say nothing of joints:
  // the warning stays. It went silent at any rdtf_* key (s80blend D1).
  doc["nodes"][0]["extras"] = {{"rdtf_density", 2700}};
  doc["nodes"][2]["extras"] = {{"rdtf_mass", 1.5}};
  expect_one(convert_and_find(doc, codes::NO_RDTF_PROPERTIES), "/nodes",
             {"no node has a joint property", "parented to one another", "Selected Objects"});
  // From another tool, a model of parts alone is not judged (a fixed assembly is a model too).
  doc["asset"]["generator"] = "some CAD exporter";
  EXPECT_TRUE(convert_and_find(doc, codes::NO_RDTF_PROPERTIES).empty());
}

// gltfpack replaces asset.generator: behind it rdtf cannot tell that Blender wrote the axes the
// modeller typed, so it reads them in glTF's axes, and says so at each typed axis. gltfpack's
// output of a Blender export turned every joint axis by 90 degrees without a word.
TEST(Plausibility, AxesBehindAPackersGeneratorAreNamedAsAssumed) {
  json doc = arm();
  doc["asset"]["generator"] = "gltfpack 1.3";
  const auto found = convert_and_find(doc, codes::RDTF_AXES_ASSUMED);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].pointer, "/nodes/1/extras/rdtf_axis");
  EXPECT_EQ(found[1].pointer, "/nodes/2/extras/rdtf_axis");
  for (const char* phrase : {"node 1 'arm': rdtf_axis [0,0,1] is read in glTF's axes", "'gltfpack 1.3'",
                             "\"rdtf_axes\": \"blender\"", "gltfpack -kn -ke"}) {
    EXPECT_NE(found[0].message.find(phrase), std::string::npos) << phrase << " not in: " << found[0].message;
  }
  // Saying which axes it typed answers it; so does any generator that is no packer.
  doc["nodes"][1]["extras"]["rdtf_axes"] = "blender";
  doc["nodes"][2]["extras"]["rdtf_axes"] = "gltf";
  EXPECT_TRUE(convert_and_find(doc, codes::RDTF_AXES_ASSUMED).empty());
  doc = arm();
  doc["asset"]["generator"] = "some CAD exporter";
  EXPECT_TRUE(convert_and_find(doc, codes::RDTF_AXES_ASSUMED).empty());
  // Editors that load a file and save it again keep node extras and replace the generator too:
  // arm3 re-saved by three.js turned both its joints by 90 degrees without a word (s90tools D2).
  for (const char* editor : {"THREE.GLTFExporter r187", "Open Asset Import Library (assimp v5.2.0)",
                             "Babylon.js glTF2 Serializer v6"}) {
    doc["asset"]["generator"] = editor;
    EXPECT_EQ(convert_and_find(doc, codes::RDTF_AXES_ASSUMED).size(), 2u) << editor;
  }
  // Without any property (gltfpack without -ke), the warning says what the packer drops.
  for (json& node : doc["nodes"]) node.erase("extras");
  doc["asset"]["generator"] = "gltfpack 1.3";
  expect_one(convert_and_find(doc, codes::NO_RDTF_PROPERTIES), "/nodes",
             {"packed by 'gltfpack 1.3'", "drops node extras", "gltfpack -kn -ke", "Include > Custom Properties"});
  // glTF-Transform keeps node extras: its advice is its own options, not gltfpack's (s90tools D1).
  doc["asset"]["generator"] = "glTF-Transform v4.5.1";
  const auto transformed = convert_and_find(doc, codes::NO_RDTF_PROPERTIES);
  expect_one(transformed, "/nodes", {"keeps node extras", "--flatten false --join false"});
  EXPECT_EQ(transformed[0].message.find("gltfpack"), std::string::npos) << transformed[0].message;
  // With a density still on a part, the packer kept the extras: the robot has no joints as its
  // source had none, and is not warned about where the source was not.
  doc["nodes"][0]["extras"] = {{"rdtf_density", 2700}};
  EXPECT_TRUE(convert_and_find(doc, codes::NO_RDTF_PROPERTIES).empty());
  doc["nodes"][0].erase("extras");
  // Nor is it Blender's export setting when Assimp or Draco's decoder wrote the file: they dropped
  // the extras themselves (the advice was "In Blender, tick Include > Custom Properties").
  doc["asset"]["generator"] = "Open Asset Import Library (assimp v5.2.0)";
  expect_one(convert_and_find(doc, codes::NO_RDTF_PROPERTIES), "/nodes",
             {"'Open Asset Import Library (assimp v5.2.0)', which drops every node extra"});
  doc["asset"]["generator"] = "draco_decoder";
  expect_one(convert_and_find(doc, codes::NO_RDTF_PROPERTIES), "/nodes", {"'draco_decoder', which may have dropped"});
}

// Node extras that are not an object (glTF allows any type) with rdtf's properties written in them
// as text: the joint was lost without a word. Extras of someone else's, without "rdtf", are left
// alone; and a document whose extras is null converts (it was refused: EXTRAS_NOT_OBJECT).
TEST(Plausibility, RdtfPropertiesInExtrasThatAreNoObjectAreNamed) {
  json doc = arm();
  doc["nodes"][1]["extras"] = "rdtf_joint=revolute";
  expect_one(convert_and_find(doc, codes::RDTF_UNKNOWN_KEY), "/nodes/1/extras",
             {"extras is text (\"rdtf_joint=revolute\"), not an object, so the rdtf properties in it are not read"});
  doc["nodes"][1]["extras"] = json::array({1, 2, 3});
  EXPECT_TRUE(convert_and_find(doc, codes::RDTF_UNKNOWN_KEY).empty());
  doc = arm();
  doc["extras"] = nullptr;
  EXPECT_TRUE(convert_and_find(doc, codes::EXTRAS_NOT_OBJECT).empty());
}

// A robot in a scene other than the one converted (gltf-transform merge keeps each file's scene;
// a decoy in scene 0) was left out without a word.
TEST(Plausibility, ARobotInASceneNotConvertedIsNamed) {
  json doc = arm();
  const json robot_scene = doc["scenes"][doc.value("scene", 0)];
  doc["nodes"].push_back({{"name", "decoy"}, {"mesh", 0}});
  doc["scenes"] = json::array({{{"name", "props"}, {"nodes", {doc["nodes"].size() - 1}}}, robot_scene});
  doc.erase("scene");
  const auto found = convert_and_find(doc, codes::SCENE_NOT_CONVERTED);
  expect_one(found, "/scenes/1",
             {"scene 1 holds 4 node(s) with rdtf properties (node 0 'base'",
              "but rdtf converts one scene, scene 0 'props' (the first: the document names none): set the document's "
              "'scene' to 1"});
  doc["scene"] = 1;
  EXPECT_TRUE(convert_and_find(doc, codes::SCENE_NOT_CONVERTED).empty());
}

// The arm with its elbow as a joint empty, as Blender models it: base > elbow (empty) > arm.
json arm_with_elbow_empty() {
  json doc = arm();
  json elbow = {{"name", "elbow"},
                {"translation", doc["nodes"][1]["translation"]},
                {"rotation", doc["nodes"][1]["rotation"]},
                {"children", {1}},
                {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", {0, 0, 1}}, {"rdtf_lower", -1.0}, {"rdtf_upper", 1.5}}}};
  doc["nodes"][1].erase("translation");
  doc["nodes"][1].erase("rotation");
  for (const char* key : {"rdtf_joint", "rdtf_axis", "rdtf_lower", "rdtf_upper", "rdtf_damping", "rdtf_spring_stiffness"}) {
    doc["nodes"][1]["extras"].erase(key);
  }
  doc["nodes"].push_back(elbow);  // node 4
  doc["nodes"][0]["children"] = {4};
  return doc;
}

// A part's density or mass typed on its joint empty (selected to type the joint's keys) was
// ignored without a word: the part kept the default density (s80blend D4).
TEST(Plausibility, MassKeysOnAJointEmptyAreNamedAsIgnored) {
  json doc = arm_with_elbow_empty();
  EXPECT_TRUE(convert_and_find(doc, codes::RDTF_NODE_EXTRAS_IGNORED).empty());
  doc["nodes"][4]["extras"]["rdtf_density"] = 2700;
  doc["nodes"][4]["extras"]["rdtf_mass"] = 1.5;
  const auto found = convert_and_find(doc, codes::RDTF_NODE_EXTRAS_IGNORED);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].pointer, "/nodes/4/extras/rdtf_density");
  EXPECT_EQ(found[1].pointer, "/nodes/4/extras/rdtf_mass");
  for (const Diagnostic& d : found) {
    EXPECT_EQ(d.severity, Severity::kWarning);
    EXPECT_NE(d.message.find("joint node 4 'elbow'"), std::string::npos) << d.message;
    EXPECT_NE(d.message.find("set it on the part 'arm' (the link below it)"), std::string::npos) << d.message;
  }
}

// A joint empty at the top of the tree has its part below it, and nothing above to turn on: the
// warning said "no part hangs below it" and told the modeller to do what was done (s80blend D5).
TEST(Plausibility, AJointEmptyAtTheTopOfTheTreeIsSaidToHaveNothingAbove) {
  json doc = arm_with_elbow_empty();
  doc["nodes"].push_back({{"name", "root_joint"}, {"children", {0}}, {"extras", {{"rdtf_joint", "revolute"}}}});
  doc["scenes"][0]["nodes"] = {5};
  expect_one(convert_and_find(doc, codes::JOINT_MOVES_NOTHING), "/nodes/5",
             {"joint node 5 'root_joint'", "no part above it", "Parent the empty to the part it turns on"});
  // An empty whose part went elsewhere still hears that nothing hangs below it.
  doc = arm_with_elbow_empty();
  doc["nodes"][4].erase("children");
  doc["nodes"][0]["children"] = {4, 1};
  expect_one(convert_and_find(doc, codes::JOINT_MOVES_NOTHING), "/nodes/4",
             {"joint node 4 'elbow'", "no part hangs below it"});
}

}  // namespace
}  // namespace rdtf

namespace rdtf {
namespace {

// Two links named alike (the objects of a Blender collection instance keep the collection's
// names): said once per name, at the second, listing their nodes. The model's own names are
// distinct: nothing.
TEST(Plausibility, LinksThatShareANameAreNamedOnce) {
  EXPECT_TRUE(convert_and_find(arm(), codes::DUPLICATE_NAMES).empty());
  json doc = arm();
  doc["nodes"][2]["name"] = "arm";  // The slider, a link of its own, now named as the arm.
  expect_one(convert_and_find(doc, codes::DUPLICATE_NAMES), "/nodes/2",
             {"2 links are named 'arm' (nodes 1, 2)", "renamed there ('arm_2', ...)"});
}

}  // namespace
}  // namespace rdtf

namespace rdtf {
namespace {

// Two joint empties of one name: the joints take it, and that is said. (Joints rdtf names after
// their links are not: the links' own warning says it.)
TEST(Plausibility, JointEmptiesThatShareANameAreNamed) {
  json doc = arm();
  const std::size_t first = doc["nodes"].size();
  json hinge = {{"name", "hinge"}, {"children", {1}}, {"translation", doc["nodes"][1]["translation"]},
                {"rotation", doc["nodes"][1]["rotation"]}, {"extras", doc["nodes"][1]["extras"]}};
  json slide = {{"name", "hinge"}, {"children", {2}}, {"translation", doc["nodes"][2]["translation"]},
                {"extras", doc["nodes"][2]["extras"]}};
  for (const std::size_t part : {1, 2}) {
    doc["nodes"][part].erase("extras");
    doc["nodes"][part].erase("translation");
    doc["nodes"][part].erase("rotation");
  }
  doc["nodes"].push_back(hinge);
  doc["nodes"].push_back(slide);
  doc["nodes"][0]["children"] = {first};
  doc["nodes"][1]["children"] = {first + 1, 3};
  const auto found = convert_and_find(doc, codes::DUPLICATE_NAMES);
  expect_one(found, "/nodes/" + std::to_string(first + 1),
             {"2 joints are named 'hinge' (nodes " + std::to_string(first) + ", " + std::to_string(first + 1) + ")"});
}

// Joints rdtf names after their links can share a name though every link's is its own, since "_"
// joins them: root > a_b > c and root > a > b_c both give "a_b_c_joint", which joint commands and
// states cannot tell apart (s80spec D8).
TEST(Plausibility, JointNamesMadeAlikeFromDistinctLinksAreNamed) {
  json doc = arm();
  const json box = doc["nodes"][0]["mesh"];
  doc["nodes"] = json::array({{{"name", "root"}, {"mesh", box}, {"children", {1, 2}}},
                              {{"name", "a_b"}, {"mesh", box}, {"translation", {1, 0, 0}}, {"children", {3}}},
                              {{"name", "a"}, {"mesh", box}, {"translation", {-1, 0, 0}}, {"children", {4}}},
                              {{"name", "c"}, {"mesh", box}, {"translation", {1, 0, 0}}},
                              {{"name", "b_c"}, {"mesh", box}, {"translation", {-1, 0, 0}}}});
  doc["scenes"][0]["nodes"] = {0};
  const auto found = convert_and_find(doc, codes::DUPLICATE_NAMES);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NE(found[0].message.find("2 joints are named 'a_b_c_joint'"), std::string::npos) << found[0].message;
}

// A skew is named where a rotation inside a non-uniform scale makes one; the rounding of a float
// quaternion (Blender's 90 degrees about x, [0.70710683, 0, 0, 0.70710671]) inside a scale of ratio
// 300 is none, nor is a node outside the scene, nor a scale of 0 (which flattens).
TEST(Plausibility, ASkewIsNamedButNotFloatRoundingNodesOutsideTheSceneOrAFlatteningScale) {
  const auto with = [](const json& base_scale, const json& arm_rotation) {
    json doc = arm();
    doc["nodes"][0]["scale"] = base_scale;
    doc["nodes"][1]["rotation"] = arm_rotation;
    return doc;
  };
  const json thirty_about_x = {0.25881904510252074, 0, 0, 0.9659258262890683};
  expect_one(convert_and_find(with({1, 1, 3}, thirty_about_x), codes::NODE_SHEARED), "/nodes/1",
             {"node 1 'arm' is skewed", "node 0 'base' (scale 1, 1, 3)"});
  EXPECT_TRUE(convert_and_find(with({1, 1, 1.0 / 300}, {0.7071068286895752, 0, 0, 0.7071067094802856}),
                               codes::NODE_SHEARED)
                  .empty());
  // The same skew in a second scene that is not the one converted.
  json other = with({1, 1, 3}, thirty_about_x);
  other["scenes"].push_back({{"nodes", {0}}});
  other["scenes"][0]["nodes"] = json::array();
  other["nodes"].push_back({{"name", "root"}, {"mesh", 0}});
  other["scenes"][0]["nodes"].push_back(other["nodes"].size() - 1);
  other["scene"] = 0;
  EXPECT_TRUE(convert_and_find(other, codes::NODE_SHEARED).empty());
  EXPECT_TRUE(convert_and_find(with({1, 1, 0}, thirty_about_x), codes::NODE_SHEARED).empty());
}

}  // namespace
}  // namespace rdtf
