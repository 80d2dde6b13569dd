// The formats a vertex attribute's accessor may have (core/gltf/validate_attribute_formats.cc): on
// every model of tests/data/gltf-attribute-formats (each attribute, on a primitive and on a morph
// target, with and without KHR_mesh_quantization, in 60 formats each), rdtf reports
// MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT, ..._UNSIGNED_INT and
// MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS exactly where the Khronos validator does: a format
// it refuses is never passed on into an output, and no format it allows is refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/validate.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

namespace fs = std::filesystem;

using Places = std::set<std::pair<std::string, std::string>>;  // {code, JSON pointer}

const std::set<std::string> kCodes = {"MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT",
                                      "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_UNSIGNED_INT",
                                      "MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS"};

fs::path models_dir() { return testing::data_dir() / "gltf-attribute-formats"; }

std::vector<fs::path> models() {
  std::vector<fs::path> found;
  for (const auto& entry : fs::directory_iterator(models_dir())) {
    if (entry.path().extension() == ".gltf") found.push_back(entry.path());
  }
  std::sort(found.begin(), found.end());
  return found;
}

Places rdtf_places(const fs::path& model) {
  Diagnostics diag;
  validate_document(Json::parse(testing::read_file(model)), LoadLimits{}, diag);
  Places places;
  for (const Diagnostic& d : diag.all()) {
    if (kCodes.count(d.code) == 0) continue;
    EXPECT_EQ(d.severity, Severity::kError) << format(d);
    places.insert({d.code, d.pointer});
  }
  return places;
}

Places validator_places(const fs::path& model) {
  const nlohmann::json report = testing::khronos_report(model);
  Places places;
  for (const auto& issue : report.at("issues").at("messages")) {
    const std::string code = issue.at("code");
    if (kCodes.count(code) == 0) continue;
    EXPECT_EQ(issue.at("severity"), 0) << code;
    places.insert({code, issue.value("pointer", "")});
  }
  return places;
}

std::string text(const Places& places) {
  std::string out;
  for (const auto& [code, pointer] : places) out += "  " + code + " at " + pointer + "\n";
  return out.empty() ? "  (none)\n" : out;
}

TEST(AttributeFormats, EveryFormatIsRefusedWhereTheValidatorRefusesIt) {
  const auto all = models();
  ASSERT_EQ(all.size(), 28u);  // 8 attributes on a primitive, 6 on a morph target, x 2
  std::size_t refused = 0, allowed = 0;
  for (const fs::path& model : all) {
    SCOPED_TRACE(model.filename().string());
    const Places ours = rdtf_places(model);
    const Places theirs = validator_places(model);
    Places only_ours, only_theirs;
    std::set_difference(ours.begin(), ours.end(), theirs.begin(), theirs.end(),
                        std::inserter(only_ours, only_ours.end()));
    std::set_difference(theirs.begin(), theirs.end(), ours.begin(), ours.end(),
                        std::inserter(only_theirs, only_theirs.end()));
    EXPECT_TRUE(only_ours.empty() && only_theirs.empty())
        << "rdtf only:\n" << text(only_ours) << "validator only:\n" << text(only_theirs);
    // 60 primitives a model: those whose tested attribute is refused, and those allowed.
    std::size_t formats_refused = 0;
    for (const auto& [code, pointer] : theirs) {
      formats_refused += code != "MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS" ? 1 : 0;
    }
    refused += formats_refused;
    allowed += 60 - std::min<std::size_t>(formats_refused, 60);
  }
  // Both kinds are there, in numbers: the tables allow 1 to 10 formats of the 60 per attribute.
  EXPECT_GE(refused, 1000u);
  EXPECT_GE(allowed, 60u);
}

// What a user reads: the place, the format found and the formats allowed, and the extension that
// would allow it.
TEST(AttributeFormats, TheMessageSaysWhatIsFoundAndWhatIsAllowed) {
  Diagnostics diag;
  validate_document(Json::parse(testing::read_file(models_dir() / "base_NORMAL.gltf")), LoadLimits{}, diag);
  const Diagnostic* mat4 = nullptr;
  const Diagnostic* short_normalized = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code != "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT") continue;
    // Primitive k tests format k: types SCALAR..MAT4 x components BYTE..FLOAT x normalized.
    if (d.pointer == "/meshes/0/primitives/59/attributes/NORMAL") mat4 = &d;
    if (d.pointer == "/meshes/0/primitives/29/attributes/NORMAL") short_normalized = &d;
  }
  ASSERT_NE(mat4, nullptr);
  EXPECT_NE(mat4->message.find("is MAT4 of normalized FLOAT; NORMAL must be VEC3 of FLOAT"), std::string::npos)
      << mat4->message;
  ASSERT_NE(short_normalized, nullptr);
  EXPECT_NE(short_normalized->message.find("VEC3 of normalized SHORT needs KHR_mesh_quantization"),
            std::string::npos)
      << short_normalized->message;

  Diagnostics quantized;
  validate_document(Json::parse(testing::read_file(models_dir() / "base_NORMAL_quantized.gltf")), LoadLimits{},
                    quantized);
  for (const Diagnostic& d : quantized.all()) {
    if (d.code != "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT") continue;
    EXPECT_NE(d.pointer, "/meshes/0/primitives/29/attributes/NORMAL") << format(d);
  }
}

// The CLI refuses a model whose NORMAL is a MAT4, naming the file, the place and the code, and
// writes nothing.
TEST(AttributeFormats, ConvertRefusesAndWritesNothing) {
  testing::TempDir dir;
  const fs::path model = models_dir() / "base_NORMAL.gltf";
  const fs::path out = dir.path() / "out.gltf";
  const auto run = testing::run_command("'" + testing::cli_path() + "' convert '" + model.string() + "' -o '" +
                                        out.string() + "'");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("base_NORMAL.gltf"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("/meshes/0/primitives/59/attributes/NORMAL"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

}  // namespace
}  // namespace rdtf
