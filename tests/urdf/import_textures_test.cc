// The base colour images of COLLADA and OBJ meshes (docs/urdf.md, "Textures"): the image's bytes
// in the glTF buffer, each corner's texture coordinate with v from the image's top (glTF) where
// COLLADA and OBJ count it from the bottom, vertices split along seams without opening the surface,
// and a warning naming the texture where it cannot be carried. The files are written here, so every
// expected coordinate follows from the corner's position.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>

#include "rdtf/write.h"

#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using namespace urdf_test;
namespace fs = std::filesystem;

// A unit cube centred at the origin, each face textured with its own unit square of the image row:
// the face with outward normal along axis k (sign s) is face f = 2k + (s > 0), and a corner of it
// at position p has (u, v) = ((f + a + 0.5) / 8, b + 0.5) in COLLADA's convention (v up), a and
// b the corner's two other coordinates in axis order (eighths: short decimals, exact in float). Every corner of a face is written with its
// own texture coordinate, so each position has three (a seam along every edge).
struct CubeFace {
  int axis;
  double sign;
};
const CubeFace kFaces[6] = {{0, -1}, {0, 1}, {1, -1}, {1, 1}, {2, -1}, {2, 1}};

std::array<double, 2> cube_uv(const Eigen::Vector3d& p, int face) {
  const int k = kFaces[face].axis;
  const int a = k == 0 ? 1 : 0, b = k == 2 ? 1 : 2;
  return {(face + p[a] + 0.5) / 8.0, p[b] + 0.5};
}

// The cube's 12 outward triangles as COLLADA text: 8 positions, a texture coordinate per corner.
std::string textured_cube_collada(const std::string& image) {
  std::vector<Eigen::Vector3d> corners;
  for (int i = 0; i < 8; ++i) corners.emplace_back((i & 1) ? 0.5 : -0.5, (i & 2) ? 0.5 : -0.5, (i & 4) ? 0.5 : -0.5);
  std::string positions, uvs, p;
  const auto text = [](double value) { return Json(value).dump(); };
  for (const auto& c : corners) positions += text(c.x()) + " " + text(c.y()) + " " + text(c.z()) + " ";
  int uv_count = 0;
  for (int f = 0; f < 6; ++f) {
    const int k = kFaces[f].axis;
    const int a = k == 0 ? 1 : 0, b = k == 2 ? 1 : 2;
    // The face's corners in counter-clockwise order seen from outside.
    std::vector<int> quad;
    for (const auto& [da, db] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
      Eigen::Vector3d q;
      q[k] = kFaces[f].sign * 0.5;
      q[a] = da * 0.5;
      q[b] = db * 0.5;
      const int index = (q.x() > 0 ? 1 : 0) | (q.y() > 0 ? 2 : 0) | (q.z() > 0 ? 4 : 0);
      quad.push_back(index);
    }
    // (a, b, normal) is right-handed for k = 0 and 2 and left-handed for k = 1: there the order
    // that faces outward for +1 is reversed.
    const bool reverse = (kFaces[f].sign < 0) != (k == 1);
    if (reverse) std::reverse(quad.begin(), quad.end());
    for (const int t : {0, 1, 2, 0, 2, 3}) {
      const auto uv = cube_uv(corners[static_cast<std::size_t>(quad[static_cast<std::size_t>(t)])], f);
      uvs += text(uv[0]) + " " + text(uv[1]) + " ";
      p += std::to_string(quad[static_cast<std::size_t>(t)]) + " " + std::to_string(uv_count++) + " ";
    }
  }
  return R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
<library_images><image id="img" name="img"><init_from>)" + image + R"(</init_from></image></library_images>
<library_effects><effect id="paint-effect"><profile_COMMON>
<newparam sid="img-surface"><surface type="2D"><init_from>img</init_from></surface></newparam>
<newparam sid="img-sampler"><sampler2D><source>img-surface</source></sampler2D></newparam>
<technique sid="common"><lambert><diffuse><texture texture="img-sampler" texcoord="UVMap"/></diffuse></lambert></technique>
</profile_COMMON></effect></library_effects>
<library_materials><material id="paint-material" name="paint"><instance_effect url="#paint-effect"/></material></library_materials>
<library_geometries><geometry id="cube-mesh" name="cube"><mesh>
<source id="cube-positions"><float_array id="cube-positions-array" count="24">)" + positions + R"(</float_array>
<technique_common><accessor source="#cube-positions-array" count="8" stride="3"><param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
<source id="cube-uv"><float_array id="cube-uv-array" count="72">)" + uvs + R"(</float_array>
<technique_common><accessor source="#cube-uv-array" count="36" stride="2"><param name="S" type="float"/><param name="T" type="float"/></accessor></technique_common></source>
<vertices id="cube-vertices"><input semantic="POSITION" source="#cube-positions"/></vertices>
<triangles material="paint-material" count="12"><input semantic="VERTEX" source="#cube-vertices" offset="0"/><input semantic="TEXCOORD" source="#cube-uv" offset="1" set="0"/><p>)" + p + R"(</p></triangles>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="Scene" name="Scene"><node id="n" name="n" type="NODE">
<instance_geometry url="#cube-mesh"><bind_material><technique_common><instance_material symbol="paint-material" target="#paint-material"><bind_vertex_input semantic="UVMap" input_semantic="TEXCOORD" input_set="0"/></instance_material></technique_common></bind_material></instance_geometry>
</node></visual_scene></library_visual_scenes>
<scene><instance_visual_scene url="#Scene"/></scene>
</COLLADA>
)";
}

const std::string kRobot =
    "<robot name=\"r\">\n<link name=\"a\">\n<visual><geometry><mesh filename=\"cube.dae\"/></geometry>"
    "<material name=\"blue\"><color rgba=\"0 0 1 1\"/></material></visual>\n</link>\n</robot>\n";

std::string tutorial_png() {
  return testing::read_file(testing::data_dir() / "urdf" / "urdf_tutorial" / "meshes" / "l_finger_tip_color.png");
}

// The float values of an accessor of the import's own buffer (tightly packed float32).
std::vector<float> floats_of(const Conversion& conversion, std::size_t accessor_index, int components) {
  const Json& document = conversion.asset.document;
  const Json& accessor = document["accessors"][accessor_index];
  const Json& view = document["bufferViews"][accessor["bufferView"].get<std::size_t>()];
  const auto& bytes = conversion.asset.buffers.at(0);
  std::vector<float> out(accessor["count"].get<std::size_t>() * static_cast<std::size_t>(components));
  std::memcpy(out.data(), bytes.data() + view.value("byteOffset", std::size_t{0}), out.size() * 4);
  return out;
}

// The textured cube: the image in the buffer byte for byte, a white colour factor, and every
// corner's coordinate exactly the one its position and face give, with v turned to glTF's (1 - v);
// its 6 x 4 corners are separate vertices, and its mass is still the closed cube's, 1000 kg.
TEST(UrdfImportTextures, ColladaCoordinatesAndImageAreCarried) {
  TempDir dir;
  const std::string png = tutorial_png();
  testing::write_file(dir / "paint.png", png);
  testing::write_file(dir / "cube.dae", textured_cube_collada("paint.png"));
  testing::write_file(dir / "robot.urdf", kRobot);
  Diagnostics diag;
  const Conversion conversion = import_ok(dir / "robot.urdf", diag);
  for (const Diagnostic& d : diag.all()) EXPECT_NE(d.severity, Severity::kError) << format(d);
  EXPECT_EQ(find_code(diag, "URDF_TEXTURE_SKIPPED"), nullptr);
  EXPECT_EQ(conversion.robot.links[0].inertial.mass, 1000.0);

  const Json& document = conversion.asset.document;
  ASSERT_EQ(document["images"].size(), 1u);
  const Json& image = document["images"][0];
  EXPECT_EQ(image["mimeType"], "image/png");
  EXPECT_EQ(image["name"], "paint.png");
  const Json& image_view = document["bufferViews"][image["bufferView"].get<std::size_t>()];
  const auto& buffer = conversion.asset.buffers.at(0);
  ASSERT_EQ(image_view["byteLength"].get<std::size_t>(), png.size());
  const std::ptrdiff_t image_at = image_view.value("byteOffset", std::ptrdiff_t{0});
  EXPECT_EQ(std::memcmp(png.data(), buffer.data() + image_at, png.size()), 0);

  ASSERT_EQ(document["meshes"][0]["primitives"].size(), 1u);
  const Json& primitive = document["meshes"][0]["primitives"][0];
  const Json& material = document["materials"][primitive["material"].get<std::size_t>()];
  EXPECT_EQ(material["pbrMetallicRoughness"]["baseColorFactor"].dump(), "[1.0,1.0,1.0,1.0]");
  EXPECT_EQ(material["pbrMetallicRoughness"]["baseColorTexture"]["index"], 0);
  EXPECT_EQ(document["textures"][0]["source"], 0);

  const auto positions = floats_of(conversion, primitive["attributes"]["POSITION"].get<std::size_t>(), 3);
  const auto uvs = floats_of(conversion, primitive["attributes"]["TEXCOORD_0"].get<std::size_t>(), 2);
  EXPECT_EQ(positions.size() / 3, 24u);
  ASSERT_EQ(uvs.size() / 2, positions.size() / 3);
  const Json& indices = document["accessors"][primitive["indices"].get<std::size_t>()];
  const Json& index_view = document["bufferViews"][indices["bufferView"].get<std::size_t>()];
  std::vector<std::uint32_t> triangles(indices["count"].get<std::size_t>());
  std::memcpy(triangles.data(), buffer.data() + index_view.value("byteOffset", std::size_t{0}), triangles.size() * 4);
  ASSERT_EQ(triangles.size(), 36u);
  // The mesh is in the link's frame, URDF's axes (the robot's root node turns them to glTF's).
  for (std::size_t t = 0; t < triangles.size(); t += 3) {
    std::array<Eigen::Vector3d, 3> p;
    for (int k = 0; k < 3; ++k) {
      const std::size_t v = triangles[t + static_cast<std::size_t>(k)];
      p[static_cast<std::size_t>(k)] = Eigen::Vector3d(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
    }
    const Eigen::Vector3d normal = (p[1] - p[0]).cross(p[2] - p[0]);
    int axis = 0;
    normal.cwiseAbs().maxCoeff(&axis);
    const int face = 2 * axis + (normal[axis] > 0 ? 1 : 0);
    for (int k = 0; k < 3; ++k) {
      const std::size_t v = triangles[t + static_cast<std::size_t>(k)];
      const auto uv = cube_uv(p[static_cast<std::size_t>(k)], face);
      EXPECT_EQ(uvs[2 * v], static_cast<float>(uv[0])) << "triangle " << t / 3 << " corner " << k;
      EXPECT_EQ(uvs[2 * v + 1], 1.0f - static_cast<float>(uv[1])) << "triangle " << t / 3 << " corner " << k;
    }
  }
  Diagnostics write_diag;
  ASSERT_TRUE(write_rdtf(conversion.asset, dir / "out.gltf", OutputFormat::kGltf, write_diag));
  const auto report = testing::khronos_report(dir / "out.gltf");
  EXPECT_EQ(report["issues"]["numErrors"].get<int>(), 0) << report["issues"].dump(1);
}

// An OBJ's map_Kd: the same image and coordinates (vt, v up), the Kd colour replaced by white.
TEST(UrdfImportTextures, ObjMapKdIsCarried) {
  TempDir dir;
  testing::write_file(dir / "paint.png", tutorial_png());
  testing::write_file(dir / "cube.mtl", "newmtl paint\nKd 0.2 0.3 0.4\nmap_Kd paint.png\n");
  std::string obj = "mtllib cube.mtl\n";
  for (int i = 0; i < 8; ++i) {
    obj += std::string("v ") + ((i & 1) ? "1" : "0") + " " + ((i & 2) ? "1" : "0") + " " + ((i & 4) ? "1" : "0") + "\n";
  }
  obj += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.25 0.75\nusemtl paint\n";
  // Each face's corners take vt 1..4; the top face's first corner takes vt 5.
  obj += "f 5/5 6/2 8/3 7/4\nf 1/1 3/2 4/3 2/4\nf 1/1 2/2 6/3 5/4\nf 3/1 7/2 8/3 4/4\nf 1/1 5/2 7/3 3/4\nf 2/1 4/2 8/3 6/4\n";
  testing::write_file(dir / "cube.obj", obj);
  testing::write_file(dir / "robot.urdf", "<robot name=\"r\">\n<link name=\"a\">\n<visual><geometry><mesh filename=\"cube.obj\"/>"
                                          "</geometry></visual>\n</link>\n</robot>\n");
  Diagnostics diag;
  const Conversion conversion = import_ok(dir / "robot.urdf", diag);
  EXPECT_EQ(find_code(diag, "URDF_TEXTURE_SKIPPED"), nullptr);
  EXPECT_EQ(conversion.robot.links[0].inertial.mass, 1000.0);
  const Json& document = conversion.asset.document;
  const Json& primitive = document["meshes"][0]["primitives"][0];
  const Json& material = document["materials"][primitive["material"].get<std::size_t>()];
  EXPECT_EQ(material["pbrMetallicRoughness"]["baseColorFactor"].dump(), "[1.0,1.0,1.0,1.0]");
  const auto positions = floats_of(conversion, primitive["attributes"]["POSITION"].get<std::size_t>(), 3);
  const auto uvs = floats_of(conversion, primitive["attributes"]["TEXCOORD_0"].get<std::size_t>(), 2);
  // The corner at (0, 0, 1) of the top face carries vt 5 = (0.25, 0.75): (0.25, 0.25) in glTF;
  // the same position elsewhere carries vt 4 = (0, 1) and vt 2 = (1, 0): (0, 0) and (1, 1).
  std::map<std::pair<float, float>, int> at_corner;
  for (std::size_t v = 0; v < positions.size() / 3; ++v) {
    const Eigen::Vector3d p(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
    if (p == Eigen::Vector3d(0, 0, 1)) ++at_corner[{uvs[2 * v], uvs[2 * v + 1]}];
  }
  EXPECT_EQ(at_corner, (std::map<std::pair<float, float>, int>{{{0.0f, 0.0f}, 1}, {{0.25f, 0.25f}, 1}, {{1.0f, 1.0f}, 1}}));
}

// Where the texture cannot be carried the part keeps its material's colour and a warning names
// the mesh, the texture and why: not there (with where it was looked for), not PNG or JPEG (a file
// of the user's named as a texture gets nothing of it into the model), no texture coordinates.
TEST(UrdfImportTextures, ATextureThatCannotBeCarriedIsNamed) {
  struct Case {
    const char* name;
    std::function<void(const fs::path&)> setup;
    const char* says;
  };
  const std::vector<Case> cases = {
      {"missing", [](const fs::path&) {}, "image 'paint.png' not found (looked for "},
      {"not an image", [](const fs::path& dir) { testing::write_file(dir / "paint.png", "secret: 1234\n"); },
       "is not a PNG or JPEG image"},
      {"a folder", [](const fs::path& dir) { fs::create_directory(dir / "paint.png"); }, "not a file rdtf reads"},
      // An image outside the folder the URDF and the mesh share, say the user's photos.
      {"outside",
       [](const fs::path& dir) {
         fs::create_directories(dir / "photos");
         testing::write_file(dir / "photos" / "paint.png", tutorial_png());
         fs::create_directories(dir / "robot" / "meshes");
       },
       "the folder the URDF and the mesh file share (an image elsewhere is not read)"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    TempDir dir;
    c.setup(dir.path());
    const bool outside = std::string(c.name) == "outside";
    // There the robot is in robot/ and its mesh in robot/meshes/, naming ../../photos/paint.png.
    const fs::path folder = outside ? dir / "robot" : dir.path();
    const fs::path mesh_folder = outside ? folder / "meshes" : folder;
    testing::write_file(mesh_folder / "cube.dae", textured_cube_collada(outside ? "../../photos/paint.png" : "paint.png"));
    testing::write_file(folder / "robot.urdf", outside ? "<robot name=\"r\">\n<link name=\"a\">\n<visual><geometry><mesh "
                                                        "filename=\"meshes/cube.dae\"/></geometry></visual>\n</link>\n</robot>\n"
                                                      : kRobot);
    Diagnostics diag;
    const Conversion conversion = import_ok(folder / "robot.urdf", diag);
    EXPECT_EQ(conversion.robot.links[0].inertial.mass, 1000.0);
    const Diagnostic* d = find_code(diag, "URDF_TEXTURE_SKIPPED");
    ASSERT_NE(d, nullptr);
    EXPECT_EQ(d->severity, Severity::kWarning);
    EXPECT_EQ(d->pointer, "/robot/link[@name='a']/visual[1]");
    EXPECT_NE(d->message.find((mesh_folder / "cube.dae").string()), std::string::npos) << d->message;
    EXPECT_NE(d->message.find(std::string("texture '") + (outside ? "../../photos/" : "") + "paint.png' of material 'paint'"),
              std::string::npos)
        << d->message;
    EXPECT_NE(d->message.find(c.says), std::string::npos) << d->message;
    const Json& document = conversion.asset.document;
    EXPECT_FALSE(document.contains("images"));
    const Json& primitive = document["meshes"][0]["primitives"][0];
    EXPECT_FALSE(primitive["attributes"].contains("TEXCOORD_0"));
    const Json& material = document["materials"][primitive["material"].get<std::size_t>()];
    EXPECT_FALSE(material["pbrMetallicRoughness"].contains("baseColorTexture"));
  }
  // No texture coordinates: the OBJ's faces name none.
  TempDir dir;
  testing::write_file(dir / "paint.png", tutorial_png());
  testing::write_file(dir / "tri.mtl", "newmtl paint\nKd 0.2 0.3 0.4\nmap_Kd paint.png\n");
  testing::write_file(dir / "tri.obj", "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl paint\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  testing::write_file(dir / "robot.urdf", "<robot name=\"r\">\n<link name=\"a\">\n<visual><geometry><mesh filename=\"tri.obj\"/>"
                                          "</geometry></visual>\n</link>\n</robot>\n");
  Diagnostics diag;
  const Conversion conversion = import_ok(dir / "robot.urdf", diag);
  const Diagnostic* d = find_code(diag, "URDF_TEXTURE_SKIPPED");
  ASSERT_NE(d, nullptr);
  EXPECT_NE(d->message.find("the mesh has no texture coordinates for it"), std::string::npos) << d->message;
  const Json& document = conversion.asset.document;
  const Json& material = document["materials"][document["meshes"][0]["primitives"][0]["material"].get<std::size_t>()];
  EXPECT_EQ(material["pbrMetallicRoughness"]["baseColorFactor"].dump(), "[0.2,0.3,0.4,1.0]");
}

// The tutorial's PR2 fingers, textured: each image in the buffer byte for byte, and every triangle
// corner's texture coordinate where Blender's own COLLADA importer puts it (blender_uv.py matches
// Blender's 6,000 and 3,000 corners one to one with those of the import read back by Blender's glTF
// importer, by coordinate and distance from the mesh's centre; the v of every one turned, as a
// missing 1 - v would leave it, matches none). Blender is a requirement of the tests.
TEST(UrdfImportTextures, TheTutorialsFingersAreTexturedAsBlenderReadsThem) {
  const fs::path meshes = testing::data_dir() / "urdf" / "urdf_tutorial" / "meshes";
  Diagnostics diag;
  const Conversion conversion = import_ok(meshes.parent_path() / "05-visual.urdf", diag);
  EXPECT_EQ(find_code(diag, "URDF_TEXTURE_SKIPPED"), nullptr);
  const Json& document = conversion.asset.document;
  ASSERT_EQ(document["images"].size(), 2u);
  for (const Json& image : document["images"]) {
    const std::string png = testing::read_file(meshes / image["name"].get<std::string>());
    const Json& view = document["bufferViews"][image["bufferView"].get<std::size_t>()];
    ASSERT_EQ(view["byteLength"].get<std::size_t>(), png.size()) << image.dump();
    EXPECT_EQ(std::memcmp(png.data(), conversion.asset.buffers.at(0).data() + view.value("byteOffset", std::size_t{0}), png.size()), 0);
  }
  TempDir dir;
  Diagnostics write_diag;
  ASSERT_TRUE(write_rdtf(conversion.asset, dir / "r2d2.gltf", OutputFormat::kGltf, write_diag));
  const auto report_path = dir / "report.json";
  const auto result = testing::run_command(
      "blender -b --factory-startup --python '" + (meshes / "blender_uv.py").string() + "' -- '" + report_path.string() +
      "' '" + (dir / "r2d2.gltf").string() + "' '" + (meshes / "l_finger.dae").string() + ":left_gripper_visual' '" +
      (meshes / "l_finger_tip.dae").string() + ":left_tip_visual'");
  ASSERT_EQ(result.exit_code, 0) << "Blender (Debian package blender) must run for this test:\n" << result.out << result.err;
  const Json report = Json::parse(testing::read_file(report_path));
  for (const auto& [file, corners] : {std::pair{"l_finger.dae", 6000}, {"l_finger_tip.dae", 3000}}) {
    SCOPED_TRACE(file);
    const Json& entry = report.at((meshes / file).string());
    EXPECT_EQ(entry["blender_corners"], corners);
    EXPECT_EQ(entry["rdtf_corners"], corners);
    EXPECT_EQ(entry["unmatched"], 0);
    EXPECT_EQ(entry["rdtf_images"], entry["blender_images"]);
    EXPECT_EQ(entry["rdtf_images"].size(), 1u);
  }
  const auto khronos = testing::khronos_report(dir / "r2d2.gltf");
  EXPECT_EQ(khronos["issues"]["numErrors"].get<int>(), 0) << khronos["issues"].dump(1);
}

}  // namespace
}  // namespace rdtf
