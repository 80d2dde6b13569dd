// Every reproducer the fuzz targets found, fed through the entry point of the target that found
// it (fuzz/fuzz_pipeline.h, the same code the fuzzers run): each must be refused with the error
// tests/data/fuzz-regressions/expected.json names, and keep the bad-input contract (no crash,
// diagnostics that can be written as JSON).
#include <gtest/gtest.h>

#include <set>

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

// The entry point of the fuzz target a reproducer's folder is named after.
fuzz::RunResult run_reproducer(const std::string& target, const std::vector<std::uint8_t>& bytes,
                               const fs::path& folder) {
  if (target == "convert_gltf" || target == "convert_glb") return fuzz::convert_bytes(bytes, folder);
  std::string roundtrip_failure;
  if (target == "glb") return fuzz::parse_glb_bytes(bytes, roundtrip_failure);
  ADD_FAILURE() << "no entry point for target '" << target << "'";
  return fuzz::RunResult();
}

TEST(FuzzRegressions, EveryReproducerIsRefusedWithItsError) {
  const nlohmann::json expected = expected_codes();
  std::size_t checked = 0;
  for (const auto& [name, code] : expected.items()) {
    if (name == "comment") continue;
    SCOPED_TRACE(name);
    const fs::path file = regressions_dir() / name;
    testing::TempDir folder;
    const fuzz::RunResult run =
        run_reproducer(fs::path(name).parent_path().string(), fuzz::read_bytes(file), folder.path());
    EXPECT_FALSE(run.succeeded);
    EXPECT_TRUE(run.diag.contains(code.get<std::string>())) << "expected " << code;
    EXPECT_EQ(fuzz::contract_violation(run), "");
    ++checked;
  }
  EXPECT_GE(checked, 2u);
}

// A reproducer nobody listed would never run: every file below a target folder must be listed.
TEST(FuzzRegressions, EveryReproducerIsListed) {
  const nlohmann::json expected = expected_codes();
  for (const auto& entry : fs::recursive_directory_iterator(regressions_dir())) {
    if (!entry.is_regular_file()) continue;
    const std::string name = fs::relative(entry.path(), regressions_dir()).generic_string();
    if (name == "expected.json" || name.rfind("pending/", 0) == 0) continue;
    EXPECT_TRUE(expected.contains(name)) << name << " is not in expected.json";
  }
}

// The parse error quotes the bytes it stopped at: not UTF-8, so the JSON of the diagnostics
// carries U+FFFD in their place (rdtf validate --json used to die in nlohmann's writer).
TEST(FuzzRegressions, ParseErrorWithInvalidUtf8IsWrittenAsJson) {
  testing::TempDir folder;
  const auto run = fuzz::convert_bytes(fuzz::to_bytes("{\"asset\":\xff}"), folder.path());
  ASSERT_TRUE(run.diag.contains("INVALID_JSON"));
  const std::string text = diagnostics_json(run.diag).dump();
  EXPECT_NE(text.find("\xEF\xBF\xBD"), std::string::npos) << text;
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
