// Every reproducer the fuzz targets found, fed through run_target (fuzz/fuzz_pipeline.h), the
// very code the fuzz target that found it runs on each input: tests/data/fuzz-regressions/
// <target>/<file>. Each must keep the bad-input contract (no crash, an error diagnostic with a
// code for every refusal, diagnostics and summaries that can be written as JSON, output that
// converts again) and end as tests/data/fuzz-regressions/expected.json says: refused with the
// error code named there, or converted when it says "OK" (a valid input that used to crash).
#include <gtest/gtest.h>

#include <algorithm>

#include "../../fuzz/fuzz_pipeline.h"
#include "rdtf/summary.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

namespace fs = std::filesystem;

fs::path regressions_dir() { return testing::data_dir() / "fuzz-regressions"; }

nlohmann::json expected_codes() {
  return nlohmann::json::parse(testing::read_file(regressions_dir() / "expected.json"));
}

// The target a reproducer belongs to: its folder.
std::string target_of(const std::string& name) {
  const fs::path path(name);
  return path.has_parent_path() ? path.begin()->string() : std::string();
}

TEST(FuzzRegressions, EveryReproducerEndsAsExpected) {
  const nlohmann::json expected = expected_codes();
  std::size_t checked = 0;
  for (const auto& [name, code] : expected.items()) {
    if (name == "comment") continue;
    SCOPED_TRACE(name);
    testing::TempDir folder;
    const fuzz::Workspace workspace = fuzz::make_workspace(folder.path(), testing::data_dir());
    const fuzz::TargetRun result =
        fuzz::run_target(target_of(name), fuzz::read_bytes(regressions_dir() / name), workspace);
    EXPECT_FALSE(result.not_for_target) << "the target skips this input";
    EXPECT_EQ(result.violation, "");
    if (code == "OK") {
      EXPECT_TRUE(result.run.succeeded);
      for (const Diagnostic& d : result.run.diag.all()) {
        if (d.severity == Severity::kError) ADD_FAILURE() << format(d);
      }
    } else {
      EXPECT_FALSE(result.run.succeeded);
      EXPECT_TRUE(result.run.diag.contains(code.get<std::string>())) << "expected " << code;
      if (!result.run.diag.contains(code.get<std::string>())) {
        for (const Diagnostic& d : result.run.diag.all()) ADD_FAILURE() << format(d);
      }
    }
    ++checked;
  }
  EXPECT_GE(checked, 2u);
}

// A reproducer nobody listed would never run: every file below a target folder must be listed,
// with an error code or "OK", and every target folder must be a target.
TEST(FuzzRegressions, EveryReproducerIsListed) {
  const nlohmann::json expected = expected_codes();
  for (const auto& entry : fs::recursive_directory_iterator(regressions_dir())) {
    if (!entry.is_regular_file()) continue;
    const std::string name = fs::relative(entry.path(), regressions_dir()).generic_string();
    if (name == "expected.json") continue;
    EXPECT_TRUE(expected.contains(name)) << name << " is not in expected.json";
  }
  for (const auto& [name, code] : expected.items()) {
    if (name == "comment") continue;
    EXPECT_TRUE(fs::is_regular_file(regressions_dir() / name)) << name << " is listed but missing";
    EXPECT_TRUE(code.is_string() && !code.get<std::string>().empty()) << name;
    const std::string target = target_of(name);
    EXPECT_TRUE(std::find(std::begin(fuzz::kTargets), std::end(fuzz::kTargets), target) !=
                std::end(fuzz::kTargets))
        << name << ": '" << target << "' is not a fuzz target";
  }
}

// The regression tests and the fuzzers share run_target: a reproducer replayed here is the input
// the fuzzer ran. One input per target that must convert (or parse), through the same call.
TEST(FuzzRegressions, EveryTargetRunsAValidInput) {
  testing::TempDir folder;
  const fuzz::Workspace workspace = fuzz::make_workspace(folder.path(), testing::data_dir());
  const auto khronos = fuzz::read_bytes(testing::data_dir() / "khronos/Box.gltf");
  const auto arm3_glb = fuzz::read_bytes(testing::data_dir() / "blender/arm3.glb");
  const auto urdf = fuzz::read_bytes(testing::data_dir() / "urdf/urdf_tutorial/02-multipleshapes.urdf");
  const std::pair<std::string_view, std::vector<std::uint8_t>> inputs[] = {
      {"convert_gltf", khronos}, {"convert_glb", arm3_glb}, {"glb", arm3_glb},
      {"extras", fuzz::to_bytes(R"({"version":"1.0"})")}, {"urdf_import", urdf}};
  for (const auto& [target, bytes] : inputs) {
    SCOPED_TRACE(std::string(target));
    const fuzz::TargetRun result = fuzz::run_target(target, bytes, workspace);
    EXPECT_FALSE(result.not_for_target);
    EXPECT_TRUE(result.run.succeeded);
    EXPECT_EQ(result.violation, "");
  }
  EXPECT_TRUE(fuzz::run_target("convert_gltf", arm3_glb, workspace).not_for_target);
  EXPECT_TRUE(fuzz::run_target("convert_glb", khronos, workspace).not_for_target);
  EXPECT_TRUE(fuzz::run_target("extras", fuzz::to_bytes("{"), workspace).not_for_target);
  EXPECT_NE(fuzz::run_target("no_such_target", khronos, workspace).violation, "");
}

// A parse error at bytes that are not UTF-8: the diagnostic says where (line, column, byte) but never
// quotes the file's bytes (a model may be any file), and its JSON is written (rdtf validate --json
// used to die in nlohmann's writer on the quoted bytes).
TEST(FuzzRegressions, ParseErrorWithInvalidUtf8IsWrittenAsJson) {
  testing::TempDir folder;
  const auto run = fuzz::convert_bytes(fuzz::to_bytes("{\"asset\":\xff}"), folder.path());
  ASSERT_TRUE(run.diag.contains("INVALID_JSON"));
  const std::string text = diagnostics_json(run.diag).dump();
  EXPECT_NE(text.find("line 1, column 10 (byte 10)"), std::string::npos) << text;
  EXPECT_EQ(text.find('\xff'), std::string::npos) << text;
}

// File names are bytes on Linux: a model named "\xff.gltf" gives the robot that name and every
// diagnostic that file; both must still be written as JSON.
TEST(FuzzRegressions, FileNameThatIsNotUtf8IsWrittenAsJson) {
  testing::TempDir folder;
  const fs::path model = folder / "\xff.gltf";
  fs::copy_file(testing::data_dir() / "khronos" / "Box.gltf", model);
  Diagnostics diag;
  const auto conversion = convert_file(model, ConvertOptions{}, diag);
  ASSERT_TRUE(conversion.has_value());
  EXPECT_EQ(conversion->robot.name, "\xff");
  const Json summary = robot_summary(conversion->robot, conversion->asset.document, diag);
  EXPECT_EQ(summary["robot"], "\xEF\xBF\xBD");
  EXPECT_NO_THROW(summary.dump());

  const fs::path broken = folder / "\xfe-broken.gltf";
  testing::write_file(broken, "{");
  Diagnostics broken_diag;
  EXPECT_FALSE(convert_file(broken, ConvertOptions{}, broken_diag).has_value());
  const Json items = diagnostics_json(broken_diag);
  ASSERT_FALSE(items.empty());
  const std::string file = items[0]["file"].get<std::string>();
  EXPECT_EQ(fs::path(file).filename().string(), "\xEF\xBF\xBD-broken.gltf");
  EXPECT_NO_THROW(items.dump());
}

}  // namespace
}  // namespace rdtf
