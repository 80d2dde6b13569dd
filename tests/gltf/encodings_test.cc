// Instanced meshes, encoders' mesh carrier nodes and unusable compressed data, on small models
// made here. Closed forms: a 0.1 m cube of 1000 kg/m^3 weighs 1 kg; a scaled copy weighs the
// product of its scales.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "../../fuzz/fuzz_pipeline.h"
#include "rdtf/convert.h"
#include "rdtf/dynamics.h"
#include "rdtf/glb.h"
#include "rdtf/urdf.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

constexpr double kExact = 1e-12;

std::vector<std::uint8_t> floats_and_shorts(const std::vector<float>& floats, const std::vector<std::uint16_t>& shorts) {
  std::vector<std::uint8_t> bin(floats.size() * 4 + shorts.size() * 2);
  std::memcpy(bin.data(), floats.data(), floats.size() * 4);
  std::memcpy(bin.data() + floats.size() * 4, shorts.data(), shorts.size() * 2);
  while (bin.size() % 4 != 0) bin.push_back(0);
  return bin;
}

// A 0.1 m cube (mesh 0: 8 vertices, 12 triangles wound outwards) and `extra` floats after it
// (accessors from 2 on, each `extra_accessors` entry's offset counted in floats from there).
struct Model {
  Json document;
  std::vector<std::uint8_t> bin;
};

Model cube_model(const std::vector<float>& extra, const Json& extra_accessors) {
  std::vector<float> floats;
  for (int c = 0; c < 8; ++c) {
    floats.push_back(c & 1 ? 0.05f : -0.05f);
    floats.push_back(c & 2 ? 0.05f : -0.05f);
    floats.push_back(c & 4 ? 0.05f : -0.05f);
  }
  std::vector<std::uint16_t> shorts;
  const int quads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (const auto& q : quads) {
    for (int v : {q[0], q[1], q[2], q[0], q[2], q[3]}) shorts.push_back(static_cast<std::uint16_t>(v));
  }
  Model model;
  model.bin = floats_and_shorts(floats, shorts);
  const std::size_t extra_at = model.bin.size();
  model.bin.resize(extra_at + extra.size() * 4);
  if (!extra.empty()) std::memcpy(model.bin.data() + extra_at, extra.data(), extra.size() * 4);
  Json& d = model.document;
  d["asset"] = {{"version", "2.0"}};
  d["scene"] = 0;
  d["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}};
  d["accessors"] = {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"},
                     {"min", {-0.05, -0.05, -0.05}}, {"max", {0.05, 0.05, 0.05}}},
                    {{"bufferView", 1}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}}};
  d["bufferViews"] = {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}, {"target", 34962}},
                      {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 72}, {"target", 34963}}};
  if (!extra.empty()) {
    d["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", extra_at}, {"byteLength", extra.size() * 4}});
    for (const Json& a : extra_accessors) {
      d["accessors"].push_back({{"bufferView", 2}, {"byteOffset", a["offset"].get<int>() * 4}, {"componentType", 5126},
                                {"count", a["count"]}, {"type", a["type"]}});
    }
  }
  d["buffers"] = {{{"byteLength", model.bin.size()}}};
  return model;
}

std::optional<Conversion> convert_model(const Model& model, Diagnostics& diag, LoadLimits limits = {}) {
  const auto glb = make_glb(model.document.dump(), model.bin);
  auto asset = load_gltf_from_memory(glb, "model.glb", "", limits, diag);
  if (!asset) return std::nullopt;
  return convert(std::move(*asset), ConvertOptions{}, diag);
}

Conversion convert_ok(const Model& model) {
  Diagnostics diag;
  auto conversion = convert_model(model, diag);
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError) ADD_FAILURE() << format(d);
  }
  if (!conversion) throw std::runtime_error("did not convert");
  return std::move(*conversion);
}

void expect_same_mass(const MassProperties& got, const MassProperties& want) {
  EXPECT_NEAR(got.mass, want.mass, kExact * want.mass);
  EXPECT_TRUE(got.center_of_mass.isApprox(want.center_of_mass, kExact)) << got.center_of_mass.transpose();
  EXPECT_TRUE(got.inertia.isApprox(want.inertia, kExact)) << got.inertia;
}

// Three instances: at the origin; 0.3 m along x turned 90 degrees about z and stretched twice
// along its x; 0.5 m up, half as tall. Not required (as Blender writes it), still counted.
TEST(GpuInstancing, EveryInstanceIsASolidOfTheLink) {
  const float s = std::sqrt(0.5f);
  Model instanced = cube_model({0, 0, 0, 0.3f, 0, 0, 0, 0.5f, 0,          // TRANSLATION
                                0, 0, 0, 1, 0, 0, s, s, 0, 0, 0, 1,       // ROTATION
                                1, 1, 1, 2, 1, 1, 1, 1, 0.5f},            // SCALE
                               Json::array({{{"offset", 0}, {"count", 3}, {"type", "VEC3"}},
                                            {{"offset", 9}, {"count", 3}, {"type", "VEC4"}},
                                            {{"offset", 21}, {"count", 3}, {"type", "VEC3"}}}));
  instanced.document["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
  instanced.document["scenes"] = {{{"nodes", {0}}}};
  instanced.document["nodes"] = {
      {{"name", "base"}, {"children", {1}}},
      {{"name", "parts"}, {"mesh", 0},
       {"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", {{"TRANSLATION", 2}, {"ROTATION", 3}, {"SCALE", 4}}}}}}}}};
  // The twin: one node per instance, with the instance's transform.
  Model nodes = cube_model({}, Json::array());
  nodes.document["scenes"] = {{{"nodes", {0}}}};
  nodes.document["nodes"] = {
      {{"name", "base"}, {"children", {1, 2, 3}}},
      {{"name", "part0"}, {"mesh", 0}},
      {{"name", "part1"}, {"mesh", 0}, {"translation", {0.3f, 0, 0}}, {"rotation", {0, 0, s, s}}, {"scale", {2, 1, 1}}},
      {{"name", "part2"}, {"mesh", 0}, {"translation", {0, 0.5f, 0}}, {"scale", {1, 1, 0.5f}}}};

  const Conversion a = convert_ok(instanced);
  const Conversion b = convert_ok(nodes);
  ASSERT_EQ(a.robot.links.size(), 1u);
  ASSERT_EQ(b.robot.links.size(), 1u);
  const double cube = 1000.0 * std::pow(0.1f, 3.0);  // The float32 cube of 0.1 m, 1000 kg/m^3.
  EXPECT_NEAR(a.robot.links[0].inertial.mass, 3.5 * cube, 1e-6 * cube);
  EXPECT_EQ(a.robot.links[0].meshes.size(), 3u);
  expect_same_mass(a.robot.links[0].inertial, b.robot.links[0].inertial);
  // The gate's bounds hold every instance where it is drawn, as the twin's three nodes: they
  // held the first instance only (0.05 m about the origin), so the centre of mass, at (0.17,
  // 0.07, 0) m, lay outside them and rdtf validate refused the model.
  const auto bounds_a = link_geometry_bounds(a.asset, a.robot);
  const auto bounds_b = link_geometry_bounds(b.asset, b.robot);
  ASSERT_TRUE(bounds_a[0] && bounds_b[0]);
  EXPECT_TRUE(bounds_a[0]->min().isApprox(bounds_b[0]->min(), 1e-7)) << bounds_a[0]->min().transpose();
  EXPECT_TRUE(bounds_a[0]->max().isApprox(bounds_b[0]->max(), 1e-7)) << bounds_a[0]->max().transpose();
  // The part stretched twice along its x and turned 90 degrees about z reaches 0.1 m along y.
  EXPECT_NEAR(bounds_a[0]->max().y(), 0.55, 1e-7);
  EXPECT_NEAR(bounds_a[0]->max().x(), 0.35, 1e-7);
  // The URDF's mesh of the link holds every instance too, as the twin's does: it held the first
  // one only, beside an <inertial> of all three (helper sweep s70geo D1).
  Diagnostics diag;
  const auto urdf_a = export_urdf(a, UrdfOptions{}, diag);
  const auto urdf_b = export_urdf(b, UrdfOptions{}, diag);
  ASSERT_TRUE(urdf_a && urdf_b) << diag.all().size();
  ASSERT_EQ(urdf_a->meshes.size(), 1u);
  ASSERT_EQ(urdf_b->meshes.size(), 1u);
  std::string why;
  const auto stl_a = parse_stl(urdf_a->meshes[0].bytes, why);
  const auto stl_b = parse_stl(urdf_b->meshes[0].bytes, why);
  ASSERT_TRUE(stl_a && stl_b) << why;
  EXPECT_EQ(stl_a->triangles.size(), 3 * 12u);
  EXPECT_EQ(stl_a->triangles.size(), stl_b->triangles.size());
  Eigen::AlignedBox3d box_a, box_b;
  for (const Eigen::Vector3d& p : stl_a->positions) box_a.extend(p);
  for (const Eigen::Vector3d& p : stl_b->positions) box_b.extend(p);
  EXPECT_TRUE(box_a.min().isApprox(box_b.min(), 1e-6)) << box_a.min().transpose();
  EXPECT_TRUE(box_a.max().isApprox(box_b.max(), 1e-6)) << box_a.max().transpose();
}

// What the extension leaves undefined or the file gets wrong is said, never guessed silently
// (helper sweep s70geo D3, D4): a quaternion of length 2 (normalized, it placed the instance turned
// 180 degrees) and an instance scaled to nothing (its mass vanished without a word, where a node's
// scale of 0 is warned of).
TEST(GpuInstancing, WhatCannotPlaceAnInstanceIsSaid) {
  Model model = cube_model({0, 0, 2, 0, 0, 0, 0, 1}, Json::array({{{"offset", 0}, {"count", 2}, {"type", "VEC4"}}}));
  model.document["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
  model.document["scenes"] = {{{"nodes", {0}}}};
  model.document["nodes"] = {{{"name", "base"}, {"mesh", 0},
                              {"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", {{"ROTATION", 2}}}}}}}}};
  Diagnostics diag;
  EXPECT_FALSE(convert_model(model, diag));
  ASSERT_TRUE(diag.has_errors());
  bool named = false;
  for (const Diagnostic& d : diag.all()) {
    if (d.code != "INSTANCING_INVALID") continue;
    named = true;
    EXPECT_EQ(d.pointer, "/nodes/0/extensions/EXT_mesh_gpu_instancing/attributes/ROTATION");
    EXPECT_NE(d.message.find("ROTATION element 0 has length 2; each must be a unit quaternion"), std::string::npos)
        << d.message;
  }
  EXPECT_TRUE(named);

  Model flat = cube_model({1, 1, 1, 1, 0, 1}, Json::array({{{"offset", 0}, {"count", 2}, {"type", "VEC3"}}}));
  flat.document["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
  flat.document["scenes"] = {{{"nodes", {0}}}};
  flat.document["nodes"] = {{{"name", "base"}, {"mesh", 0},
                             {"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", {{"SCALE", 2}}}}}}}}};
  Diagnostics flat_diag;
  const auto c = convert_model(flat, flat_diag);
  ASSERT_TRUE(c);
  const double cube = 1000.0 * std::pow(0.1f, 3.0);
  EXPECT_NEAR(c->robot.links[0].inertial.mass, cube, 1e-6 * cube);
  bool warned = false;
  for (const Diagnostic& d : flat_diag.all()) {
    if (d.code == "MESH_SCALED_TO_NOTHING" && d.message.find("instance 1 of mesh node") != std::string::npos) warned = true;
  }
  EXPECT_TRUE(warned);
}

// A skinned mesh is placed by its bones, and where instances of it go is undefined: one copy was
// counted, silently (helper sweep s70geo D3). Refused, naming the node.
TEST(GpuInstancing, ASkinnedMeshInstancedIsRefused) {
  testing::TempDir dir;
  Json doc = Json::parse(testing::read_file(testing::data_dir() / "blender" / "skinned_arm.gltf"));
  testing::write_file(dir.path() / "skinned_arm.bin", testing::read_file(testing::data_dir() / "blender" / "skinned_arm.bin"));
  const float offsets[6] = {0, 0, 0, 2, 0, 0};
  std::vector<std::uint8_t> bytes(sizeof offsets);
  std::memcpy(bytes.data(), offsets, sizeof offsets);
  doc["buffers"].push_back({{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + testing::base64(bytes)}});
  doc["bufferViews"].push_back({{"buffer", doc["buffers"].size() - 1}, {"byteLength", bytes.size()}});
  doc["accessors"].push_back({{"bufferView", doc["bufferViews"].size() - 1}, {"componentType", 5126}, {"count", 2}, {"type", "VEC3"}});
  std::size_t skinned = doc["nodes"].size();
  for (std::size_t n = 0; n < doc["nodes"].size(); ++n) {
    if (doc["nodes"][n].contains("skin")) skinned = n;
  }
  ASSERT_LT(skinned, doc["nodes"].size());
  doc["nodes"][skinned]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"] = doc["accessors"].size() - 1;
  doc["extensionsUsed"].push_back("EXT_mesh_gpu_instancing");
  testing::write_file(dir.path() / "skinned_arm.gltf", doc.dump());
  Diagnostics diag;
  EXPECT_FALSE(convert_file(dir.path() / "skinned_arm.gltf", {}, diag));
  bool named = false;
  for (const Diagnostic& d : diag.all()) {
    if (d.code != "INSTANCING_INVALID") continue;
    named = true;
    EXPECT_EQ(d.pointer, "/nodes/" + std::to_string(skinned) + "/extensions/EXT_mesh_gpu_instancing");
    EXPECT_NE(d.message.find("is skinned and instanced"), std::string::npos) << d.message;
  }
  EXPECT_TRUE(named);
}

// On a link node that also has children (Blender's layout), the instances move with the mesh to
// the node completion splits off.
TEST(GpuInstancing, InstancesFollowTheMeshOfALink) {
  Model model = cube_model({0, 0, 0, 0, 0.3f, 0}, Json::array({{{"offset", 0}, {"count", 2}, {"type", "VEC3"}}}));
  model.document["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
  model.document["scenes"] = {{{"nodes", {0}}}};
  model.document["nodes"] = {
      {{"name", "base"}, {"mesh", 0}, {"children", {1}},
       {"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", {{"TRANSLATION", 2}}}}}}}},
      {{"name", "arm"}, {"mesh", 0}, {"translation", {0, 0, 1}}}};
  const Conversion c = convert_ok(model);
  ASSERT_EQ(c.robot.links.size(), 2u);
  const double cube = 1000.0 * std::pow(0.1f, 3.0);
  EXPECT_NEAR(c.robot.links[0].inertial.mass, 2 * cube, 1e-6 * cube);
  EXPECT_NEAR(c.robot.links[0].inertial.center_of_mass.y(), 0.15f, 1e-7);
  EXPECT_NEAR(c.robot.links[1].inertial.mass, cube, 1e-6 * cube);
}

TEST(GpuInstancing, UnusableAttributesAreErrors) {
  Model model = cube_model({0, 0, 0, 1, 0, 0}, Json::array({{{"offset", 0}, {"count", 2}, {"type", "VEC2"}}}));
  model.document["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};  // Without it, UNDECLARED_EXTENSION comes first.
  model.document["scenes"] = {{{"nodes", {0}}}};
  model.document["nodes"] = {{{"name", "base"}, {"mesh", 0},
                              {"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", {{"TRANSLATION", 2}}}}}}}}};
  Diagnostics diag;
  EXPECT_FALSE(convert_model(model, diag));
  Diagnostic d;
  for (const Diagnostic& each : diag.all()) {
    if (each.severity == Severity::kError && d.code.empty()) d = each;
  }
  // The instances moved with the mesh to a node split off the link (node 1, 'base_mesh'), which
  // only the output has: the error names the node of the input, where the user can fix it.
  EXPECT_EQ(d.code, "INSTANCING_INVALID");
  EXPECT_EQ(d.pointer, "/nodes/0/extensions/EXT_mesh_gpu_instancing/attributes/TRANSLATION");
  EXPECT_NE(d.message.find("VEC3 of FLOAT"), std::string::npos) << d.message;
}

// gltfpack's layout: the mesh moved from "base" and "arm" into unnamed children that carry the
// dequantization transform (here a scale of 1 and no offset, so the geometry is the same).
TEST(MeshCarriers, EncoderInsertedMeshNodesLeaveTheRobotUnchanged) {
  Model plain = cube_model({}, Json::array());
  plain.document["scenes"] = {{{"nodes", {0}}}};
  plain.document["nodes"] = {{{"name", "base"}, {"mesh", 0}, {"children", {1}}},
                             {{"name", "arm"}, {"mesh", 0}, {"translation", {0.3, 0, 0}}}};
  Model carried = cube_model({}, Json::array());
  carried.document["scenes"] = {{{"nodes", {0}}}};
  carried.document["nodes"] = {{{"name", "base"}, {"children", {1, 2}}},
                               {{"name", "arm"}, {"translation", {0.3, 0, 0}}, {"children", {3}}},
                               {{"mesh", 0}, {"scale", {1, 1, 1}}},
                               {{"mesh", 0}, {"translation", {0, 0, 0}}}};
  const Conversion a = convert_ok(plain);
  const Conversion b = convert_ok(carried);
  ASSERT_EQ(a.robot.links.size(), 2u);
  ASSERT_EQ(b.robot.links.size(), 2u);
  ASSERT_EQ(b.robot.joints.size(), 1u);
  for (std::size_t l = 0; l < 2; ++l) {
    EXPECT_EQ(b.robot.links[l].name, a.robot.links[l].name);
    expect_same_mass(b.robot.links[l].inertial, a.robot.links[l].inertial);
  }
  EXPECT_EQ(b.robot.joints[0].name, a.robot.joints[0].name);
  EXPECT_TRUE(b.robot.joints[0].X_PJ.isApprox(a.robot.joints[0].X_PJ, kExact));
}

// Two bare mesh children are no encoder's work: each is an ordinary mesh node of the link.
TEST(MeshCarriers, TwoBareMeshChildrenAreOrdinaryMeshes) {
  Model model = cube_model({}, Json::array());
  model.document["scenes"] = {{{"nodes", {0}}}};
  model.document["nodes"] = {{{"name", "base"}, {"children", {1, 2}}},
                             {{"mesh", 0}},
                             {{"mesh", 0}, {"translation", {0.3, 0, 0}}}};
  const Conversion c = convert_ok(model);
  ASSERT_EQ(c.robot.links.size(), 1u);
  EXPECT_EQ(c.robot.links[0].meshes.size(), 2u);
}

Diagnostic refusal(const std::optional<std::vector<std::uint8_t>>& glb, LoadLimits limits = {},
                   const std::string& name = "model.glb") {
  Diagnostics diag;
  EXPECT_TRUE(glb);
  EXPECT_FALSE(load_gltf_from_memory(*glb, name, "", limits, diag));
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError) return d;
  }
  ADD_FAILURE() << "no error";
  return {};
}

std::vector<std::uint8_t> with_header(std::vector<std::uint8_t> header, const std::string& payload) {
  header.insert(header.end(), payload.begin(), payload.end());
  return header;
}

TEST(CompressedData, DracoBytesThatAreNoMeshAreRefused) {
  const Diagnostic d = refusal(fuzz::draco_model(with_header({8, 0, 36, 0, 0, 0}, "DRACO but not really a mesh")));
  EXPECT_EQ(d.code, "DRACO_INVALID");
  EXPECT_EQ(d.pointer, "/meshes/0/primitives/0/extensions/KHR_draco_mesh_compression");
}

TEST(CompressedData, DracoDecodedSizeIsCheckedBeforeDecoding) {
  // The first seed's mesh decodes to 192 vertices and 372 indices; the limit leaves room for the
  // compressed bytes only.
  const auto seed = fuzz::read_bytes(testing::data_dir() / "fuzz-regressions/draco/arm_draco_mesh1");
  LoadLimits limits;
  limits.max_buffer_bytes = seed.size() + 16;
  const Diagnostic d = refusal(fuzz::draco_model(seed), limits);
  EXPECT_EQ(d.code, "LIMIT_EXCEEDED");
  EXPECT_NE(d.message.find("max_buffer_bytes"), std::string::npos) << d.message;
}

// The first seed with its Draco connectivity counts (varints at bytes 18 and 19 of the fuzz
// input: 64 encoded vertices, 124 faces) replaced.
std::vector<std::uint8_t> seed_with_counts(const std::vector<std::uint8_t>& vertices, const std::vector<std::uint8_t>& faces) {
  auto bytes = fuzz::read_bytes(testing::data_dir() / "fuzz-regressions/draco/arm_draco_mesh1");
  EXPECT_EQ(bytes[18], 0x40);
  EXPECT_EQ(bytes[19], 0x7c);
  std::vector<std::uint8_t> out(bytes.begin(), bytes.begin() + 18);
  out.insert(out.end(), vertices.begin(), vertices.end());
  out.insert(out.end(), faces.begin(), faces.end());
  out.insert(out.end(), bytes.begin() + 20, bytes.end());
  return out;
}

TEST(CompressedData, DracoFacesOtherThanTheIndicesAreRefusedBeforeDecoding) {
  const Diagnostic d = refusal(fuzz::draco_model(seed_with_counts({0x40}, {0x7d})));  // 125 faces
  EXPECT_EQ(d.code, "DRACO_INVALID");
  EXPECT_EQ(d.pointer, "/meshes/0/primitives/0/extensions/KHR_draco_mesh_compression");
  EXPECT_NE(d.message.find("(version 2.2, edgebreaker) declares 125 faces (375 indices) but the indices "
                           "accessor declares 372"), std::string::npos) << d.message;
}

TEST(CompressedData, DracoVerticesBeyondTheAttributesAreRefusedBeforeDecoding) {
  const Diagnostic d = refusal(fuzz::draco_model(seed_with_counts({0xc1, 0x01}, {0x7c})));  // 193 vertices
  EXPECT_EQ(d.code, "DRACO_INVALID");
  EXPECT_NE(d.message.find("declares 193 vertices but the attribute accessors declare 192"), std::string::npos)
      << d.message;
}

TEST(CompressedData, DracoFaceCountOverTheTriangleLimitIsRefusedBeforeDecoding) {
  // 2^32 - 1 faces, the largest a varint of libdraco holds.
  const Diagnostic d = refusal(fuzz::draco_model(seed_with_counts({0x40}, {0xff, 0xff, 0xff, 0xff, 0x0f})));
  EXPECT_EQ(d.code, "LIMIT_EXCEEDED");
  EXPECT_NE(d.message.find("declares 4294967295 faces, over the limit of 67108864 (max_triangles)"), std::string::npos)
      << d.message;
}

TEST(CompressedData, DracoVersionsNotReadAreRefused) {
  auto bytes = fuzz::read_bytes(testing::data_dir() / "fuzz-regressions/draco/arm_draco_mesh1");
  bytes[12] = 3;  // Version 2.3
  const Diagnostic d = refusal(fuzz::draco_model(bytes));
  EXPECT_EQ(d.code, "DRACO_INVALID");
  EXPECT_NE(d.message.find("version 2.3 is not read"), std::string::npos) << d.message;
}

// A unit cube with texture coordinates as draco_encoder writes it (tests/data/encoded/make.sh,
// fuzz/make_decoder_seeds.py): 1000 kg at the default 1000 kg/m^3, exactly, since 11-bit
// quantization keeps the corners 0 and 1. The same stream declaring 2^30 texture-coordinate
// orientations for its 36 corners is refused: libdraco 1.5.5 as shipped allocates 130 MB and loops
// for seconds over that count, then decodes the cube (scripts/draco's patch bounds it).
TEST(CompressedData, DracoTextureCoordinateOrientationsBeyondTheCornersAreRefused) {
  const auto cube = fuzz::read_bytes(testing::data_dir() / "fuzz-regressions/draco/cube_texcoords");
  const auto glb = fuzz::draco_model(cube);
  ASSERT_TRUE(glb);
  Diagnostics diag;
  auto asset = load_gltf_from_memory(*glb, "model.glb", "", LoadLimits{}, diag);
  ASSERT_TRUE(asset) << diag.all().size();
  const auto conversion = convert(std::move(*asset), ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  ASSERT_EQ(conversion->robot.links.size(), 1u);
  const MassProperties& cube_mass = conversion->robot.links[0].inertial;
  EXPECT_NEAR(cube_mass.mass, 1000.0, kExact * 1000.0);
  EXPECT_TRUE(cube_mass.center_of_mass.isApprox(Eigen::Vector3d(0.5, 0.5, 0.5), kExact)) << cube_mass.center_of_mass;
  EXPECT_TRUE(cube_mass.inertia.isApprox(Eigen::Matrix3d::Identity() * (1000.0 / 6.0), kExact)) << cube_mass.inertia;

  const auto crafted = fuzz::read_bytes(testing::data_dir() / "fuzz-regressions/draco/texcoord_orientations_over_corners");
  ASSERT_EQ(crafted.size(), cube.size());
  const Diagnostic d = refusal(fuzz::draco_model(crafted));
  EXPECT_EQ(d.code, "DRACO_INVALID");
  EXPECT_EQ(d.pointer, "/meshes/0/primitives/0/extensions/KHR_draco_mesh_compression");
  EXPECT_NE(d.message.find("libdraco could not decode the mesh"), std::string::npos) << d.message;
}

// glTF requires every extension an object uses in extensionsUsed, and every required one there
// too; the Khronos validator refuses either. Real encoders' files with the lists removed or
// mismatched are refused, naming the object (a required extension that is not used was kept by
// the output and made it invalid).
// gltfpack marks its fallback buffer; a buffer of real bytes may carry the extension too, with
// "fallback": false. Once decoded, the extension leaves extensionsUsed and every buffer: the
// output checked again has no object using an extension it does not list.
TEST(CompressedData, AMeshoptBufferThatIsNoFallbackLosesTheExtensionWithTheName) {
  const auto glb = fuzz::read_bytes(testing::data_dir() / "encoded" / "arm_meshopt.glb");
  Diagnostics parse_diag;
  const auto chunks = parse_glb(glb, parse_diag);
  ASSERT_TRUE(chunks && chunks->bin);
  Json document = Json::parse(chunks->json);
  ASSERT_FALSE(document["buffers"][0].contains("extensions"));
  document["buffers"][0]["extensions"] = {{"EXT_meshopt_compression", {{"fallback", false}}}};
  Diagnostics diag;
  const auto asset = load_gltf_from_memory(make_glb(document.dump(), *chunks->bin), "model.glb", "", LoadLimits{}, diag);
  ASSERT_TRUE(asset) << (diag.all().empty() ? std::string() : format(diag.all().back()));
  EXPECT_FALSE(asset->document["buffers"][0].contains("extensions")) << asset->document["buffers"].dump();
  for (const Json& name : asset->document.value("extensionsUsed", Json::array())) EXPECT_NE(name, "EXT_meshopt_compression");
}

TEST(CompressedData, ExtensionsMissingFromExtensionsUsedAreRefused) {
  const auto refused = [](const std::string& name, Json document, std::span<const std::uint8_t> bin) {
    const std::string json = document.dump();
    const auto bytes = bin.empty() ? std::vector<std::uint8_t>(json.begin(), json.end()) : make_glb(json, bin);
    return refusal(bytes, LoadLimits{}, name);
  };
  Json draco = Json::parse(testing::read_file(testing::data_dir() / "encoded" / "arm_draco.gltf"));
  draco.erase("extensionsUsed");
  draco.erase("extensionsRequired");
  Diagnostic d = refused("model.gltf", draco, {});
  EXPECT_EQ(d.code, "UNDECLARED_EXTENSION");
  EXPECT_EQ(d.pointer, "/meshes/0/primitives/0/extensions/KHR_draco_mesh_compression");

  const auto glb = fuzz::read_bytes(testing::data_dir() / "encoded" / "arm_meshopt.glb");
  Diagnostics parse_diag;
  const auto chunks = parse_glb(glb, parse_diag);
  ASSERT_TRUE(chunks && chunks->bin);
  Json meshopt = Json::parse(chunks->json);
  Json used = Json::array();
  for (const Json& name : meshopt["extensionsUsed"]) {
    if (name != "EXT_meshopt_compression") used.push_back(name);
  }
  meshopt["extensionsUsed"] = used;
  // KHR_mesh_quantization stays required (NON_REQUIRED_EXTENSION otherwise): only the meshopt
  // extension goes.
  Json required = Json::array();
  for (const Json& name : meshopt.value("extensionsRequired", Json::array())) {
    if (name != "EXT_meshopt_compression") required.push_back(name);
  }
  meshopt["extensionsRequired"] = required;
  if (required.empty()) meshopt.erase("extensionsRequired");
  d = refused("model.glb", meshopt, *chunks->bin);
  EXPECT_EQ(d.code, "UNDECLARED_EXTENSION");
  EXPECT_NE(d.pointer.find("/extensions/EXT_meshopt_compression"), std::string::npos) << d.pointer;

  Json textured = Json::parse(testing::read_file(testing::data_dir() / "encoded" / "arm_draco.gltf"));
  textured["extensionsRequired"] = {"KHR_draco_mesh_compression", "KHR_texture_transform"};
  d = refused("model.gltf", textured, {});
  EXPECT_EQ(d.code, "UNUSED_EXTENSION_REQUIRED");
  EXPECT_EQ(d.pointer, "/extensionsRequired/1");
  EXPECT_NE(d.message.find("KHR_texture_transform is required but not in extensionsUsed"), std::string::npos) << d.message;
}

TEST(CompressedData, MeshoptBytesThatDoNotDecodeAreRefused) {
  // 8 vertices of 12 bytes from a stream of 5 bytes that is no meshopt vertex stream.
  const Diagnostic d = refusal(fuzz::meshopt_model({8, 0, 36, 0, 0, 5, 0, 1, 2, 3, 4, 5, 9, 9}));
  EXPECT_EQ(d.code, "MESHOPT_INVALID");
  EXPECT_EQ(d.pointer, "/bufferViews/0/extensions/EXT_meshopt_compression");
}

TEST(CompressedData, MeshoptLayoutRulesAreChecked) {
  const auto glb = fuzz::meshopt_model({8, 0, 35, 0, 0, 5, 0, 1, 2, 3, 4, 5, 9, 9});  // 35 indices: not triangles
  ASSERT_TRUE(glb);
  Diagnostics diag;
  EXPECT_FALSE(load_gltf_from_memory(*glb, "model.glb", "", LoadLimits{}, diag));
  bool found = false;
  for (const Diagnostic& d : diag.all()) {
    if (d.pointer != "/bufferViews/1/extensions/EXT_meshopt_compression") continue;
    found = true;
    EXPECT_EQ(d.code, "MESHOPT_INVALID");
    EXPECT_NE(d.message.find("multiple of 3"), std::string::npos) << d.message;
  }
  EXPECT_TRUE(found);
}

}  // namespace
}  // namespace rdtf
