// Bad input through the real CLI: each case is a clear error on stderr that names the file and
// the place in it, exit code 2, and no output file.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <functional>

#include "rdtf/glb.h"
#include "rdtf/gltf.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

struct BadCase {
  std::string name;
  // Writes the model into the folder and returns its path.
  std::function<std::filesystem::path(const std::filesystem::path&)> make;
  std::string expected_place;  // A JSON pointer or other locator the error must name.
};

// gtest names each case by its name, not by the bytes of the struct.
void PrintTo(const BadCase& bad, std::ostream* out) { *out << bad.name; }

Json arm3() { return Json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf")); }

// arm3.gltf with `edit` applied, beside a copy of arm3.bin.
std::function<std::filesystem::path(const std::filesystem::path&)> edited_arm3(
    std::function<void(Json&)> edit) {
  return [edit](const std::filesystem::path& folder) {
    Json document = arm3();
    edit(document);
    std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin", folder / "arm3.bin");
    testing::write_file(folder / "model.gltf", document.dump());
    return folder / "model.gltf";
  };
}

std::function<std::filesystem::path(const std::filesystem::path&)> raw_file(std::string name,
                                                                            std::string bytes) {
  return [name, bytes](const std::filesystem::path& folder) {
    testing::write_file(folder / name, bytes);
    return folder / name;
  };
}

std::string glb_bytes() { return testing::read_file(testing::data_dir() / "blender" / "arm3.glb"); }

std::vector<BadCase> cases() {
  std::vector<BadCase> all;
  all.push_back({"TruncatedGlb", raw_file("model.glb", glb_bytes().substr(0, 1000)), "@8"});
  all.push_back({"WrongMagic", raw_file("model.glb", "glTX" + glb_bytes().substr(4)), ""});
  {
    // A stray character in a GLB's JSON chunk (its data starts at file offset 20): said in the
    // chunk and in the file, whose "byte 9" alone pointed into the GLB header (s100err D6).
    std::string bytes = glb_bytes();
    bytes[20 + 8] = ',';
    all.push_back({"GlbJsonChunkBroken", raw_file("model.glb", bytes), "of the JSON chunk, at offset 28 of the file"});
  }
  // A URDF saved with a byte order mark, and an SDF whose plugin names a robotNamespace.
  all.push_back({"UrdfWithABom", raw_file("robot.urdf", "\xEF\xBB\xBF<?xml version=\"1.0\"?>\n<robot name=\"r\"/>\n"),
                 "error JSON_BOM: the file starts with a UTF-8 byte order mark. This is a URDF"});
  all.push_back({"Sdf", raw_file("model.sdf", "<?xml version=\"1.0\"?>\n<sdf version=\"1.6\"><model name=\"m\"><plugin><robotNamespace>/r</robotNamespace></plugin></model></sdf>\n"),
                 "This is an SDF (XML), not glTF"});
  // A URDF given to a command that reads glTF says so, and what reads it (s100err D5).
  all.push_back({"UrdfWhereGltfIsRead",
                 raw_file("robot.urdf", "<?xml version=\"1.0\"?>\n<robot name=\"r\"><link name=\"a\"/></robot>\n"),
                 "This is a URDF (XML), not glTF: convert it with `rdtf import <this file> -o model.gltf`"});
  {
    std::string bytes = glb_bytes();
    bytes[0] = 'G';
    // Not glTF's magic: a damaged GLB by its name, and by its header's version 2 whatever its
    // name (it was read as JSON that failed at line 1).
    all.push_back({"WrongMagicByName", raw_file("model.glb", bytes), "@0: error GLB_INVALID_MAGIC: a GLB"});
    all.push_back({"WrongMagicByVersion", raw_file("model.gltf", bytes), "47 6c 54 46, not 'glTF'"});
  }
  {
    // arm3.glb with its BIN chunk 8 bytes short, and with none.
    const std::string glb = glb_bytes();
    const std::vector<std::uint8_t> bytes(glb.begin(), glb.end());
    Diagnostics ignored;
    const auto chunks = parse_glb(bytes, ignored);
    if (chunks && chunks->bin) {
      const std::span<const std::uint8_t> bin = *chunks->bin;
      const auto shorter = make_glb(chunks->json, bin.subspan(0, bin.size() - 8));
      all.push_back({"GlbBinChunkShorterThanItsBuffer", raw_file("model.glb", std::string(shorter.begin(), shorter.end())),
                     "/buffers/0: error BUFFER_BYTE_LENGTH_MISMATCH: buffer 0 has byteLength " +
                         std::to_string(bin.size()) + ", but the GLB's BIN chunk (its data at byte "});
      const auto without = make_glb(chunks->json, {});
      all.push_back({"GlbWithoutItsBinChunk", raw_file("model.glb", std::string(without.begin(), without.end())),
                     "/buffers/0: error BUFFER_MISSING_GLB_DATA: buffer 0 has no uri, so its " +
                         std::to_string(bin.size()) + " bytes are the GLB's BIN chunk, but the file has no BIN chunk"});
    }
  }
  all.push_back({"InvalidJson", raw_file("model.gltf", "{\"asset\": {\"version\": \"2.0\"},\n \"nodes\": [}"),
                 "line 2"});
  all.push_back({"EmptyFile", raw_file("model.gltf", ""), "empty"});
  // nlohmann stops at a NUL byte: what follows one must not vanish unread.
  all.push_back({"JsonWithANulByte",
                 raw_file("model.gltf", std::string("{\"asset\": {\"version\": \"2.0\"}}\n\0{\"nodes\": [}", 43)),
                 "line 2, column 1 (byte 31): a NUL byte (0x00)"});
  {
    // A GLB whose JSON chunk is padded with NULs instead of spaces (the validator refuses it too).
    const std::string json = arm3().dump();
    const auto glb = make_glb(json + std::string(4 - json.size() % 4, '\0'), {});
    all.push_back({"GlbJsonChunkPaddedWithNuls", raw_file("model.glb", std::string(glb.begin(), glb.end())),
                   "(byte " + std::to_string(json.size() + 1) + " of the JSON chunk, at offset " +
                       std::to_string(20 + json.size()) + " of the file): a NUL byte"});
  }
  // Valid JSON syntax, but beyond a double: placed like any other JSON error (it named no place).
  all.push_back({"NumberBeyondDouble",
                 raw_file("model.gltf", "{\"asset\": {\"version\": \"2.0\"},\n \"nodes\": [{\"translation\": [1e400, 0, 0]}]}"),
                 "error INVALID_JSON: unusable JSON value at line 2, column 29 (byte 59)"});
  // 16-bit texture coordinates starting 2 bytes into their view: aligned to their component size,
  // not to the 4 bytes glTF requires of vertex attributes (the output kept the layout, which the
  // Khronos validator refused).
  all.push_back({"VertexAttributeOffTheFourByteGrid", edited_arm3([](Json& d) {
                   d["accessors"][1]["componentType"] = 5123;
                   d["accessors"][1]["normalized"] = true;
                   d["accessors"][1]["byteOffset"] = 2;
                 }),
                 "/meshes/0/primitives/0/attributes/TEXCOORD_0: error MESH_PRIMITIVE_ACCESSOR_UNALIGNED: mesh 0 "
                 "'Cylinder.001': attribute "
                 "TEXCOORD_0 reads accessor 1, whose elements start at byte 2306 of its buffer"});
  // gltf-pipeline removes the nodes nothing refers to and leaves their parent's children empty:
  // the error names the node and that cause (it said only "the array is empty").
  all.push_back({"EmptyChildrenNameTheNodeAndTheLikelyCause",
                 edited_arm3([](Json& d) { d["nodes"][2]["children"] = Json::array(); }),
                 "/nodes/2/children: error EMPTY_ENTITY: 'forearm': 'children' is an empty array"});
  all.push_back({"AccessorOutOfItsBufferView",
                 edited_arm3([](Json& d) { d["accessors"][0]["byteOffset"] = 4096; }), "/accessors/0"});
  all.push_back({"AbsurdCount",
                 edited_arm3([](Json& d) { d["accessors"][0]["count"] = 2147483648ull; }),
                 "/accessors/0"});
  all.push_back({"MissingBin",
                 [](const std::filesystem::path& folder) {
                   testing::write_file(folder / "model.gltf", arm3().dump());
                   return folder / "model.gltf";
                 },
                 "/buffers/0/uri"});
  all.push_back({"UriClimbsOutOfTheFolder",
                 edited_arm3([](Json& d) { d["buffers"][0]["uri"] = "../arm3.bin"; }), "/buffers/0/uri"});
  all.push_back({"PercentEncodedClimb",
                 edited_arm3([](Json& d) { d["buffers"][0]["uri"] = "%2e%2e/%2e%2e/etc/passwd"; }),
                 "/buffers/0/uri"});
  all.push_back({"AbsoluteUri", edited_arm3([](Json& d) { d["buffers"][0]["uri"] = "/etc/passwd"; }),
                 "/buffers/0/uri"});
  all.push_back({"FileUri",
                 edited_arm3([](Json& d) { d["buffers"][0]["uri"] = "file:///etc/passwd"; }),
                 "/buffers/0/uri"});
  all.push_back({"DotUri", edited_arm3([](Json& d) { d["buffers"][0]["uri"] = "."; }), "/buffers/0/uri"});
  all.push_back({"SymlinkLeavingTheFolder",
                 [](const std::filesystem::path& folder) {
                   std::filesystem::create_directories(folder / "model");
                   std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin",
                                              folder / "outside.bin");
                   std::filesystem::create_symlink(folder / "outside.bin", folder / "model" / "arm3.bin");
                   testing::write_file(folder / "model" / "model.gltf", arm3().dump());
                   return folder / "model" / "model.gltf";
                 },
                 "/buffers/0/uri"});
  all.push_back({"NodeCycle", edited_arm3([](Json& d) { d["nodes"][0]["children"] = Json::array({7}); }),
                 "/nodes/"});
  all.push_back({"NodeWithTwoParents",
                 edited_arm3([](Json& d) { d["nodes"][2]["children"].push_back(4); }), "/nodes/"});
  // Every node scaled by 1e38: nested, a mesh is 1e76 across and its inertia overflows a double.
  // It was written as JSON null with exit 0.
  all.push_back({"InertiaBeyondDouble", edited_arm3([](Json& d) {
                   for (Json& node : d["nodes"]) node["scale"] = {1e38, 1e38, 1e38};
                 }),
                 "is not finite"});
  all.push_back({"NameNotAString", edited_arm3([](Json& d) { d["nodes"][0]["name"] = 12; }), "/nodes/0/name"});
  // The skin loses its last joint, which JOINTS_0 still names: refused where the validator
  // refuses it (it was converted, and the output failed the validator).
  all.push_back({"SkinJointIndexOutOfRange",
                 [](const std::filesystem::path& folder) {
                   Json document = Json::parse(testing::read_file(testing::data_dir() / "blender" / "skinned_arm.gltf"));
                   document["skins"][0]["joints"].erase(2);
                   std::filesystem::copy_file(testing::data_dir() / "blender" / "skinned_arm.bin", folder / "skinned_arm.bin");
                   testing::write_file(folder / "model.gltf", document.dump());
                   return folder / "model.gltf";
                 },
                 "/meshes/0/primitives/0/attributes/JOINTS_0"});
  all.push_back({"IndexOutOfRange",
                 [](const std::filesystem::path& folder) {
                   // One triangle whose third index (5) is past its 3 vertices; data: URI buffer.
                   // Positions (0,0,0), (1,0,0), (0,1,0) as float32, then uint16 indices 0 1 5 + pad.
                   const std::string model = R"({
                     "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
                     "nodes": [{"mesh": 0}],
                     "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
                     "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAUAAAA="}],
                     "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
                     "accessors": [
                       {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
                       {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
                   })";
                   testing::write_file(folder / "model.gltf", model);
                   return folder / "model.gltf";
                 },
                 "/meshes/0/primitives/0/indices"});
  return all;
}

class BadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInput, CliRefusesWithAPlaceAndWritesNothing) {
  testing::TempDir folder;
  const auto model = GetParam().make(folder.path());
  const auto output = folder / "out.gltf";
  const auto run = testing::run_command("'" + testing::cli_path() + "' convert '" + model.string() +
                                        "' -o '" + output.string() + "'");
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find(model.string()), std::string::npos) << run.err;
  EXPECT_NE(run.err.find(GetParam().expected_place), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("error"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(output));
  EXPECT_FALSE(std::filesystem::exists(folder / "arm3.rdtf.gltf"));
  // Nothing new in the folder: no output, no temporary file.
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder.path())) {
    const std::string name = entry.path().filename().string();
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
    EXPECT_EQ(name.find("rdtf"), std::string::npos) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(Cases, BadInput, ::testing::ValuesIn(cases()),
                         [](const auto& case_info) { return case_info.param.name; });

TEST(BadInputLoader, SymlinkInsideTheFolderIsFollowed) {
  testing::TempDir folder;
  std::filesystem::create_directories(folder / "data");
  std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin", folder / "data" / "real.bin");
  std::filesystem::create_symlink("data/real.bin", folder / "arm3.bin");
  testing::write_file(folder / "model.gltf", arm3().dump());
  Diagnostics diag;
  EXPECT_TRUE(load_gltf(folder / "model.gltf", LoadLimits{}, diag)) << format(diag.all().front());
}

TEST(BadInputLoader, UriWithSpacesAndPercentEscapesLoads) {
  testing::TempDir folder;
  std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin", folder / "my arm+1.bin");
  Json document = arm3();
  document["buffers"][0]["uri"] = "my%20arm+1.bin";
  testing::write_file(folder / "model.gltf", document.dump());
  Diagnostics diag;
  EXPECT_TRUE(load_gltf(folder / "model.gltf", LoadLimits{}, diag))
      << (diag.all().empty() ? "" : format(diag.all().front()));
}

TEST(BadInputLoader, FileOverTheSizeLimitIsRefusedBeforeReading) {
  LoadLimits limits;
  limits.max_file_bytes = 1000;
  Diagnostics diag;
  EXPECT_FALSE(load_gltf(testing::data_dir() / "blender" / "arm3.gltf", limits, diag));
  ASSERT_TRUE(diag.has_errors());
  EXPECT_NE(diag.all().front().message.find("over the limit"), std::string::npos);
}

TEST(BadInputLoader, FifoIsRefusedWithoutBlocking) {
  testing::TempDir folder;
  ASSERT_EQ(::mkfifo((folder / "arm3.bin").c_str(), 0600), 0);
  testing::write_file(folder / "model.gltf", arm3().dump());
  Diagnostics diag;
  EXPECT_FALSE(load_gltf(folder / "model.gltf", LoadLimits{}, diag));
  ASSERT_TRUE(diag.has_errors());
  EXPECT_NE(format(diag.all().front()).find("FIFO"), std::string::npos) << format(diag.all().front());
}

}  // namespace
}  // namespace rdtf
