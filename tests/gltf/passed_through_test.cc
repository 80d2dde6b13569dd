// What rdtf writes out again without reading it: KHR_lights_punctual (core/gltf/validate_extensions.cc),
// the extensions any object uses (each must be in extensionsUsed) and an accessor's byteOffset
// (which needs its bufferView). Each broken one passed into an output the Khronos validator
// refused. On small documents, rdtf reports its errors exactly where the validator reports its own
// (code and JSON pointer); on a sound one neither does, and a converted model keeps its lights.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>
#include <string>
#include <utility>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/validate.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

using Places = std::set<std::pair<std::string, std::string>>;  // {code, JSON pointer}

std::string listing(const Places& places) {
  std::string text;
  for (const auto& [code, pointer] : places) text += "  " + code + " " + pointer + "\n";
  return text.empty() ? "  (none)\n" : text;
}

Places rdtf_errors(const Json& document) {
  Diagnostics diag;
  validate_document(document, LoadLimits{}, diag);
  Places places;
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError) places.insert({d.code, d.pointer});
  }
  return places;
}

Places validator_errors(const Json& document) {
  testing::TempDir dir;
  testing::write_file(dir / "model.gltf", document.dump());
  const nlohmann::json report = testing::khronos_report(dir / "model.gltf");
  Places places;
  for (const auto& issue : report.at("issues").at("messages")) {
    if (issue.at("severity") == 0) places.insert({issue.at("code"), issue.value("pointer", "")});
  }
  return places;
}

// Nodes named n0, n1, ... each carrying the light of its index, and the document's lights.
Json with_lights(const Json& lights, std::size_t lit_nodes) {
  Json document = {{"asset", {{"version", "2.0"}}}, {"scene", 0}, {"extensionsUsed", {"KHR_lights_punctual"}}};
  document["nodes"] = Json::array();
  document["scenes"] = Json::parse(R"([{"nodes": []}])");
  for (std::size_t i = 0; i < lit_nodes; ++i) {
    document["nodes"].push_back({{"name", "n" + std::to_string(i)}, {"extensions", {{"KHR_lights_punctual", {{"light", i}}}}}});
    document["scenes"][0]["nodes"].push_back(i);
  }
  if (!lights.is_null()) document["extensions"] = {{"KHR_lights_punctual", {{"lights", lights}}}};
  return document;
}

void expect_same_errors(const Json& document, const std::string& what) {
  const Places ours = rdtf_errors(document);
  const Places theirs = validator_errors(document);
  EXPECT_EQ(ours, theirs) << what << "\nrdtf:\n" << listing(ours) << "validator:\n" << listing(theirs);
}

TEST(PassedThrough, BrokenLightsAreRefusedWhereTheValidatorRefusesThem) {
  const double right = std::numbers::pi / 2;
  const Json sound = Json::parse(R"([
    {"type": "point", "color": [1, 0.5, 0], "intensity": 0, "range": 1e-30},
    {"type": "directional", "intensity": 3},
    {"type": "spot", "spot": {}},
    {"type": "spot", "spot": {"innerConeAngle": 0, "outerConeAngle": 1.5707963267948966}},
    {"type": "spot", "spot": {"outerConeAngle": 0.1}}])");
  const Json document = with_lights(sound, sound.size());
  EXPECT_EQ(rdtf_errors(document), Places{}) << listing(rdtf_errors(document));
  expect_same_errors(document, "sound lights");

  const std::vector<std::pair<std::string, Json>> broken = {
      {"color out of [0, 1]", Json::parse(R"([{"type": "point", "color": [1, 2, 0]}])")},
      {"color of two", Json::parse(R"([{"type": "point", "color": [1, 1]}])")},
      {"color not numbers", Json::parse(R"([{"type": "point", "color": [0, 0, "x"]}])")},
      {"color a string", Json::parse(R"([{"type": "point", "color": "red"}])")},
      {"negative intensity", Json::parse(R"([{"type": "point", "intensity": -1}])")},
      {"intensity a string", Json::parse(R"([{"type": "point", "intensity": "a"}])")},
      {"range 0", Json::parse(R"([{"type": "point", "range": 0}])")},
      {"range negative", Json::parse(R"([{"type": "point", "range": -1}])")},
      {"no type", Json::parse(R"([{"color": [1, 1, 1]}])")},
      {"type a number", Json::parse(R"([{"type": 3}])")},
      {"name a number", Json::parse(R"([{"type": "point", "name": 3}])")},
      {"spot without its cone", Json::parse(R"([{"type": "spot"}])")},
      {"spot cone a number", Json::parse(R"([{"type": "spot", "spot": 3}])")},
      {"cones in the wrong order", Json::parse(R"([{"type": "spot", "spot": {"innerConeAngle": 1.0, "outerConeAngle": 0.5}}])")},
      {"inner cone past the default outer", Json::parse(R"([{"type": "spot", "spot": {"innerConeAngle": 0.9}}])")},
      {"cones out of range", Json::parse(R"([{"type": "spot", "spot": {"innerConeAngle": -1, "outerConeAngle": 2}}])")},
      {"inner cone a right angle", Json::array({{{"type", "spot"}, {"spot", {{"innerConeAngle", right}, {"outerConeAngle", right}}}}})},
      {"outer cone 0", Json::parse(R"([{"type": "spot", "spot": {"innerConeAngle": 0, "outerConeAngle": 0}}])")},
      {"a light not an object", Json::parse(R"([{"type": "point"}, 3])")},
      {"no lights", Json::array()},
      {"lights an object", Json::object()},
  };
  for (const auto& [what, lights] : broken) {
    const Json broken_document = with_lights(lights, 1);
    EXPECT_FALSE(rdtf_errors(broken_document).empty()) << what;
    expect_same_errors(broken_document, what);
  }
}

TEST(PassedThrough, NodesNamingMissingLightsAreRefusedWhereTheValidatorRefusesThem) {
  const Json one = Json::parse(R"([{"type": "point"}])");
  Json document = with_lights(one, 1);
  document["nodes"].push_back(Json::parse(R"({"name": "far", "extensions": {"KHR_lights_punctual": {"light": 9}}})"));
  document["nodes"].push_back(Json::parse(R"({"name": "none", "extensions": {"KHR_lights_punctual": {}}})"));
  document["nodes"].push_back(Json::parse(R"({"name": "half", "extensions": {"KHR_lights_punctual": {"light": 1.5}}})"));
  document["nodes"].push_back(Json::parse(R"({"name": "three", "extensions": {"KHR_lights_punctual": 3}})"));
  for (std::size_t i = 1; i < document["nodes"].size(); ++i) document["scenes"][0]["nodes"].push_back(i);
  expect_same_errors(document, "nodes naming lights");
  EXPECT_EQ(rdtf_errors(document).count({"UNRESOLVED_REFERENCE", "/nodes/1/extensions/KHR_lights_punctual/light"}), 1u);

  // No lights in the document at all.
  expect_same_errors(with_lights(Json(), 1), "a node's light without the document's");
  Json root_not_object = with_lights(Json(), 1);
  root_not_object["extensions"] = {{"KHR_lights_punctual", Json::array()}};
  expect_same_errors(root_not_object, "the document's extension an array");
  Json root_without_lights = with_lights(Json(), 1);
  root_without_lights["extensions"] = {{"KHR_lights_punctual", Json::object()}};
  expect_same_errors(root_without_lights, "the document's extension without lights");

  // A negative index: the validator's INVALID_INDEX, rdtf's VALUE_NOT_IN_RANGE (as for every index).
  Json negative = with_lights(one, 1);
  negative["nodes"][0]["extensions"]["KHR_lights_punctual"]["light"] = -1;
  EXPECT_EQ(rdtf_errors(negative), (Places{{"VALUE_NOT_IN_RANGE", "/nodes/0/extensions/KHR_lights_punctual/light"}}));
}

TEST(PassedThrough, ExtensionsMissingFromExtensionsUsedAndOffsetsIntoNoViewAreRefused) {
  Json undeclared = with_lights(Json::parse(R"([{"type": "point"}])"), 1);
  undeclared.erase("extensionsUsed");
  undeclared["nodes"][0]["extensions"]["EXT_made_up"] = {{"x", 1}};
  undeclared["materials"] = Json::parse(R"([{"extensions": {"KHR_materials_unlit": {}}}])");
  expect_same_errors(undeclared, "undeclared extensions");
  EXPECT_EQ(rdtf_errors(undeclared).count({"UNDECLARED_EXTENSION", "/nodes/0/extensions/EXT_made_up"}), 1u);
  EXPECT_EQ(rdtf_errors(undeclared).count({"UNDECLARED_EXTENSION", "/materials/0/extensions/KHR_materials_unlit"}), 1u);
  undeclared["extensionsUsed"] = {"KHR_lights_punctual", "EXT_made_up", "KHR_materials_unlit"};
  EXPECT_EQ(rdtf_errors(undeclared), Places{}) << listing(rdtf_errors(undeclared));

  // Undeclared and misplaced: the validator says only that it is undeclared, and so does rdtf.
  Json misplaced = undeclared;
  misplaced["scenes"][0]["extensions"] = Json::parse(R"({"KHR_texture_transform": {}})");
  expect_same_errors(misplaced, "an undeclared extension in the wrong place");
  EXPECT_EQ(rdtf_errors(misplaced).count({"UNDECLARED_EXTENSION", "/scenes/0/extensions/KHR_texture_transform"}), 1u);

  for (const int offset : {0, 4}) {
    Json accessor = Json::parse(R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
      "nodes": [{"name": "n"}], "accessors": [{"componentType": 5126, "count": 3, "type": "VEC3"}]})");
    accessor["accessors"][0]["byteOffset"] = offset;
    expect_same_errors(accessor, "byteOffset " + std::to_string(offset) + " without bufferView");
    EXPECT_EQ(rdtf_errors(accessor), (Places{{"UNSATISFIED_DEPENDENCY", "/accessors/0/byteOffset"}}));
  }
}

// One mesh of one primitive (its positions all zero: an accessor without a view) with materials
// m0 and m1, two variants, and the primitive's variant mappings.
Json with_variants(const Json& root, const Json& mappings) {
  Json document = Json::parse(R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "extensionsUsed": ["KHR_materials_variants"], "nodes": [{"name": "n", "mesh": 0}],
    "materials": [{"name": "m0"}, {"name": "m1"}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
    "accessors": [{"componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 0]}]})");
  if (!root.is_null()) document["extensions"]["KHR_materials_variants"] = root;
  document["meshes"][0]["primitives"][0]["extensions"]["KHR_materials_variants"] = mappings;
  return document;
}

TEST(PassedThrough, BrokenMaterialVariantsAreRefusedWhereTheValidatorRefusesThem) {
  const Json variants = Json::parse(R"({"variants": [{"name": "a"}, {"name": "b", "extras": {"id": 3}}]})");
  const Json sound = Json::parse(R"({"mappings": [{"material": 0, "variants": [0], "name": "x"}, {"material": 1, "variants": [1]}]})");
  EXPECT_EQ(rdtf_errors(with_variants(variants, sound)), Places{}) << listing(rdtf_errors(with_variants(variants, sound)));
  expect_same_errors(with_variants(variants, sound), "sound variants");

  const std::vector<std::pair<std::string, Json>> broken_mappings = {
      {"no mappings", Json::object()},
      {"empty mappings", Json::parse(R"({"mappings": []})")},
      {"a mapping not an object", Json::parse(R"({"mappings": [3]})")},
      {"unresolved and missing", Json::parse(R"({"mappings": [{"material": 5, "variants": [7]}, {"material": 0, "variants": []},
                                                                {"variants": [0]}, {"material": 1}]})")},
      {"a variant twice in a mapping", Json::parse(R"({"mappings": [{"material": 0, "variants": [0, 0]}]})")},
      {"a variant in two mappings", Json::parse(R"({"mappings": [{"material": 0, "variants": [0]}, {"material": 1, "variants": [1, 0]}]})")},
      {"a mapping's name a number", Json::parse(R"({"mappings": [{"material": 0, "variants": [0], "name": 1}]})")},
      {"mappings an object", Json::parse(R"({"mappings": {}})")},
  };
  for (const auto& [what, mappings] : broken_mappings) {
    EXPECT_FALSE(rdtf_errors(with_variants(variants, mappings)).empty()) << what;
    expect_same_errors(with_variants(variants, mappings), what);
  }
  const Json one_mapping = Json::parse(R"({"mappings": [{"material": 0, "variants": [0]}]})");
  const std::vector<std::pair<std::string, Json>> broken_roots = {
      {"no root extension", Json()},
      {"no variants", Json::object()},
      {"empty variants", Json::parse(R"({"variants": []})")},
      {"variants an object", Json::parse(R"({"variants": {}})")},
      {"a variant not an object", Json::parse(R"({"variants": [{"name": "a"}, 3]})")},
      {"a variant without its name", Json::parse(R"({"variants": [{}]})")},
      {"a variant's name a number", Json::parse(R"({"variants": [{"name": 0}]})")},
  };
  for (const auto& [what, root] : broken_roots) {
    EXPECT_FALSE(rdtf_errors(with_variants(root, one_mapping)).empty()) << what;
    expect_same_errors(with_variants(root, one_mapping), what);
  }
}

// Each extension the validator knows extends some kinds of object only; on another it is an error.
TEST(PassedThrough, ExtensionsOnObjectsTheyDoNotExtendAreRefused) {
  Json document = with_variants(Json::parse(R"({"variants": [{"name": "a"}]})"),
                                Json::parse(R"({"mappings": [{"material": 0, "variants": [0]}]})"));
  document["extensionsUsed"] = {"KHR_materials_variants", "KHR_lights_punctual", "KHR_materials_unlit",
                                "KHR_texture_transform", "KHR_animation_pointer", "EXT_made_up"};
  document["extensions"]["KHR_lights_punctual"] = Json::parse(R"({"lights": [{"type": "point"}]})");
  document["extensions"]["KHR_materials_unlit"] = Json::object();                     // Wrong: a material's.
  document["nodes"][0]["extensions"] = Json::parse(R"({"KHR_lights_punctual": {"light": 0},
                                                      "KHR_materials_variants": {}, "EXT_made_up": {}})");
  document["meshes"][0]["extensions"] = Json::parse(R"({"KHR_lights_punctual": {"light": 0}})");
  document["materials"][0]["extensions"] = Json::parse(R"({"KHR_materials_unlit": {}, "KHR_texture_transform": {}})");
  document["materials"][1]["pbrMetallicRoughness"] =
      Json::parse(R"({"extensions": {"KHR_texture_transform": {}, "KHR_animation_pointer": {}}})");
  const Places ours = rdtf_errors(document);
  expect_same_errors(document, "extensions in the wrong places");
  const std::string wrong[] = {"/extensions/KHR_materials_unlit", "/nodes/0/extensions/KHR_materials_variants",
                               "/meshes/0/extensions/KHR_lights_punctual",
                               "/materials/0/extensions/KHR_texture_transform",
                               "/materials/1/pbrMetallicRoughness/extensions/KHR_texture_transform",
                               "/materials/1/pbrMetallicRoughness/extensions/KHR_animation_pointer"};
  for (const std::string& pointer : wrong) {
    EXPECT_EQ(ours.count({"UNEXPECTED_EXTENSION_OBJECT", pointer}), 1u) << pointer << "\n" << listing(ours);
  }
}

// Blender's arm with a point light and a spot light on frames under two of its links: converted, the
// output keeps both, each on its node, and passes the validator.
TEST(PassedThrough, AConvertedModelKeepsItsLights) {
  testing::TempDir dir;
  Json document = Json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf"));
  std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin", dir / "arm3.bin");
  if (!document.contains("extensionsUsed")) document["extensionsUsed"] = Json::array();
  document["extensionsUsed"].push_back("KHR_lights_punctual");
  document["extensions"]["KHR_lights_punctual"]["lights"] =
      Json::parse(R"([{"type": "point", "intensity": 2}, {"type": "spot", "spot": {"outerConeAngle": 0.5}}])");
  const std::size_t parents[] = {2, 6};  // The links forearm and upper_arm.
  ASSERT_EQ(document["nodes"][2]["name"], "forearm");
  ASSERT_EQ(document["nodes"][6]["name"], "upper_arm");
  for (std::size_t light = 0; light < 2; ++light) {
    const std::size_t index = document["nodes"].size();
    document["nodes"].push_back({{"name", "lamp" + std::to_string(light)}, {"translation", {0.0, 0.1, 0.0}},
                                 {"extensions", {{"KHR_lights_punctual", {{"light", light}}}}}});
    document["nodes"][parents[light]]["children"].push_back(index);
  }
  testing::write_file(dir / "lit.gltf", document.dump());
  const auto result = testing::run_command(testing::cli_path() + " convert " + (dir / "lit.gltf").string() + " -o " +
                                           (dir / "out" / "lit.gltf").string());
  ASSERT_EQ(result.exit_code, 0) << result.out << result.err;
  const Json out = Json::parse(testing::read_file(dir / "out" / "lit.gltf"));
  EXPECT_EQ(out["extensions"]["KHR_lights_punctual"], document["extensions"]["KHR_lights_punctual"]);
  std::set<std::string> lit;
  for (const Json& node : out["nodes"]) {
    if (node.contains("extensions") && node["extensions"].contains("KHR_lights_punctual")) {
      lit.insert(node["name"].get<std::string>() + ":" + node["extensions"]["KHR_lights_punctual"]["light"].dump());
    }
  }
  EXPECT_EQ(lit, (std::set<std::string>{"lamp0:0", "lamp1:1"}));
  const nlohmann::json report = testing::khronos_report(dir / "out" / "lit.gltf");
  EXPECT_EQ(report["issues"]["numErrors"], 0) << report["issues"].dump(1);
}

}  // namespace
}  // namespace rdtf
