// What accessors and buffer views are used for (core/gltf/validate_usage.cc): on every model of
// tests/data/gltf-usage, rdtf reports ACCESSOR_USAGE_OVERRIDE, BUFFER_VIEW_TARGET_OVERRIDE and
// ACCESSOR_MATRIX_ALIGNMENT at exactly the places the Khronos validator does, so that it never
// copies into its output a use the validator refuses, and refuses nothing the validator accepts.
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

const std::set<std::string> kCodes = {"ACCESSOR_USAGE_OVERRIDE", "BUFFER_VIEW_TARGET_OVERRIDE",
                                      "ACCESSOR_MATRIX_ALIGNMENT"};

fs::path models_dir() { return testing::data_dir() / "gltf-usage"; }

std::vector<fs::path> models() {
  std::vector<fs::path> found;
  for (const auto& entry : fs::recursive_directory_iterator(models_dir())) {
    if (entry.path().extension() == ".gltf") found.push_back(entry.path());
  }
  std::sort(found.begin(), found.end());
  return found;
}

Places rdtf_places(const fs::path& model, bool& errors) {
  Diagnostics diag;
  validate_document(Json::parse(testing::read_file(model)), LoadLimits{}, diag);
  errors = diag.has_errors();
  Places places;
  for (const Diagnostic& d : diag.all()) {
    if (kCodes.count(d.code) != 0) {
      EXPECT_EQ(d.severity, Severity::kError) << format(d);
      places.insert({d.code, d.pointer});
    }
  }
  return places;
}

// The validator reports a view used twice by one animation output twice at one place; a set
// compares places.
// `unreadable_accessor`: the validator warns of an accessor's componentType or type not in its list
// (its VALUE_NOT_IN_LIST is a warning), which rdtf, unable to read such an accessor, refuses.
Places validator_places(const fs::path& model, bool& errors, bool& unreadable_accessor) {
  const nlohmann::json report = testing::khronos_report(model);
  errors = report.at("issues").at("numErrors").get<int>() > 0;
  unreadable_accessor = false;
  Places places;
  for (const auto& issue : report.at("issues").at("messages")) {
    const std::string code = issue.at("code");
    if (code == "VALUE_NOT_IN_LIST" && issue.value("pointer", "").rfind("/accessors/", 0) == 0) {
      unreadable_accessor = true;
    }
    if (kCodes.count(code) == 0) continue;
    EXPECT_EQ(issue.at("severity"), 0) << code;
    places.insert({code, issue.value("pointer", "")});
  }
  return places;
}

std::string all_text(const Diagnostics& diag) {
  std::string out;
  for (const Diagnostic& d : diag.all()) out += format(d) + "\n";
  return out;
}

std::string text(const Places& places) {
  std::string out;
  for (const auto& [code, pointer] : places) out += "  " + code + " at " + pointer + "\n";
  return out.empty() ? "  (none)\n" : out;
}

TEST(ValidateUsage, EveryModelIsReportedWhereTheValidatorReportsIt) {
  const auto all = models();
  ASSERT_GE(all.size(), 40u);
  std::size_t refused = 0, accepted = 0;
  for (const fs::path& model : all) {
    SCOPED_TRACE(model.filename().string());
    bool our_errors = false, their_errors = false, unreadable_accessor = false;
    const Places ours = rdtf_places(model, our_errors);
    const Places theirs = validator_places(model, their_errors, unreadable_accessor);
    EXPECT_EQ(ours, theirs) << "rdtf:\n" << text(ours) << "validator:\n" << text(theirs);
    // What the validator accepts, rdtf reads too (a negative bufferView target, say, is a warning).
    if (!their_errors && !unreadable_accessor) {
      EXPECT_FALSE(our_errors) << "the validator accepts it";
    }
    (theirs.empty() ? accepted : refused) += 1;
  }
  // Both kinds are there: uses the validator refuses, and sharing it allows.
  EXPECT_GE(refused, 25u);
  EXPECT_GE(accepted, 10u);
}

// The places and the first use named, for the cases a user meets: a POSITION accessor reused
// as an animation's output (its view then holds vertices and animation data), a view whose target
// says indices holding positions, and a byte matrix off a 4-byte boundary.
TEST(ValidateUsage, TheMessageNamesBothUsesAtTheLaterReference) {
  Diagnostics diag;
  validate_document(Json::parse(testing::read_file(models_dir() / "06b_usage_position_reused_as_anim_output.gltf")),
                    LoadLimits{}, diag);
  const Diagnostic* usage = nullptr;
  const Diagnostic* view = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == "ACCESSOR_USAGE_OVERRIDE") usage = &d;
    if (d.code == "BUFFER_VIEW_TARGET_OVERRIDE") view = &d;
  }
  ASSERT_NE(usage, nullptr) << all_text(diag);
  EXPECT_EQ(usage->pointer, "/animations/0/samplers/0/output");
  EXPECT_NE(usage->message.find("vertex data ('VertexAttribute')"), std::string::npos) << usage->message;
  EXPECT_NE(usage->message.find("animation values ('AnimationOutput')"), std::string::npos) << usage->message;
  ASSERT_NE(view, nullptr);
  EXPECT_EQ(view->pointer, "/animations/0/samplers/0/output");
  EXPECT_NE(view->message.find("vertices (target 34962"), std::string::npos) << view->message;

  Diagnostics target;
  validate_document(Json::parse(testing::read_file(models_dir() / "11_bv_target_element_used_by_position.gltf")),
                    LoadLimits{}, target);
  ASSERT_TRUE(target.contains("BUFFER_VIEW_TARGET_OVERRIDE")) << all_text(target);

  Diagnostics matrix;
  validate_document(Json::parse(testing::read_file(models_dir() / "22_mat3_ushort_offset6.gltf")), LoadLimits{},
                    matrix);
  ASSERT_TRUE(matrix.contains("ACCESSOR_MATRIX_ALIGNMENT")) << all_text(matrix);
}

// The CLI refuses such a model with the file, the place and the code, and writes nothing.
TEST(ValidateUsage, ConvertRefusesAndWritesNothing) {
  testing::TempDir dir;
  const fs::path model = models_dir() / "06b_usage_position_reused_as_anim_output.gltf";
  const fs::path out = dir.path() / "out.gltf";
  const auto run = testing::run_command("'" + testing::cli_path() + "' convert '" + model.string() + "' -o '" +
                                        out.string() + "'");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("06b_usage_position_reused_as_anim_output.gltf"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("/animations/0/samplers/0/output"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("ACCESSOR_USAGE_OVERRIDE"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

}  // namespace
}  // namespace rdtf
