// Writing RDTF: every output passes the Khronos validator with no errors and no more warnings than
// its input, converting an output again gives it back unchanged, and .glb outputs are complete.
#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/write.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

struct Fixture {
  std::string folder;
  std::string file;
};

std::vector<Fixture> models() {
  std::vector<Fixture> result;
  for (const char* file : {"two_cylinder.gltf", "arm3.gltf", "arm3.glb", "transforms.gltf",
                           "skinned_arm.gltf"}) {
    result.push_back({"blender", file});
  }
  for (const char* file : {"Box.gltf", "Triangle.gltf", "TriangleWithoutIndices.gltf",
                           "SimpleMeshes.gltf", "SimpleSparseAccessor.gltf", "MultipleScenes.gltf",
                           "Cameras.gltf", "SimpleSkin.gltf", "RiggedSimple.gltf",
                           "MeshPrimitiveModes.gltf"}) {
    result.push_back({"khronos", file});
  }
  return result;
}

int count(const nlohmann::json& report, const char* what) {
  return report["issues"][what].get<int>();
}

std::string messages(const nlohmann::json& report) {
  std::string out;
  for (const auto& m : report["issues"]["messages"]) {
    if (m["severity"].get<int>() <= 1) out += m.dump() + "\n";
  }
  return out;
}

class WriteRdtf : public ::testing::TestWithParam<std::tuple<Fixture, OutputFormat>> {};

TEST_P(WriteRdtf, OutputValidatesAndConvertsBackToItself) {
  const auto& [fixture, output_format] = GetParam();
  const auto input = testing::data_dir() / fixture.folder / fixture.file;
  testing::TempDir out;
  const std::string extension = output_format == OutputFormat::kGlb ? ".glb" : ".gltf";
  const auto first = out / ("first" + extension);
  const auto second = out / ("second" + extension);

  Diagnostics diag;
  auto conversion = convert_file(input, ConvertOptions{}, diag);
  ASSERT_TRUE(conversion) << (diag.all().empty() ? "" : format(diag.all().front()));
  ASSERT_TRUE(write_rdtf(conversion->asset, first, output_format, diag));

  const auto input_report = testing::khronos_report(input);
  const auto output_report = testing::khronos_report(first);
  EXPECT_EQ(count(output_report, "numErrors"), 0) << messages(output_report);
  EXPECT_LE(count(output_report, "numWarnings"), count(input_report, "numWarnings"))
      << messages(output_report);

  Diagnostics again_diag;
  auto again = convert_file(first, ConvertOptions{}, again_diag);
  ASSERT_TRUE(again);
  ASSERT_TRUE(write_rdtf(again->asset, second, output_format, again_diag));
  // Idempotent: the output of converting the output is the output, byte for byte.
  EXPECT_EQ(testing::read_file(second), testing::read_file(first)) << "conversion is not idempotent";
  ASSERT_EQ(again->robot.links.size(), conversion->robot.links.size());
  for (std::size_t i = 0; i < again->robot.links.size(); ++i) {
    EXPECT_EQ(again->robot.links[i].name, conversion->robot.links[i].name);
    EXPECT_EQ(again->robot.links[i].inertial.mass, conversion->robot.links[i].inertial.mass);
    EXPECT_EQ(again->robot.links[i].inertial.center_of_mass,
              conversion->robot.links[i].inertial.center_of_mass);
  }
}

std::string case_name(const ::testing::TestParamInfo<WriteRdtf::ParamType>& info) {
  std::string name = std::get<0>(info.param).file;
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return name + (std::get<1>(info.param) == OutputFormat::kGlb ? "_to_glb" : "_to_gltf");
}

INSTANTIATE_TEST_SUITE_P(Fixtures, WriteRdtf,
                         ::testing::Combine(::testing::ValuesIn(models()),
                                            ::testing::Values(OutputFormat::kGltf,
                                                              OutputFormat::kGlb)),
                         case_name);

TEST(WriteRdtfFiles, GltfOutputCopiesItsBufferBesideIt) {
  testing::TempDir out;
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / "arm3.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  ASSERT_TRUE(write_rdtf(conversion->asset, out / "robot.gltf", OutputFormat::kGltf, diag));
  EXPECT_EQ(testing::read_file(out / "arm3.bin"),
            testing::read_file(testing::data_dir() / "blender" / "arm3.bin"));
}

TEST(WriteRdtfFiles, GlbInputToGltfGetsItsBinaryChunkAsAFile) {
  testing::TempDir out;
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / "arm3.glb", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  ASSERT_TRUE(write_rdtf(conversion->asset, out / "my robot.gltf", OutputFormat::kGltf, diag));
  EXPECT_EQ(conversion->asset.buffers[0].size(), std::filesystem::file_size(out / "my robot.bin"));
  const auto written = Json::parse(testing::read_file(out / "my robot.gltf"));
  EXPECT_EQ(written["buffers"][0]["uri"], "my%20robot.bin");
}

TEST(WriteRdtfFiles, NoTemporaryFilesAreLeftBehind) {
  testing::TempDir out;
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / "arm3.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  ASSERT_TRUE(write_rdtf(conversion->asset, out / "robot.glb", OutputFormat::kGlb, diag));
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(out.path())) {
    names.push_back(entry.path().filename().string());
  }
  EXPECT_EQ(names, std::vector<std::string>{"robot.glb"});
}

TEST(WriteRdtfFiles, UnwritableTargetIsAnErrorAndLeavesNoTemporaryFile) {
  testing::TempDir out;
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / "arm3.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  // A directory where the file should go: rename() refuses, even for root.
  std::filesystem::create_directories(out / "robot.glb" / "occupied");
  Diagnostics write_diag;
  EXPECT_FALSE(write_rdtf(conversion->asset, out / "robot.glb", OutputFormat::kGlb, write_diag));
  ASSERT_TRUE(write_diag.contains("WRITE_FAILED"));
  EXPECT_NE(format(write_diag.all().front()).find("robot.glb"), std::string::npos);
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(out.path())) ++entries;
  EXPECT_EQ(entries, 1u) << "only the directory that was already there";
}

}  // namespace
}  // namespace rdtf
