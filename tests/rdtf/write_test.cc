// Writing RDTF: every output passes the Khronos validator with no errors and no more warnings than
// its input, converting an output again gives it back unchanged, and .glb outputs are complete.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <set>
#include <stdexcept>

#include "conversion.h"  // rdtfd's output_digest: the SHA-256 the daemon names its files with.
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
                           "skinned_arm.gltf", "modelled_arm.gltf", "modelled_bones.gltf", "skinned_roundtrip.glb"}) {
    result.push_back({"blender", file});
  }
  result.push_back({"frames", "mount_empty.gltf"});
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
  // Idempotent: the output of converting the output is the output, byte for byte, but for the
  // names of its buffer files, which follow the output's name (and whose bytes are the same).
  std::string second_text = testing::read_file(second);
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"\"second.bin\"", "\"first.bin\""},
                                 {"\"second_", "\"first_"}}) {
    for (auto at = second_text.find(from); at != std::string::npos; at = second_text.find(from, at + to.size())) {
      second_text.replace(at, from.size(), to);
    }
  }
  EXPECT_EQ(second_text, testing::read_file(first)) << "conversion is not idempotent";
  if (output_format == OutputFormat::kGltf) {
    for (std::size_t i = 0; i < conversion->asset.buffers.size(); ++i) {
      const std::string suffix = (i == 0 ? "" : "_" + std::to_string(i)) + ".bin";
      if (!std::filesystem::exists(out / ("first" + suffix))) continue;  // An embedded buffer.
      EXPECT_EQ(testing::read_file(out / ("second" + suffix)), testing::read_file(out / ("first" + suffix)));
    }
  }
  ASSERT_EQ(again->robot.links.size(), conversion->robot.links.size());
  ASSERT_EQ(again->robot.joints.size(), conversion->robot.joints.size());
  // The same frames: a joint's pivot read again where the first conversion put it.
  for (std::size_t i = 0; i < again->robot.joints.size(); ++i) {
    const Joint& a = again->robot.joints[i];
    const Joint& b = conversion->robot.joints[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_LE((a.X_PJ.matrix() - b.X_PJ.matrix()).cwiseAbs().maxCoeff(), 1e-12)
        << a.name << ":\n" << a.X_PJ.matrix() << "\nfirst:\n" << b.X_PJ.matrix();
    EXPECT_LE((a.axis - b.axis).norm(), 1e-12) << a.name;
  }
  for (std::size_t i = 0; i < again->robot.links.size(); ++i) {
    EXPECT_EQ(again->robot.links[i].name, conversion->robot.links[i].name);
    EXPECT_LE((again->robot.links[i].X_SL.matrix() - conversion->robot.links[i].X_SL.matrix()).cwiseAbs().maxCoeff(),
              1e-12) << again->robot.links[i].name;
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

// rdtf's output of mount_empty holds the joint's entry on the mount and its keys on the arm, its
// own pivot. Keys on the arm that name another joint type than the entry are stale (extras.RDTF
// wins, and says so): they do not move the pivot off the mount, where the entry alone puts it.
TEST(WriteRdtfFiles, StaleNodeExtrasDoNotMoveAPivotTheEntryPlaces) {
  testing::TempDir out;
  Diagnostics diag;
  auto first = convert_file(testing::data_dir() / "frames" / "mount_empty.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(first);
  ASSERT_TRUE(write_rdtf(first->asset, out / "out.gltf", OutputFormat::kGltf, diag));
  Json document = Json::parse(testing::read_file(out / "out.gltf"));
  std::size_t arm = 0;
  for (std::size_t i = 0; i < document["nodes"].size(); ++i) {
    if (document["nodes"][i].value("name", "") == "arm") arm = i;
  }
  const auto origin_of = [&](const Json& doc, Diagnostics& d) {
    testing::write_file(out / "edited.gltf", doc.dump());
    auto conversion = convert_file(out / "edited.gltf", ConvertOptions{}, d);
    EXPECT_TRUE(conversion);
    return conversion ? Eigen::Vector3d(conversion->robot.joints.at(0).X_PJ.translation()) : Eigen::Vector3d::Zero();
  };
  Diagnostics agreeing;
  EXPECT_LE((origin_of(document, agreeing) - Eigen::Vector3d(0.1 * std::sqrt(0.5), 0.2 + 0.1 * std::sqrt(0.5), 0)).norm(),
            1e-9);
  document["nodes"][arm]["extras"]["rdtf_joint"] = "fixed";
  Diagnostics stale;
  EXPECT_LE((origin_of(document, stale) - Eigen::Vector3d(0, 0.2, 0)).norm(), 1e-9);
  EXPECT_TRUE(stale.contains("RDTF_NODE_EXTRAS_IGNORED"));
  document["nodes"][arm]["extras"].erase("rdtf_joint");
  document["nodes"][arm]["extras"].erase("rdtf_axis");
  document["nodes"][arm]["extras"].erase("rdtf_lower");
  document["nodes"][arm]["extras"].erase("rdtf_upper");
  Diagnostics entry_only;
  EXPECT_LE((origin_of(document, entry_only) - Eigen::Vector3d(0, 0.2, 0)).norm(), 1e-9);
}

TEST(WriteRdtfFiles, GltfOutputCopiesItsBufferBesideIt) {
  testing::TempDir out;
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / "arm3.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  ASSERT_TRUE(write_rdtf(conversion->asset, out / "robot.gltf", OutputFormat::kGltf, diag));
  EXPECT_EQ(testing::read_file(out / "robot.bin"),
            testing::read_file(testing::data_dir() / "blender" / "arm3.bin"));
  EXPECT_EQ(Json::parse(testing::read_file(out / "robot.gltf"))["buffers"][0]["uri"], "robot.bin");
}

// Two models whose buffers have the same name, converted into one folder, keep their own.
TEST(WriteRdtfFiles, BuffersOfModelsWithTheSameBufferNameDoNotCollide) {
  testing::TempDir in_a, in_b, out;
  const auto arm = testing::data_dir() / "blender" / "arm3";
  for (const auto* folder : {&in_a, &in_b}) {
    std::filesystem::copy_file(arm.string() + ".gltf", *folder / "model.gltf");
    std::filesystem::copy_file(arm.string() + ".bin", *folder / "arm3.bin");
  }
  // b's buffer differs: one float of its first position changed.
  std::string bytes = testing::read_file(in_b / "arm3.bin");
  bytes[0] = static_cast<char>(bytes[0] ^ 0x01);
  testing::write_file(in_b / "arm3.bin", bytes);
  for (const auto& [input, output] : {std::pair{in_a / "model.gltf", out / "a.gltf"}, {in_b / "model.gltf", out / "b.gltf"}}) {
    Diagnostics diag;
    auto conversion = convert_file(input, ConvertOptions{}, diag);
    ASSERT_TRUE(conversion);
    ASSERT_TRUE(write_rdtf(conversion->asset, output, OutputFormat::kGltf, diag));
  }
  EXPECT_EQ(testing::read_file(out / "a.bin"), testing::read_file(in_a / "arm3.bin"));
  EXPECT_EQ(testing::read_file(out / "b.bin"), testing::read_file(in_b / "arm3.bin"));
  EXPECT_FALSE(std::filesystem::exists(out / "arm3.bin"));
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

// ---- Content-addressed names (the daemon's outputs: docs/daemon.md, "Outputs") ----

std::vector<std::uint8_t> bytes_of(const std::string& text) { return {text.begin(), text.end()}; }

// "<stem>.<first 16 hex digits of SHA-256(bytes)><extension>", computed here from the bytes.
std::string addressed(const std::string& stem, const std::vector<std::uint8_t>& bytes, const std::string& extension) {
  return stem + "." + daemon::output_digest(bytes).substr(0, 16) + extension;
}

std::set<std::string> names_in(const std::filesystem::path& folder) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) names.insert(entry.path().filename().string());
  return names;
}

WriteOptions content_addressed() {
  WriteOptions options;
  options.content_digest = daemon::output_digest;
  return options;
}

TEST(WriteContentAddressedName, IsTheStemThenSixteenHexDigitsOfTheDigestThenTheExtension) {
  // SHA-256("abc") = ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad (FIPS 180-2).
  const auto abc = bytes_of("abc");
  EXPECT_EQ(content_addressed_name("m6", ".bin", abc, daemon::output_digest), "m6.ba7816bf8f01cfea.bin");
  EXPECT_EQ(content_addressed_name("my robot", "", abc, daemon::output_digest), "my robot.ba7816bf8f01cfea");
  // An output converted again keeps one digest in its name, not two.
  EXPECT_EQ(content_addressed_name("m6.0123456789abcdef", ".bin", abc, daemon::output_digest),
            "m6.ba7816bf8f01cfea.bin");
  EXPECT_THROW(content_addressed_name("m6", ".bin", abc, [](auto) { return std::string("0123"); }),
               std::invalid_argument);
  EXPECT_THROW(content_addressed_name("m6", ".bin", abc, [](auto) { return std::string("0123456789ABCDEF"); }),
               std::invalid_argument);
}

TEST(WriteContentAddressedName, PatternMatchesOnlyNamesOfThatForm) {
  for (const char* name : {"m6.ba7816bf8f01cfea.bin", "my robot.ba7816bf8f01cfea", "base.0123456789abcdef.stl",
                           "a.b.0123456789abcdef.png"}) {
    EXPECT_TRUE(is_content_addressed_name(name)) << name;
  }
  for (const char* name : {"m6.bin", "m6.rdtf.gltf", "robot.urdf", "base.stl", ".0123456789abcdef.bin",
                           "m6.0123456789ABCDEF.bin", "m6.0123456789abcde.bin", "m6.0123456789abcdef0.bin",
                           "m6.0123456789abcdef.rdtf.gltf", "m6.0123456789abcdef.bin.tmp",
                           ".m6.0123456789abcdef.bin.4242-123456.tmp"}) {
    EXPECT_FALSE(is_content_addressed_name(name)) << name;
  }
}

TEST(WriteRdtfContentAddressed, BufferIsNamedAfterItsContentAndTheJsonRefersToIt) {
  testing::TempDir out;
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / "arm3.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  std::string json;
  ASSERT_TRUE(write_rdtf(conversion->asset, out / "arm3.rdtf.gltf", content_addressed(), diag, &json));
  const std::string bin = addressed("arm3", conversion->asset.buffers[0], ".bin");
  EXPECT_EQ(names_in(out.path()), (std::set<std::string>{"arm3.rdtf.gltf", bin}));
  EXPECT_EQ(testing::read_file(out / bin), testing::read_file(testing::data_dir() / "blender" / "arm3.bin"));
  EXPECT_EQ(testing::read_file(out / "arm3.rdtf.gltf"), json);
  EXPECT_EQ(Json::parse(json)["buffers"][0]["uri"], bin);
  Diagnostics load_diag;
  EXPECT_TRUE(load_gltf(out / "arm3.rdtf.gltf", LoadLimits{}, load_diag));
}

TEST(WriteRdtfContentAddressed, GlbChunkAndImagesGetContentNamesWithEncodedUris) {
  testing::TempDir in;
  testing::TempDir out;
  // arm3 with a texture image in a subfolder (images are copied, never decoded).
  std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin", in / "arm3.bin");
  Json document = Json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf"));
  document["images"] = Json::array({Json{{"uri", "tex/wood%20grain.png"}}});
  std::filesystem::create_directories(in / "tex");
  testing::write_file(in / "tex" / "wood grain.png", "not really a PNG");
  testing::write_file(in / "arm3.gltf", document.dump());
  Diagnostics diag;
  auto conversion = convert_file(in / "arm3.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  ASSERT_TRUE(write_rdtf(conversion->asset, out / "my robot.gltf", content_addressed(), diag));
  const std::string bin = addressed("arm3", conversion->asset.buffers[0], ".bin");
  const std::string png = addressed("wood grain", bytes_of("not really a PNG"), ".png");
  EXPECT_EQ(names_in(out.path()), (std::set<std::string>{"my robot.gltf", bin, png}));
  const auto written = Json::parse(testing::read_file(out / "my robot.gltf"));
  EXPECT_EQ(written["images"][0]["uri"], "wood%20grain." + png.substr(11));
  EXPECT_EQ(testing::read_file(out / png), "not really a PNG");

  // A GLB's binary chunk: "<output stem>.<digest>.bin".
  Diagnostics glb_diag;
  auto glb = convert_file(testing::data_dir() / "blender" / "arm3.glb", ConvertOptions{}, glb_diag);
  ASSERT_TRUE(glb);
  testing::TempDir glb_out;
  ASSERT_TRUE(write_rdtf(glb->asset, glb_out / "my robot.gltf", content_addressed(), glb_diag));
  const std::string chunk = addressed("my robot", glb->asset.buffers[0], ".bin");
  EXPECT_EQ(names_in(glb_out.path()), (std::set<std::string>{"my robot.gltf", chunk}));
  EXPECT_EQ(Json::parse(testing::read_file(glb_out / "my robot.gltf"))["buffers"][0]["uri"],
            "my%20robot." + chunk.substr(9));
}

// A GLB's image says what it holds, read from its bytes: the name said it before, so JPEG bytes in
// a .png, a file without an extension or a percent-encoded dot made a valid model an invalid GLB
// (s80valid D1). Bytes of no image format, with no mimeType declared, stay behind their URI.
TEST(WriteRdtfFiles, GlbImagesAreTypedByTheirBytes) {
  testing::TempDir in;
  testing::TempDir out;
  const auto images = testing::data_dir() / "gltf-validator" / "base" / "data" / "image";
  std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin", in / "arm3.bin");
  std::filesystem::copy_file(images / "cyan.jpg", in / "cyan.png");        // JPEG bytes, .png name
  std::filesystem::copy_file(images / "magenta.png", in / "magenta");      // PNG bytes, no extension
  std::filesystem::copy_file(images / "magenta.png", in / "tex2.png");     // named as tex2%2Epng
  testing::write_file(in / "notes.txt", "not an image");
  Json document = Json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf"));
  document["images"] = Json::array({{{"uri", "cyan.png"}}, {{"uri", "magenta"}}, {{"uri", "tex2%2Epng"}}, {{"uri", "notes.txt"}}});
  testing::write_file(in / "arm3.gltf", document.dump());
  Diagnostics diag;
  auto conversion = convert_file(in / "arm3.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  WriteOptions as_glb;
  as_glb.format = OutputFormat::kGlb;
  ASSERT_TRUE(write_rdtf(conversion->asset, out / "arm3.glb", as_glb, diag));
  bool kept_uri = false;
  for (const Diagnostic& d : diag.all()) {
    kept_uri |= d.code == "IMAGE_NOT_EMBEDDED" && d.pointer == "/images/3/uri" &&
                d.message.find("no PNG, JPEG, WebP or KTX2 by its bytes") != std::string::npos;
  }
  EXPECT_TRUE(kept_uri);
  const std::string glb = testing::read_file(out / "arm3.glb");
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, glb.data() + 12, 4);
  const Json written = Json::parse(glb.substr(20, json_length));
  EXPECT_EQ(written["images"][0]["mimeType"], "image/jpeg");
  EXPECT_EQ(written["images"][1]["mimeType"], "image/png");
  EXPECT_EQ(written["images"][2]["mimeType"], "image/png");
  EXPECT_EQ(written["images"][3]["uri"], "notes.txt");
  EXPECT_FALSE(written["images"][3].contains("bufferView"));
  // The validator reads the three images from the GLB; the fourth it cannot, as in the input.
  std::filesystem::copy_file(in / "notes.txt", out / "notes.txt");
  const auto report = testing::khronos_report(out / "arm3.glb");
  for (const auto& m : report["issues"]["messages"]) {
    EXPECT_NE(m["severity"].get<int>(), 0) << m.dump();
  }
}

// Vertex accessors of different element sizes sharing a view without byteStride: no stride serves
// them all, so the file is refused as the validator refuses it; it was copied into an output the
// validator refused (s80valid D2). One size (Box.gltf, among the fixtures above) gets its stride.
TEST(WriteRdtfFiles, AViewSharedByAccessorsOfDifferentSizesIsRefused) {
  testing::TempDir in;
  Json document = Json::parse(testing::read_file(testing::data_dir() / "khronos" / "Box.gltf"));
  document["accessors"].push_back({{"bufferView", 1}, {"byteOffset", 0}, {"componentType", 5126}, {"count", 24}, {"type", "VEC2"}});
  document["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 3;
  testing::write_file(in / "Box.gltf", document.dump());
  Diagnostics diag;
  EXPECT_FALSE(convert_file(in / "Box.gltf", ConvertOptions{}, diag));
  bool named = false;
  for (const Diagnostic& d : diag.all()) {
    named |= d.code == "MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE" && d.severity == Severity::kError &&
             d.pointer == "/meshes/0/primitives/0/attributes/TEXCOORD_0" &&
             d.message.find("buffer view 1 is shared by 3 vertex accessors of different element sizes") != std::string::npos;
  }
  EXPECT_TRUE(named) << diag.all().size();
}

// arm3 whose buffer carries `padding` zero bytes more (counted in byteLength): a new revision.
GltfAsset arm3_revision(const GltfAsset& asset, std::size_t padding) {
  GltfAsset revision = asset;
  revision.buffers[0].resize(revision.buffers[0].size() + padding, 0);
  revision.document["buffers"][0]["byteLength"] = revision.buffers[0].size();
  return revision;
}

TEST(WriteRdtfContentAddressed, EachWriteKeepsThePreviousGenerationAndRemovesWhatNoneRefersTo) {
  testing::TempDir out;
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / "arm3.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  const auto output = out / "arm3.rdtf.gltf";
  // Left by writes that never committed (a killed daemon), and files that are no one's to remove.
  const std::string orphan = "arm3.0123456789abcdef.bin";
  testing::write_file(out / orphan, "orphan");
  testing::write_file(out / "arm3.bin", "not content-addressed");
  std::filesystem::create_directories(out / "urdf.0123456789abcdef");
  // A link is nothing of ours: neither it nor what it points to goes.
  testing::TempDir elsewhere;
  testing::write_file(elsewhere / "precious", "not the writer's");
  std::filesystem::create_symlink(elsewhere / "precious", out / "arm3.7777777777777777.bin");
  const std::set<std::string> others{"arm3.rdtf.gltf", "arm3.bin", "urdf.0123456789abcdef", "arm3.7777777777777777.bin"};

  std::vector<std::string> bins;
  for (std::size_t padding : {0, 4, 8}) {
    const GltfAsset revision = arm3_revision(conversion->asset, padding);
    ASSERT_TRUE(write_rdtf(revision, output, content_addressed(), diag));
    bins.push_back(addressed("arm3", revision.buffers[0], ".bin"));
    // The first write has no previous JSON: only its own .bin stays; later ones keep one before.
    std::set<std::string> expected = others;
    expected.insert(bins.back());
    if (bins.size() > 1) expected.insert(bins[bins.size() - 2]);
    EXPECT_EQ(names_in(out.path()), expected);
    EXPECT_EQ(std::filesystem::file_size(out / bins.back()), revision.buffers[0].size());
  }
  // The same content again: the same name, and the generation before it is now the same files.
  ASSERT_TRUE(write_rdtf(arm3_revision(conversion->asset, 8), output, content_addressed(), diag));
  std::set<std::string> expected = others;
  expected.insert(bins[2]);
  EXPECT_EQ(names_in(out.path()), expected);
  EXPECT_EQ(testing::read_file(elsewhere / "precious"), "not the writer's");
}

TEST(WriteRdtfContentAddressed, FailedWriteLeavesNoFileItCreatedAndKeepsTheCommittedOutput) {
  testing::TempDir out;
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / "arm3.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  const auto output = out / "arm3.rdtf.gltf";
  ASSERT_TRUE(write_rdtf(conversion->asset, output, content_addressed(), diag));
  const std::string committed = testing::read_file(output);
  const std::string bin = addressed("arm3", conversion->asset.buffers[0], ".bin");

  // The JSON cannot be replaced (a directory took its place): the new revision's .bin goes again.
  const GltfAsset revision = arm3_revision(conversion->asset, 4);
  std::filesystem::rename(output, out / "saved.json");
  std::filesystem::create_directories(output / "occupied");
  Diagnostics write_diag;
  EXPECT_FALSE(write_rdtf(revision, output, content_addressed(), write_diag));
  ASSERT_TRUE(write_diag.contains("WRITE_FAILED"));
  const std::string error = format(write_diag.all().front());
  EXPECT_NE(error.find(output.string()), std::string::npos) << error;
  EXPECT_EQ(names_in(out.path()), (std::set<std::string>{"arm3.rdtf.gltf", "saved.json", bin}));
  EXPECT_EQ(testing::read_file(out / "saved.json"), committed);
}

}  // namespace
}  // namespace rdtf
