// The Khronos glTF-Validator's own test models (tests/data/gltf-validator, see its README.md),
// each beside the validator's report. What a model's report says decides what rdtf must do:
//
// - Refuse: the report has an error about the container (GLB_*, JSON), or about what converting
//   mesh geometry and the node tree reads: /asset, /buffers, /bufferViews, /accessors, /meshes,
//   /nodes, /scenes, /scene, /skins (skinned meshes are split by bone) and /animations (rdtf reads
//   the channels that move the robot, NODE_ANIMATED, and writes every animation into its output). load_gltf must then
//   fail with an error naming the file and, when the validator's errors include some about the
//   document proper (not the container, not loading buffer data), report at least one of them
//   with the validator's code and JSON pointer. Three kinds of error are exempt, because the
//   converter never reads what they are about and copies it unchanged:
//     1. errors inside an "extensions" object (rdtf reads no extension);
//     2. a primitive's "material" not suiting it (tangent space, texture coordinates): shading;
//     3. values of NORMAL, TANGENT and COLOR_n attributes (ACCESSOR_NON_CLAMPED,
//        ACCESSOR_VECTOR3_NON_UNIT, ACCESSOR_INVALID_SIGN): shading.
// - Load (and convert): the report has no error at all. load_gltf must succeed, since rdtf must
//   not refuse what the validator accepts; and when the default scene (or scene 0) holds a node
//   with a mesh, convert_file must succeed too. Exempt: models with a buffer whose data is not
//   provided (no uri in a .gltf, a placeholder in a GLB: the report lists it among its resources
//   without a "storage"). The validator checks nothing of such data; rdtf, which has to read
//   it, refuses the buffer (BUFFER_MISSING_URI).
// - Otherwise (errors only about materials, textures, images, cameras, animations...) there is
//   nothing to require but robustness.
// No model may crash or throw, whatever its class.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "rdtf/convert.h"
#include "rdtf/gltf.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

namespace fs = std::filesystem;

fs::path suite_dir() { return testing::data_dir() / "gltf-validator"; }

std::vector<fs::path> suite_models() {
  std::vector<fs::path> models;
  for (const auto& entry : fs::recursive_directory_iterator(suite_dir())) {
    const auto extension = entry.path().extension();
    if (entry.is_regular_file() && (extension == ".gltf" || extension == ".glb")) {
      models.push_back(entry.path());
    }
  }
  std::sort(models.begin(), models.end());
  return models;
}

// "base/data/accessor/alignment.gltf" -> "accessor_alignment_gltf".
std::string case_name(const fs::path& model) {
  std::string name;
  for (const auto& part : fs::relative(model, suite_dir())) {
    if (part == "base" || part == "data") continue;
    if (!name.empty()) name += '_';
    name += part.string();
  }
  std::replace_if(
      name.begin(), name.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); },
      '_');
  return name;
}

bool starts_with(const std::string& text, const std::string& prefix) {
  return text.rfind(prefix, 0) == 0;
}

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The issue's JSON pointer; empty for issues of the GLB container, which have none.
std::string pointer_of(const nlohmann::json& issue) {
  const auto found = issue.find("pointer");
  return found != issue.end() && found->is_string() ? found->get<std::string>() : "";
}

// An error of the validator that concerns what rdtf reads (see the comment at the top).
bool concerns_the_converter(const nlohmann::json& issue) {
  const std::string code = issue.value("code", "");
  const std::string pointer = pointer_of(issue);
  if (starts_with(code, "GLB_") || starts_with(code, "JSON_") || code == "INVALID_JSON")
    return true;
  // "/scene" also covers "/scenes".
  static const char* const kRead[] = {"/asset",  "/buffers", "/bufferViews", "/accessors",
                                      "/meshes", "/nodes",   "/scene",       "/skins",
                                      "/animations"};
  const bool read = std::any_of(std::begin(kRead), std::end(kRead),
                                [&](const char* prefix) { return starts_with(pointer, prefix); });
  if (!read) return false;
  const bool in_extension = pointer.find("/extensions/") != std::string::npos;
  const bool material_fit = starts_with(pointer, "/meshes/") && ends_with(pointer, "/material");
  const bool shading_values = code == "ACCESSOR_NON_CLAMPED" ||
                              code == "ACCESSOR_VECTOR3_NON_UNIT" ||
                              code == "ACCESSOR_INVALID_SIGN";
  return !in_extension && !material_fit && !shading_values;
}

enum class Expectation { kRefuse, kLoad, kRobust };

struct Verdict {
  Expectation expectation = Expectation::kRobust;
  std::string reason;  // The validator's issue that decided it, for failure messages.
  // (code, pointer) of the errors in the document proper: not GLB or JSON, not about buffers' data.
  std::vector<std::pair<std::string, std::string>> document_errors;
};

// A buffer the model declares but does not provide (no uri in a .gltf, a GLB placeholder).
bool has_unprovided_buffer(const nlohmann::json& report) {
  if (!report.contains("info") || !report["info"].contains("resources")) return false;
  return std::any_of(report["info"]["resources"].begin(), report["info"]["resources"].end(),
                     [](const auto& resource) {
                       return starts_with(resource.value("pointer", ""), "/buffers/") &&
                              !resource.contains("storage");
                     });
}

Verdict classify(const nlohmann::json& report) {
  if (report.contains("fatalError"))
    return {Expectation::kRefuse, "validator: " + report["fatalError"].dump(), {}};
  std::size_t errors = 0;
  Verdict refuse{Expectation::kRefuse, "", {}};
  bool refused = false;
  for (const auto& issue : report.at("issues").at("messages")) {
    if (issue.value("severity", -1) != 0) continue;
    ++errors;
    if (!concerns_the_converter(issue)) continue;
    if (!refused) refuse.reason = issue.dump();
    refused = true;
    const std::string pointer = pointer_of(issue);
    if (!pointer.empty() && !starts_with(pointer, "/buffers"))
      refuse.document_errors.emplace_back(issue.value("code", ""), pointer);
  }
  if (refused) return refuse;
  if (errors == 0 && !has_unprovided_buffer(report)) return {Expectation::kLoad, "", {}};
  return {Expectation::kRobust, "", {}};
}

// The default scene (or scene 0) holds, somewhere below its roots, a node with a mesh.
bool default_scene_has_mesh(const Json& document) {
  if (!document.contains("scenes")) return false;
  const std::size_t scene = document.contains("scene") ? document["scene"].get<std::size_t>() : 0;
  std::vector<std::size_t> stack;
  for (const Json& root : document["scenes"][scene].value("nodes", Json::array()))
    stack.push_back(root.get<std::size_t>());
  while (!stack.empty()) {
    const Json& node = document["nodes"][stack.back()];
    stack.pop_back();
    if (node.contains("mesh")) return true;
    for (const Json& child : node.value("children", Json::array()))
      stack.push_back(child.get<std::size_t>());
  }
  return false;
}

std::string listing(const Diagnostics& diag) {
  std::string text;
  for (const Diagnostic& d : diag.all()) text += "  " + format(d) + "\n";
  return text.empty() ? "  (no diagnostics)\n" : text;
}

class ValidatorSuite : public ::testing::TestWithParam<fs::path> {};

TEST_P(ValidatorSuite, MatchesTheValidatorsVerdict) {
  const fs::path model = GetParam();
  const fs::path report_path = model.string() + ".report.json";
  ASSERT_TRUE(fs::exists(report_path)) << report_path << " is missing: run make_reports.sh";
  const Verdict verdict = classify(nlohmann::json::parse(std::ifstream(report_path)));

  Diagnostics diag;
  std::optional<GltfAsset> asset;
  ASSERT_NO_THROW(asset = load_gltf(model, LoadLimits{}, diag)) << model;
  Diagnostics converted;
  std::optional<Conversion> conversion;
  ASSERT_NO_THROW(conversion = convert_file(model, ConvertOptions{}, converted)) << model;

  switch (verdict.expectation) {
    case Expectation::kRefuse: {
      EXPECT_FALSE(asset.has_value())
          << "the validator reports " << verdict.reason << "\nbut rdtf loaded it:\n"
          << listing(diag);
      const std::string file = model.filename().string();
      const bool named =
          std::any_of(diag.all().begin(), diag.all().end(), [&](const Diagnostic& d) {
            return d.severity == Severity::kError && format(d).find(file) != std::string::npos;
          });
      EXPECT_TRUE(named) << "no error names " << file << ":\n" << listing(diag);
      EXPECT_FALSE(conversion.has_value());
      // Refused for the validator's reason: each problem of the document proper (not of the
      // container or of loading buffer data) is reported with the validator's code and pointer.
      // Unless rdtf refused the file as a whole, before a JSON pointer exists (an error without
      // one): the JSON reader rejects a number beyond the range of a double (1e309), which the
      // validator reads as Infinity and reports where it stands.
      const bool refused_whole = std::any_of(
          diag.all().begin(), diag.all().end(),
          [](const Diagnostic& d) { return d.severity == Severity::kError && d.pointer.empty(); });
      if (!verdict.document_errors.empty() && !refused_whole) {
        const bool same_reason =
            std::any_of(diag.all().begin(), diag.all().end(), [&](const Diagnostic& d) {
              return std::count(verdict.document_errors.begin(), verdict.document_errors.end(),
                                std::pair{d.code, d.pointer}) > 0;
            });
        std::string expected;
        for (const auto& [code, pointer] : verdict.document_errors)
          expected += "  " + code + " at " + pointer + "\n";
        EXPECT_TRUE(same_reason) << "the validator reports\n"
                                 << expected << "but rdtf reports none of them:\n"
                                 << listing(diag);
      }
      break;
    }
    case Expectation::kLoad:
      ASSERT_TRUE(asset.has_value()) << "the validator finds no error, but rdtf refused it:\n"
                                     << listing(diag);
      if (default_scene_has_mesh(asset->document)) {
        EXPECT_TRUE(conversion.has_value())
            << "the default scene has a mesh, but conversion failed:\n"
            << listing(converted);
      }
      break;
    case Expectation::kRobust:
      break;
  }
}

INSTANTIATE_TEST_SUITE_P(KhronosValidator, ValidatorSuite, ::testing::ValuesIn(suite_models()),
                         [](const ::testing::TestParamInfo<fs::path>& param) {
                           return case_name(param.param);
                         });

}  // namespace
}  // namespace rdtf
