// validate_document and validate_data on small documents built inline: each test breaks one
// thing and asserts the validator's issue code and JSON pointer for it.
#include <gtest/gtest.h>

#include <algorithm>

#include <array>
#include <cmath>
#include <cstring>
#include <set>
#include <string>
#include <vector>

#include "rdtf/validate.h"

namespace rdtf {
namespace {

// A triangle: 3 vertices (VEC3 FLOAT, bytes 0-35) and 3 UNSIGNED_SHORT indices (bytes 36-41).
Json triangle_document() {
  return Json::parse(R"({
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [{"name": "base", "mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
       "min": [0, 0, 0], "max": [1, 1, 0]},
      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
    ],
    "bufferViews": [
      {"buffer": 0, "byteOffset": 0, "byteLength": 36, "target": 34962},
      {"buffer": 0, "byteOffset": 36, "byteLength": 6, "target": 34963}
    ],
    "buffers": [{"uri": "triangle.bin", "byteLength": 44}]
  })");
}

template <typename T>
void append(std::vector<std::uint8_t>& bytes, T value) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
  bytes.insert(bytes.end(), p, p + sizeof(T));
}

std::vector<std::uint8_t> triangle_bytes(const std::array<float, 9>& positions,
                                         const std::array<std::uint16_t, 3>& indices) {
  std::vector<std::uint8_t> bytes;
  for (float value : positions) append(bytes, value);
  for (std::uint16_t index : indices) append(bytes, index);
  bytes.resize(44, 0);
  return bytes;
}

GltfAsset make_asset(Json document, std::vector<std::vector<std::uint8_t>> buffers) {
  GltfAsset asset;
  asset.path = "inline.gltf";
  asset.document = std::move(document);
  asset.buffers = std::move(buffers);
  return asset;
}

std::string listing(const Diagnostics& diag) {
  std::string text;
  for (const Diagnostic& d : diag.all()) text += "  " + format(d) + "\n";
  return text.empty() ? "  (no diagnostics)\n" : text;
}

bool has_error(const Diagnostics& diag, const std::string& code, const std::string& pointer) {
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError && d.code == code && d.pointer == pointer) return true;
  }
  return false;
}

Diagnostics check_document(const Json& document, const LoadLimits& limits = {}) {
  Diagnostics diag("inline.gltf");
  validate_document(document, limits, diag);
  return diag;
}

Diagnostics check_data(const GltfAsset& asset) {
  Diagnostics diag("inline.gltf");
  validate_document(asset.document, asset.limits, diag);
  EXPECT_FALSE(diag.has_errors()) << "the document itself should be valid:\n" << listing(diag);
  validate_data(asset, diag);
  return diag;
}

#define EXPECT_DIAGNOSTIC(diag, code, pointer)                  \
  EXPECT_TRUE(has_error(diag, code, pointer))                   \
      << "expected " << code << " at " << pointer << ", got:\n" \
      << listing(diag)

TEST(ValidateDocument, AcceptsAValidTriangle) {
  const Diagnostics diag = check_document(triangle_document());
  EXPECT_EQ(diag.all().size(), 0u) << listing(diag);
  const GltfAsset asset =
      make_asset(triangle_document(), {triangle_bytes({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2})});
  const Diagnostics data = check_data(asset);
  EXPECT_EQ(data.all().size(), 0u) << listing(data);
}

// What rdtf writes out unread is checked too: each of these passed through into an output the
// Khronos validator refused, with exit 0 (s100err D1). Codes and pointers are the validator's.
TEST(ValidateDocument, WhatPassesThroughUnreadIsChecked) {
  const auto one = [](const char* patch) {
    Json document = triangle_document();
    document.merge_patch(Json::parse(patch));
    return check_document(document);
  };
  EXPECT_DIAGNOSTIC(one(R"({"asset": {"generator": 7}})"), "TYPE_MISMATCH", "/asset/generator");
  EXPECT_DIAGNOSTIC(one(R"({"asset": {"copyright": 5}})"), "TYPE_MISMATCH", "/asset/copyright");
  EXPECT_DIAGNOSTIC(one(R"({"asset": {"extensions": "x"}})"), "TYPE_MISMATCH", "/asset/extensions");
  EXPECT_DIAGNOSTIC(one(R"({"extensionsUsed": ["KHR_x", "KHR_x"]})"), "DUPLICATE_ELEMENTS", "/extensionsUsed/1");
  EXPECT_DIAGNOSTIC(one(R"({"materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0]}}]})"),
                    "ARRAY_LENGTH_NOT_IN_LIST", "/materials/0/pbrMetallicRoughness/baseColorFactor");
  EXPECT_DIAGNOSTIC(one(R"({"materials": [{"pbrMetallicRoughness": {"baseColorFactor": [2, 0, 0, 1]}}]})"),
                    "VALUE_NOT_IN_RANGE", "/materials/0/pbrMetallicRoughness/baseColorFactor/0");
  EXPECT_DIAGNOSTIC(one(R"({"materials": [{"pbrMetallicRoughness": {"roughnessFactor": -0.5}}]})"),
                    "VALUE_NOT_IN_RANGE", "/materials/0/pbrMetallicRoughness/roughnessFactor");
  EXPECT_DIAGNOSTIC(one(R"({"materials": [{"alphaMode": "CLIP"}]})"), "VALUE_NOT_IN_LIST", "/materials/0/alphaMode");
  EXPECT_DIAGNOSTIC(one(R"({"materials": [{"emissiveTexture": {"index": 3}}]})"), "UNRESOLVED_REFERENCE",
                    "/materials/0/emissiveTexture/index");
  EXPECT_DIAGNOSTIC(one(R"({"materials": [{"doubleSided": "yes"}]})"), "TYPE_MISMATCH", "/materials/0/doubleSided");
  EXPECT_DIAGNOSTIC(one(R"({"samplers": [{"wrapS": 7}]})"), "VALUE_NOT_IN_LIST", "/samplers/0/wrapS");
  EXPECT_DIAGNOSTIC(one(R"({"textures": [{"source": 0}]})"), "UNRESOLVED_REFERENCE", "/textures/0/source");
  // An image's bytes are a file or a buffer view: exactly one, and in a view with its mimeType.
  EXPECT_DIAGNOSTIC(one(R"({"images": [{"uri": "a.png", "bufferView": 0, "mimeType": "image/png"}]})"),
                    "ONE_OF_MISMATCH", "/images/0");
  EXPECT_DIAGNOSTIC(one(R"({"images": [{"name": "nothing"}]})"), "ONE_OF_MISMATCH", "/images/0");
  EXPECT_DIAGNOSTIC(one(R"({"images": [{"bufferView": 0}]})"), "UNSATISFIED_DEPENDENCY", "/images/0/bufferView");
  EXPECT_DIAGNOSTIC(one(R"({"images": [{"bufferView": 0, "mimeType": 5}]})"), "TYPE_MISMATCH", "/images/0/mimeType");
  EXPECT_DIAGNOSTIC(one(R"({"images": [{"bufferView": 0, "mimeType": 5}]})"), "UNSATISFIED_DEPENDENCY",
                    "/images/0/bufferView");
  EXPECT_DIAGNOSTIC(one(R"({"images": [{"uri": 5}]})"), "ONE_OF_MISMATCH", "/images/0");  // No usable uri.
  for (const char* image : {R"({"images": [{"uri": "a.png"}]})", R"({"images": [{"bufferView": 0, "mimeType": "image/png"}]})"}) {
    const Diagnostics diag = one(image);
    for (const Diagnostic& d : diag.all()) {
      EXPECT_NE(d.code, "ONE_OF_MISMATCH") << image;
      EXPECT_NE(d.code, "UNSATISFIED_DEPENDENCY") << image;
    }
  }
  // Every object's extensions, the node's named by its name.
  Json document = triangle_document();
  document["nodes"][0]["extensions"] = 5;
  const Diagnostics diag = check_document(document);
  EXPECT_DIAGNOSTIC(diag, "TYPE_MISMATCH", "/nodes/0/extensions");
  ASSERT_FALSE(diag.all().empty());
  EXPECT_EQ(diag.all()[0].message, "node 0 'base': must be an object, found number 5");
  document = triangle_document();
  document["meshes"][0]["primitives"][0]["extensions"] = Json::array({1});
  EXPECT_DIAGNOSTIC(check_document(document), "TYPE_MISMATCH", "/meshes/0/primitives/0/extensions");
  // Extras hold anything, and so does a property glTF does not define (s100rev D1).
  document = triangle_document();
  document["nodes"][0]["extras"] = {{"extensions", 5}};
  document["nodes"][0]["myToolData"] = {{"extensions", {"a", "b"}}};
  EXPECT_EQ(check_document(document).all().size(), 0u) << listing(check_document(document));
  document = triangle_document();
  document["nodes"][0]["extensions"] = nullptr;
  const Diagnostics null_diag = check_document(document);
  ASSERT_FALSE(null_diag.all().empty());
  EXPECT_EQ(null_diag.all()[0].message, "node 0 'base': must be an object, found null");
  // A materials, textures and samplers section as exporters write it is silent.
  EXPECT_EQ(one(R"({"materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 0, 1], "metallicFactor": 0,
                     "baseColorTexture": {"index": 0, "texCoord": 0}}, "alphaMode": "MASK", "alphaCutoff": 0.5,
                     "doubleSided": true, "normalTexture": {"index": 0, "scale": -2}, "emissiveFactor": [0, 0, 1]}],
                   "textures": [{"sampler": 0, "source": 0}], "images": [{"uri": "a.png"}],
                   "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 33648, "wrapT": 10497}]})")
                .all()
                .size(),
            0u);
}

// A material sampling a texture with a TEXCOORD_n its primitive does not have is the validator's
// MESH_PRIMITIVE_TOO_FEW_TEXCOORDS, at the primitive's material; with the UV map, silent (s100rev R2).
TEST(ValidateDocument, AMaterialsTextureNeedsItsUvMapOnThePrimitive) {
  Json document = triangle_document();
  document["materials"] = Json::parse(R"([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1}},
                                          "occlusionTexture": {"index": 0}}])");
  document["textures"] = Json::parse(R"([{"source": 0}])");
  document["images"] = Json::parse(R"([{"uri": "a.png"}])");
  document["meshes"][0]["primitives"][0]["material"] = 0;
  const Diagnostics diag = check_document(document);
  const auto count = [](const Diagnostics& d) {
    return std::count_if(d.all().begin(), d.all().end(),
                         [](const Diagnostic& x) { return x.code == "MESH_PRIMITIVE_TOO_FEW_TEXCOORDS"; });
  };
  EXPECT_EQ(count(diag), 2) << listing(diag);
  EXPECT_DIAGNOSTIC(diag, "MESH_PRIMITIVE_TOO_FEW_TEXCOORDS", "/meshes/0/primitives/0/material");
  ASSERT_FALSE(diag.all().empty());
  EXPECT_NE(diag.all()[0].message.find("/materials/0/pbrMetallicRoughness/baseColorTexture is sampled with TEXCOORD_1"),
            std::string::npos)
      << diag.all()[0].message;
  document["accessors"].push_back(Json::parse(R"({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC2"})"));
  document["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 2;
  document["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = 2;
  EXPECT_EQ(count(check_document(document)), 0) << listing(check_document(document));
}

// An accessor that fails its layout is still checked for its format: the cause is said beside the
// consequence, as the validator says both (s100err D2: only ACCESSOR_TOO_LONG, whose fix is wrong).
TEST(ValidateDocument, TheFormatIsSaidBesideTheLayoutItBreaks) {
  Json document = triangle_document();
  document["bufferViews"][1]["byteStride"] = 4;
  Diagnostics diag = check_document(document);
  EXPECT_DIAGNOSTIC(diag, "ACCESSOR_TOO_LONG", "/accessors/1");
  EXPECT_DIAGNOSTIC(diag, "MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE", "/meshes/0/primitives/0/indices");
  document = triangle_document();
  document["accessors"][1]["componentType"] = 5126;
  diag = check_document(document);
  EXPECT_DIAGNOSTIC(diag, "ACCESSOR_TOO_LONG", "/accessors/1");
  EXPECT_DIAGNOSTIC(diag, "MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT", "/meshes/0/primitives/0/indices");
  document = triangle_document();
  document["accessors"][0]["type"] = "VEC2";
  diag = check_document(document);
  EXPECT_DIAGNOSTIC(diag, "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT", "/meshes/0/primitives/0/attributes/POSITION");
}

// Schema errors on a node name it (a Blender user knows objects by name; s100err D4), and an index
// beyond 2^64 is too large, not "not an integer".
TEST(ValidateDocument, NodesAreNamedAndHugeIndicesAreOutOfRange) {
  Json document = triangle_document();
  document["nodes"][0]["mesh"] = "x";
  Diagnostics diag = check_document(document);
  ASSERT_FALSE(diag.all().empty());
  EXPECT_EQ(diag.all()[0].message, "node 0 'base': must be an integer, found string \"x\"");
  document["nodes"][0]["mesh"] = 1.8446744073709552e19;
  diag = check_document(document);
  EXPECT_DIAGNOSTIC(diag, "VALUE_NOT_IN_RANGE", "/nodes/0/mesh");
  EXPECT_NE(diag.all()[0].message.find("too large"), std::string::npos) << listing(diag);
}

TEST(ValidateDocument, AccessorPastTheEndOfItsBufferView) {
  Json document = triangle_document();
  document["accessors"][0]["count"] = 4;  // 4 x 12 bytes in a 36-byte view.
  EXPECT_DIAGNOSTIC(check_document(document), "ACCESSOR_TOO_LONG", "/accessors/0");

  document = triangle_document();
  document["accessors"][0]["byteOffset"] = 36;  // Starts at the view's end.
  EXPECT_DIAGNOSTIC(check_document(document), "ACCESSOR_TOO_LONG", "/accessors/0/byteOffset");
}

TEST(ValidateDocument, AccessorsAlignAndFitTheirStride) {
  Json document = triangle_document();
  document["accessors"][0]["byteOffset"] = 2;
  const Diagnostics diag = check_document(document);
  EXPECT_DIAGNOSTIC(diag, "ACCESSOR_OFFSET_ALIGNMENT", "/accessors/0/byteOffset");
  EXPECT_DIAGNOSTIC(diag, "ACCESSOR_TOTAL_OFFSET_ALIGNMENT", "/accessors/0");

  document = triangle_document();
  document["bufferViews"][0]["byteStride"] = 8;  // Less than one VEC3 of floats.
  EXPECT_DIAGNOSTIC(check_document(document), "ACCESSOR_SMALL_BYTESTRIDE", "/accessors/0");
  document["bufferViews"][0]["byteStride"] = 14;
  EXPECT_DIAGNOSTIC(check_document(document), "VALUE_MULTIPLE_OF", "/bufferViews/0/byteStride");
  document["bufferViews"][0]["byteStride"] = 256;
  EXPECT_DIAGNOSTIC(check_document(document), "VALUE_NOT_IN_RANGE", "/bufferViews/0/byteStride");
}

TEST(ValidateDocument, BufferViewPastTheEndOfItsBuffer) {
  Json document = triangle_document();
  document["bufferViews"][1]["byteLength"] = 10;  // 36 + 10 > 44
  EXPECT_DIAGNOSTIC(check_document(document), "BUFFER_VIEW_TOO_LONG", "/bufferViews/1/byteLength");
  document["bufferViews"][1]["byteOffset"] = 44;
  EXPECT_DIAGNOSTIC(check_document(document), "BUFFER_VIEW_TOO_LONG", "/bufferViews/1/byteOffset");
  document["bufferViews"][1]["byteOffset"] =
      std::numeric_limits<std::uint64_t>::max();  // Sum overflows.
  EXPECT_DIAGNOSTIC(check_document(document), "BUFFER_VIEW_TOO_LONG", "/bufferViews/1/byteOffset");
}

TEST(ValidateDocument, AbsurdCountsAreRefusedWithoutOverflowOrAllocation) {
  Json document = triangle_document();
  document["accessors"][0]["count"] = std::uint64_t{1} << 31;
  EXPECT_DIAGNOSTIC(check_document(document), "LIMIT_EXCEEDED", "/accessors/0/count");

  // Above the default limit the arithmetic still has to hold: (count - 1) * stride overflows
  // 64 bits for these values.
  LoadLimits generous;
  generous.max_accessor_count = std::numeric_limits<std::uint64_t>::max();
  generous.max_triangles = std::numeric_limits<std::uint64_t>::max();
  for (std::uint64_t count : {std::uint64_t{1} << 31, std::uint64_t{1} << 32,
                              std::uint64_t{1} << 62, std::numeric_limits<std::uint64_t>::max()}) {
    document["accessors"][0]["count"] = count;
    document["accessors"][1]["count"] = count;
    const Diagnostics diag = check_document(document, generous);
    EXPECT_DIAGNOSTIC(diag, "ACCESSOR_TOO_LONG", "/accessors/0");
    EXPECT_DIAGNOSTIC(diag, "ACCESSOR_TOO_LONG", "/accessors/1");
  }
  document = triangle_document();
  document["accessors"][0]["byteOffset"] = std::numeric_limits<std::uint64_t>::max() - 3;
  EXPECT_DIAGNOSTIC(check_document(document), "ACCESSOR_TOO_LONG", "/accessors/0/byteOffset");

  // validate_data on an unvalidated asset must not trust the count either.
  document = triangle_document();
  document["accessors"][0]["count"] = std::uint64_t{1} << 31;
  const GltfAsset asset = make_asset(document, {triangle_bytes({}, {0, 1, 2})});
  Diagnostics data("inline.gltf");
  validate_data(asset, data);
  EXPECT_DIAGNOSTIC(data, "ACCESSOR_DATA_UNREADABLE", "/accessors/0");
}

TEST(ValidateDocument, LimitsOnBuffersAndTriangles) {
  LoadLimits limits;
  limits.max_buffer_bytes = 43;
  EXPECT_DIAGNOSTIC(check_document(triangle_document(), limits), "LIMIT_EXCEEDED", "/buffers");
  limits = {};
  limits.max_triangles = 0;
  EXPECT_DIAGNOSTIC(check_document(triangle_document(), limits), "LIMIT_EXCEEDED", "/nodes/0/mesh");
}

// Each vertex a weighed morph target moves counts as one triangle more: a mesh of many targets
// sharing one accessor made the converter's work targets x vertices from a small file.
TEST(ValidateDocument, MorphedVerticesCountTowardsTheTriangleLimit) {
  Json document = triangle_document();
  document["meshes"][0]["primitives"][0]["targets"] = Json::parse(R"([{"POSITION": 0}, {"POSITION": 0}, {"POSITION": 0}])");
  document["meshes"][0]["weights"] = Json::parse("[1, 0, 0.5]");
  const auto limit_error = [](const Diagnostics& diag) -> const Diagnostic* {
    for (const Diagnostic& d : diag.all()) {
      if (d.code == "LIMIT_EXCEEDED") return &d;
    }
    return nullptr;
  };
  LoadLimits limits;
  limits.max_triangles = 7;  // 1 triangle, and 3 vertices moved by each of two weighed targets.
  const Diagnostics within = check_document(document, limits);
  EXPECT_EQ(within.error_count(), 0u) << listing(within);
  limits.max_triangles = 6;
  const Diagnostics over = check_document(document, limits);
  const Diagnostic* error = limit_error(over);
  ASSERT_NE(error, nullptr) << listing(over);
  EXPECT_EQ(error->pointer, "/nodes/0/mesh");
  EXPECT_NE(error->message.find("reach 7 triangles"), std::string::npos) << error->message;
  EXPECT_NE(error->message.find("this node's 6"), std::string::npos) << error->message;
  EXPECT_NE(error->message.find("over the limit of 6 (max_triangles)"), std::string::npos) << error->message;

  // The node's own weights replace the mesh's: none weighed, only the triangle counts.
  limits.max_triangles = 1;
  document["nodes"][0]["weights"] = Json::parse("[0, 0, 0]");
  const Diagnostics unweighed = check_document(document, limits);
  EXPECT_EQ(limit_error(unweighed), nullptr) << listing(unweighed);
  document["nodes"][0]["weights"] = Json::parse("[0, -2, 0]");
  limits.max_triangles = 4;
  const Diagnostics one = check_document(document, limits);
  EXPECT_EQ(limit_error(one), nullptr) << listing(one);
  limits.max_triangles = 3;
  EXPECT_NE(limit_error(check_document(document, limits)), nullptr);

  // Points are not morphed: their targets cost nothing.
  Json points = document;
  points["meshes"][0]["primitives"][0]["mode"] = 0;
  points["meshes"][0]["primitives"][0].erase("indices");
  limits.max_triangles = 0;
  const Diagnostics unmorphed = check_document(points, limits);
  EXPECT_EQ(limit_error(unmorphed), nullptr) << listing(unmorphed);

  // A second node using the mesh counts again, with its own weights.
  document["nodes"][0]["weights"] = Json::parse("[1, 1, 1]");
  document["nodes"].push_back(Json::parse(R"({"mesh": 0, "name": "again"})"));  // The mesh's: 1, 0, 0.5.
  document["scenes"][0]["nodes"].push_back(1);
  limits.max_triangles = 1 + 9 + 1 + 6;
  const Diagnostics two = check_document(document, limits);
  EXPECT_EQ(limit_error(two), nullptr) << listing(two);
  limits.max_triangles = 1 + 9 + 1 + 5;
  const Diagnostics beyond = check_document(document, limits);
  ASSERT_NE(limit_error(beyond), nullptr) << listing(beyond);
  EXPECT_EQ(limit_error(beyond)->pointer, "/nodes/1/mesh");
}

TEST(ValidateDocument, NodeLoops) {
  Json document = triangle_document();
  document["nodes"] = Json::parse(R"([{"children": [1]}, {"children": [2]}, {"children": [1]}])");
  document["scenes"][0]["nodes"] = Json::array({0});
  Diagnostics diag = check_document(document);
  EXPECT_DIAGNOSTIC(diag, "NODE_LOOP", "/nodes/1");
  EXPECT_DIAGNOSTIC(diag, "NODE_LOOP", "/nodes/2");

  document["nodes"] = Json::parse(R"([{"children": [0]}])");  // Its own child.
  document["scenes"] = Json::parse(R"([{"nodes": [0]}])");
  EXPECT_DIAGNOSTIC(check_document(document), "NODE_LOOP", "/nodes/0");
}

TEST(ValidateDocument, NodeWithTwoParents) {
  Json document = triangle_document();
  document["nodes"] = Json::parse(R"([{"children": [2]}, {"children": [2]}, {"mesh": 0}])");
  document["scenes"][0]["nodes"] = Json::array({0, 1});
  EXPECT_DIAGNOSTIC(check_document(document), "NODE_PARENT_OVERRIDE", "/nodes/1/children/0");
}

TEST(ValidateDocument, SceneRootsMustBeRoots) {
  Json document = triangle_document();
  document["nodes"] = Json::parse(R"([{"children": [1]}, {"mesh": 0}])");
  document["scenes"][0]["nodes"] = Json::array({0, 1});
  EXPECT_DIAGNOSTIC(check_document(document), "SCENE_NON_ROOT_NODE", "/scenes/0/nodes/1");
  document["scenes"][0]["nodes"] = Json::array({0, 0});
  EXPECT_DIAGNOSTIC(check_document(document), "DUPLICATE_ELEMENTS", "/scenes/0/nodes/1");
  document["scene"] = 1;
  EXPECT_DIAGNOSTIC(check_document(document), "UNRESOLVED_REFERENCE", "/scene");
}

// Users know their nodes by name: every node-graph error names them with their index.
TEST(ValidateDocument, NodeGraphErrorsNameTheNodes) {
  const auto message_of = [](const Diagnostics& diag, const std::string& code) {
    for (const Diagnostic& d : diag.all()) {
      if (d.code == code) return d.message;
    }
    return std::string("no ") + code;
  };
  Json document = triangle_document();
  document["nodes"] = Json::parse(
      R"([{"name": "base", "children": [1]}, {"name": "elbow", "children": [2]}, {"name": "hand", "children": [1]}])");
  document["scenes"][0]["nodes"] = Json::array({0});
  EXPECT_EQ(message_of(check_document(document), "NODE_LOOP"),
            "node 2 'hand' is its own descendant: the children lists form a loop");
  document["nodes"] = Json::parse(R"([{"name": "base", "children": [2]}, {"name": "tool", "children": [2]}, {"mesh": 0, "name": "hand"}])");
  document["scenes"][0]["nodes"] = Json::array({0, 1});
  EXPECT_EQ(message_of(check_document(document), "NODE_PARENT_OVERRIDE"),
            "node 2 'hand' is already a child of node 0 'base'; a node can have only one parent");
  document["nodes"] = Json::parse(R"([{"name": "base", "children": [1]}, {"mesh": 0}])");
  document["scenes"][0]["nodes"] = Json::array({0, 1});
  EXPECT_EQ(message_of(check_document(document), "SCENE_NON_ROOT_NODE"),
            "node 1 is a child of node 0 'base', so it cannot be a root of the scene");
  // A name that is not a string is invalid glTF (it was passed through into the output).
  document["nodes"] = Json::parse(R"([{"name": 12, "mesh": 0}])");
  document["scenes"][0]["nodes"] = Json::array({0});
  EXPECT_DIAGNOSTIC(check_document(document), "TYPE_MISMATCH", "/nodes/0/name");
}

TEST(ValidateDocument, UnresolvedReferences) {
  Json document = triangle_document();
  document["nodes"][0]["mesh"] = 1;
  document["nodes"][0]["children"] = Json::array({7});
  document["meshes"][0]["primitives"][0]["indices"] = 2;
  document["accessors"][0]["bufferView"] = 5;
  const Diagnostics diag = check_document(document);
  EXPECT_DIAGNOSTIC(diag, "UNRESOLVED_REFERENCE", "/nodes/0/mesh");
  EXPECT_DIAGNOSTIC(diag, "UNRESOLVED_REFERENCE", "/nodes/0/children/0");
  EXPECT_DIAGNOSTIC(diag, "UNRESOLVED_REFERENCE", "/meshes/0/primitives/0/indices");
  EXPECT_DIAGNOSTIC(diag, "UNRESOLVED_REFERENCE", "/accessors/0/bufferView");
}

TEST(ValidateDocument, NodeTransforms) {
  Json document = triangle_document();
  document["nodes"][0]["matrix"] = Json::array({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
  document["nodes"][0]["matrix"][5] = std::nan("");  // JSON cannot say NaN; a caller's Json can.
  EXPECT_DIAGNOSTIC(check_document(document), "VALUE_NOT_IN_RANGE", "/nodes/0/matrix/5");
  document["nodes"][0]["matrix"][5] = 1e300;  // Finite, but not as a float.
  EXPECT_DIAGNOSTIC(check_document(document), "VALUE_NOT_IN_RANGE", "/nodes/0/matrix/5");
  document["nodes"][0]["matrix"][5] = 1;
  document["nodes"][0]["matrix"][4] = 0.5;  // Shear.
  EXPECT_DIAGNOSTIC(check_document(document), "NODE_MATRIX_NON_TRS", "/nodes/0/matrix");
  document["nodes"][0]["matrix"].erase(15);
  EXPECT_DIAGNOSTIC(check_document(document), "ARRAY_LENGTH_NOT_IN_LIST", "/nodes/0/matrix");

  document = triangle_document();
  document["nodes"][0]["matrix"] = Json::array({2, 0, 0, 0, 0, 0, 3, 0, 0, -1, 0, 0, 5, 6, 7, 1});
  EXPECT_EQ(check_document(document).error_count(), 0u) << listing(check_document(document));
  document["nodes"][0]["translation"] = Json::array({0, 0, 0});
  EXPECT_DIAGNOSTIC(check_document(document), "NODE_MATRIX_TRS", "/nodes/0/matrix");

  document = triangle_document();
  document["nodes"][0]["rotation"] = Json::array({0, 0, 0, 0.5});
  EXPECT_DIAGNOSTIC(check_document(document), "ROTATION_NON_UNIT", "/nodes/0/rotation");
  document["nodes"][0]["scale"] = Json::array({1, 1});
  EXPECT_DIAGNOSTIC(check_document(document), "ARRAY_LENGTH_NOT_IN_LIST", "/nodes/0/scale");
}

// A transform error names the node by index and name, shows the value and says what is wrong.
TEST(ValidateDocument, NodeTransformErrorsNameTheNodeTheValueAndWhy) {
  const auto message = [](const Json& document, const std::string& code) {
    const Diagnostics diag = check_document(document);
    for (const Diagnostic& d : diag.all()) {
      if (d.code == code) return d.message;
    }
    ADD_FAILURE() << "no " << code << ":\n" << listing(diag);
    return std::string();
  };
  const Json identity = Json::array({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
  Json document = triangle_document();
  document["nodes"][0]["matrix"] = identity;
  document["nodes"][0]["matrix"][4] = 0.5;
  EXPECT_EQ(message(document, "NODE_MATRIX_NON_TRS"),
            "node 0 'base': the matrix [1, 0, 0, 0, 0.5, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1] (column-major) is not a "
            "translation, rotation and scale: its x and y columns are not orthogonal (cosine 0.447213595): "
            "it shears; apply the transform in the modeller before export");
  document["nodes"][0]["matrix"] = identity;
  document["nodes"][0]["matrix"][10] = 0;
  EXPECT_NE(message(document, "NODE_MATRIX_NON_TRS").find("its z column has length 0: it collapses space"),
            std::string::npos);
  document["nodes"][0]["matrix"] = identity;
  document["nodes"][0]["matrix"][3] = 0.25;
  EXPECT_NE(message(document, "NODE_MATRIX_NON_TRS").find("its last row is (0.25, 0, 0, 1), not (0, 0, 0, 1): it projects"),
            std::string::npos);
  document["nodes"][0]["matrix"] = identity;
  document["nodes"][0]["scale"] = Json::array({1, 1, 1});
  EXPECT_EQ(message(document, "NODE_MATRIX_TRS"),
            "node 0 'base' has a matrix and translation/rotation/scale too; a node has either, not both");

  document = triangle_document();
  document["nodes"][0]["rotation"] = Json::array({0, 0, 0, 0.5});
  EXPECT_EQ(message(document, "ROTATION_NON_UNIT"),
            "node 0 'base': the rotation quaternion [0, 0, 0, 0.5] has length 0.5; it must be 1 (x, y, z, w of a "
            "unit quaternion)");

  // SHORT positions are valid glTF with KHR_mesh_quantization: the error says so.
  document = triangle_document();
  document["accessors"][0]["componentType"] = 5122;
  EXPECT_NE(message(document, "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT")
                .find("accessor 0 is VEC3 of SHORT; POSITION must be VEC3 of FLOAT (VEC3 of SHORT needs "
                      "KHR_mesh_quantization in extensionsUsed and extensionsRequired)"),
            std::string::npos);
}

TEST(ValidateDocument, WrongJsonTypesAreErrorsNotExceptions) {
  Json document = triangle_document();
  document["accessors"][0]["count"] = "3";
  document["accessors"][1]["normalized"] = 1;
  document["bufferViews"][0]["buffer"] = -1;
  document["nodes"][0]["children"] = "none";
  document["meshes"][0]["primitives"][0]["attributes"] = Json::array({0});
  document["buffers"][0]["uri"] = 5;
  document["scenes"] = Json::object();
  Diagnostics diag("inline.gltf");
  EXPECT_NO_THROW(validate_document(document, {}, diag));
  EXPECT_DIAGNOSTIC(diag, "TYPE_MISMATCH", "/accessors/0/count");
  EXPECT_DIAGNOSTIC(diag, "TYPE_MISMATCH", "/accessors/1/normalized");
  EXPECT_DIAGNOSTIC(diag, "VALUE_NOT_IN_RANGE", "/bufferViews/0/buffer");
  EXPECT_DIAGNOSTIC(diag, "TYPE_MISMATCH", "/nodes/0/children");
  EXPECT_DIAGNOSTIC(diag, "TYPE_MISMATCH", "/meshes/0/primitives/0/attributes");
  EXPECT_DIAGNOSTIC(diag, "TYPE_MISMATCH", "/buffers/0/uri");
  EXPECT_DIAGNOSTIC(diag, "TYPE_MISMATCH", "/scenes");

  for (const char* text :
       {"null", "[]", "3", "\"gltf\"", R"({"asset": 2})", R"({"asset": {"version": 2}})"}) {
    Diagnostics other("inline.gltf");
    EXPECT_NO_THROW(validate_document(Json::parse(text), {}, other)) << text;
    EXPECT_TRUE(other.has_errors()) << text;
  }
}

// Every value of a valid document, containers included, replaced by values of every JSON type,
// and every one removed: validate_document must report, never throw; whatever it accepts,
// validate_data must then check without throwing.
TEST(ValidateDocument, SurvivesEveryMutationOfAValidDocument) {
  const Json original = triangle_document();
  std::set<std::string> pointers;
  const Json flat = original.flatten();
  for (const auto& [leaf, value] : flat.items()) {
    for (auto pointer = Json::json_pointer(leaf); !pointer.empty();
         pointer = pointer.parent_pointer()) {
      pointers.insert(pointer.to_string());
    }
  }
  const std::vector<Json> replacements = {nullptr,
                                          true,
                                          -1,
                                          0,
                                          2,
                                          1.5,
                                          1e300,
                                          "x",
                                          Json::array(),
                                          Json::object(),
                                          Json::array({0}),
                                          std::uint64_t{1} << 63};
  const auto bytes = triangle_bytes({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2});
  std::size_t accepted = 0;
  const auto exercise = [&](const Json& mutated, const std::string& what) {
    Diagnostics diag("inline.gltf");
    EXPECT_NO_THROW(validate_document(mutated, {}, diag)) << what;
    if (diag.has_errors()) return;
    ++accepted;
    EXPECT_NO_THROW(validate_data(make_asset(mutated, {bytes}), diag)) << what;
  };
  for (const std::string& text : pointers) {
    const Json::json_pointer pointer(text);
    for (const Json& replacement : replacements) {
      Json mutated = original;
      mutated[pointer] = replacement;
      exercise(mutated, text + " = " + replacement.dump());
    }
    Json removed = original;
    Json& parent = removed[pointer.parent_pointer()];
    if (parent.is_object()) {
      parent.erase(pointer.back());
    } else {
      parent.erase(std::stoul(pointer.back()));
    }
    exercise(removed, "without " + text);
  }
  EXPECT_GT(accepted, 0u);  // Some mutations are harmless (names, targets, min/max values).
}

TEST(ValidateDocument, MissingAssetVersion) {
  Json document = triangle_document();
  document["asset"].erase("version");
  EXPECT_DIAGNOSTIC(check_document(document), "UNDEFINED_PROPERTY", "/asset");
  document["asset"]["version"] = "1.0";
  EXPECT_DIAGNOSTIC(check_document(document), "UNKNOWN_ASSET_MAJOR_VERSION", "/asset/version");
  document["asset"]["version"] = "2";
  EXPECT_DIAGNOSTIC(check_document(document), "PATTERN_MISMATCH", "/asset/version");
  document.erase("asset");
  EXPECT_DIAGNOSTIC(check_document(document), "UNDEFINED_PROPERTY", "");
}

TEST(ValidateDocument, MeshPrimitiveRules) {
  Json document = triangle_document();
  auto& primitive = document["meshes"][0]["primitives"][0];
  primitive["mode"] = 7;
  primitive["attributes"]["TEXCOORD_1"] = 0;
  primitive["attributes"]["Position"] = 0;
  Diagnostics diag = check_document(document);
  EXPECT_DIAGNOSTIC(diag, "VALUE_NOT_IN_RANGE", "/meshes/0/primitives/0/mode");
  EXPECT_DIAGNOSTIC(diag, "MESH_PRIMITIVE_INVALID_ATTRIBUTE",
                    "/meshes/0/primitives/0/attributes/Position");
  EXPECT_DIAGNOSTIC(diag, "MESH_PRIMITIVE_INDEXED_SEMANTIC_CONTINUITY",
                    "/meshes/0/primitives/0/attributes");

  document = triangle_document();
  document["meshes"][0]["primitives"][0]["indices"] = 0;  // VEC3 FLOAT as indices
  EXPECT_DIAGNOSTIC(check_document(document), "MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT",
                    "/meshes/0/primitives/0/indices");
  document = triangle_document();
  document["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 1;  // SCALAR as positions
  EXPECT_DIAGNOSTIC(check_document(document), "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT",
                    "/meshes/0/primitives/0/attributes/POSITION");
  document = triangle_document();
  document["buffers"][0]["byteLength"] = 48;
  document["bufferViews"][1]["byteStride"] = 4;
  document["bufferViews"][1]["byteLength"] = 12;
  EXPECT_DIAGNOSTIC(check_document(document), "MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE",
                    "/meshes/0/primitives/0/indices");
}

TEST(ValidateDocument, BufferDataUrisAndRequiredExtensions) {
  Json document = triangle_document();
  document["buffers"][0]["uri"] = "data:application/octet-stream;;base64,AA==";
  EXPECT_DIAGNOSTIC(check_document(document), "INVALID_URI", "/buffers/0/uri");
  document["buffers"][0]["uri"] = "data:text/plain;base64,AA==";
  EXPECT_DIAGNOSTIC(check_document(document), "BUFFER_DATA_URI_MIME_TYPE_INVALID",
                    "/buffers/0/uri");
  document["buffers"][0]["uri"] = "data:application/octet-stream;base64,AAAA";  // 3 bytes, not 44
  EXPECT_DIAGNOSTIC(check_document(document), "BUFFER_BYTE_LENGTH_MISMATCH",
                    "/buffers/0/byteLength");

  document = triangle_document();
  // Draco and meshopt are decoded, instancing is read; an extension that may hold geometry
  // elsewhere (here a made-up one) is refused.
  document["extensionsRequired"] =
      Json::array({"KHR_materials_unlit", "EXT_unknown_geometry", "KHR_draco_mesh_compression",
                   "EXT_meshopt_compression", "EXT_mesh_gpu_instancing"});
  document["extensionsUsed"] = document["extensionsRequired"];
  const Diagnostics diag = check_document(document);
  EXPECT_DIAGNOSTIC(diag, "UNSUPPORTED_EXTENSION", "/extensionsRequired/1");
  EXPECT_EQ(diag.error_count(), 1u) << listing(diag);
  // Every required extension is also used (glTF 2.0).
  document["extensionsUsed"].erase(0);
  EXPECT_DIAGNOSTIC(check_document(document), "UNUSED_EXTENSION_REQUIRED", "/extensionsRequired/0");
}

TEST(ValidateDocument, SkinsAreTreesInTheirScene) {
  Json document = triangle_document();
  document["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = 2;
  document["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"] = 3;
  document["accessors"].push_back(
      Json::parse(R"({"componentType": 5121, "count": 3, "type": "VEC4"})"));
  document["accessors"].push_back(
      Json::parse(R"({"componentType": 5126, "count": 3, "type": "VEC4"})"));
  document["nodes"] = Json::parse(R"([{"mesh": 0, "skin": 0}, {"children": [2]}, {}, {}])");
  document["scenes"] = Json::parse(R"([{"nodes": [0, 1]}, {"nodes": [0]}])");
  document["skins"] = Json::parse(R"([{"joints": [1, 2]}])");
  const Diagnostics valid = check_document(document);
  EXPECT_DIAGNOSTIC(valid, "NODE_SKIN_NO_SCENE", "/nodes/0");  // Scene 1 lacks the joints.
  EXPECT_EQ(valid.error_count(), 1u) << listing(valid);
  document["skins"][0]["skeleton"] = 2;
  EXPECT_DIAGNOSTIC(check_document(document), "SKIN_SKELETON_INVALID", "/skins/0/skeleton");
  document["skins"][0] = Json::parse(R"({"joints": [1, 3]})");
  EXPECT_DIAGNOSTIC(check_document(document), "SKIN_NO_COMMON_ROOT", "/skins/0/joints");
}

TEST(ValidateData, IndexOutOfRange) {
  const GltfAsset asset =
      make_asset(triangle_document(), {triangle_bytes({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 3})});
  EXPECT_DIAGNOSTIC(check_data(asset), "ACCESSOR_INDEX_OOB", "/meshes/0/primitives/0/indices");
  const GltfAsset restart =
      make_asset(triangle_document(), {triangle_bytes({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 65535})});
  EXPECT_DIAGNOSTIC(check_data(restart), "ACCESSOR_INDEX_PRIMITIVE_RESTART",
                    "/meshes/0/primitives/0/indices");
}

TEST(ValidateData, PositionsAreFiniteAndWithinTheirBounds) {
  const float nan = std::nanf("");
  const GltfAsset not_finite =
      make_asset(triangle_document(), {triangle_bytes({0, 0, 0, nan, 0, 0, 0, 1, 0}, {0, 1, 2})});
  EXPECT_DIAGNOSTIC(check_data(not_finite), "ACCESSOR_INVALID_FLOAT", "/accessors/0");
  const GltfAsset outside =
      make_asset(triangle_document(), {triangle_bytes({0, 0, 0, 1.5f, 0, 0, 0, 1, -2}, {0, 1, 2})});
  const Diagnostics diag = check_data(outside);
  EXPECT_DIAGNOSTIC(diag, "ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND", "/accessors/0/max/0");
  EXPECT_DIAGNOSTIC(diag, "ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND", "/accessors/0/min/2");
  // Declared bounds are float32: 0.1 in the JSON bounds the float nearest 0.1.
  Json document = triangle_document();
  document["accessors"][0]["max"] = Json::array({1, 1, 0.1});
  const GltfAsset rounded =
      make_asset(document, {triangle_bytes({0, 0, 0, 1, 0, 0, 0, 1, 0.1f}, {0, 1, 2})});
  const Diagnostics clean = check_data(rounded);
  EXPECT_FALSE(clean.has_errors()) << listing(clean);
}

TEST(ValidateData, BufferShorterThanItsByteLength) {
  auto bytes = triangle_bytes({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2});
  bytes.resize(40);
  Diagnostics diag("inline.gltf");
  validate_data(make_asset(triangle_document(), {bytes}), diag);
  EXPECT_DIAGNOSTIC(diag, "BUFFER_BYTE_LENGTH_MISMATCH", "/buffers/0");
  Diagnostics missing("inline.gltf");
  validate_data(make_asset(triangle_document(), {}), missing);
  EXPECT_DIAGNOSTIC(missing, "BUFFER_BYTE_LENGTH_MISMATCH", "/buffers/0");
}

// Sparse accessor: no bufferView (zeros), two rows replaced; indices at bytes 36-39, values 40-63.
Json sparse_document(std::uint16_t first, std::uint16_t second, std::vector<std::uint8_t>& bytes) {
  Json document = triangle_document();
  document["accessors"][0] = Json::parse(R"({"componentType": 5126, "count": 3, "type": "VEC3",
    "min": [0, 0, 0], "max": [1, 1, 0],
    "sparse": {"count": 2, "indices": {"bufferView": 2, "componentType": 5123}, "values": {"bufferView": 3}}})");
  document["meshes"][0]["primitives"][0].erase("indices");
  document["bufferViews"] = Json::parse(
      R"([{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6},
    {"buffer": 0, "byteOffset": 36, "byteLength": 4}, {"buffer": 0, "byteOffset": 40, "byteLength": 24}])");
  document["buffers"][0]["byteLength"] = 64;
  bytes.assign(36, 0);
  append(bytes, first);
  append(bytes, second);
  for (float value : {1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) append(bytes, value);
  return document;
}

TEST(ValidateData, SparseIndices) {
  std::vector<std::uint8_t> bytes;
  Json document = sparse_document(1, 2, bytes);
  const Diagnostics valid = check_data(make_asset(document, {bytes}));
  EXPECT_FALSE(valid.has_errors()) << listing(valid);
  document = sparse_document(2, 1, bytes);
  EXPECT_DIAGNOSTIC(check_data(make_asset(document, {bytes})),
                    "ACCESSOR_SPARSE_INDICES_NON_INCREASING", "/accessors/0/sparse");
  document = sparse_document(1, 3, bytes);
  EXPECT_DIAGNOSTIC(check_data(make_asset(document, {bytes})), "ACCESSOR_SPARSE_INDEX_OOB",
                    "/accessors/0/sparse");
  document = sparse_document(0, 1, bytes);  // The zero left at row 2 is within min/max; max y = 1.
  document["accessors"][0]["max"] = Json::array({1, 0.5, 0});
  EXPECT_DIAGNOSTIC(check_data(make_asset(document, {bytes})), "ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND",
                    "/accessors/0/max/1");
}

// Three of the validator's rules rdtf did not have, each of which it copied into an output the
// validator then refused (s80valid): KHR_mesh_quantization listed as optional, integer bounds no
// value of the type can hold, and morph weights animated on a mesh without morph targets.
TEST(ValidateDocument, QuantizationIsRequiredIntegerBoundsFitAndWeightsNeedMorphs) {
  Json doc = triangle_document();
  doc["extensionsUsed"] = {"KHR_mesh_quantization"};
  EXPECT_DIAGNOSTIC(check_document(doc), "NON_REQUIRED_EXTENSION", "/extensionsUsed/0");
  doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  EXPECT_FALSE(check_document(doc).has_errors()) << listing(check_document(doc));

  doc = triangle_document();
  doc["accessors"][1]["min"] = {0};
  doc["accessors"][1]["max"] = {70000};  // UNSIGNED_SHORT indices
  EXPECT_DIAGNOSTIC(check_document(doc), "INVALID_GL_VALUE", "/accessors/1/max");
  doc["accessors"][1]["min"] = {-1};
  EXPECT_DIAGNOSTIC(check_document(doc), "INVALID_GL_VALUE", "/accessors/1/min");
  doc["accessors"][1]["min"] = {0};
  doc["accessors"][1]["max"] = {2.5};
  EXPECT_DIAGNOSTIC(check_document(doc), "ARRAY_TYPE_MISMATCH", "/accessors/1/max");
  doc["accessors"][1]["max"] = {2.0};  // An integer written as a float is an integer.
  EXPECT_FALSE(check_document(doc).has_errors()) << listing(check_document(doc));

  doc = triangle_document();
  doc["accessors"].push_back({{"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}, {"min", {0}}, {"max", {1}}});
  doc["accessors"].push_back({{"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}});
  doc["animations"] = Json::array({{{"channels", Json::array({{{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}}})},
                                    {"samplers", Json::array({{{"input", 2}, {"output", 3}}})}}});
  const Diagnostics no_morphs = check_document(doc);
  EXPECT_DIAGNOSTIC(no_morphs, "ANIMATION_CHANNEL_TARGET_NODE_WEIGHTS_NO_MORPHS", "/animations/0/channels/0/target");
  doc["meshes"][0]["primitives"][0]["targets"] = Json::array({{{"POSITION", 0}}});
  EXPECT_FALSE(has_error(check_document(doc), "ANIMATION_CHANNEL_TARGET_NODE_WEIGHTS_NO_MORPHS",
                         "/animations/0/channels/0/target"))
      << listing(check_document(doc));
}

// One fault, one error: an empty extensionsUsed was an EMPTY_ENTITY twice (s80valid D9), and a
// refused JOINTS_0 accessor made the node's skin a second error (s80rev R5).
TEST(ValidateDocument, OneFaultIsOneError) {
  const auto count = [](const Diagnostics& diag, const std::string& code) {
    return std::count_if(diag.all().begin(), diag.all().end(), [&](const Diagnostic& d) { return d.code == code; });
  };
  Json doc = triangle_document();
  doc["extensionsUsed"] = Json::array();
  const Diagnostics empty = check_document(doc);
  EXPECT_EQ(count(empty, "EMPTY_ENTITY"), 1) << listing(empty);
  doc = triangle_document();
  // JOINTS_0 on an accessor of an invalid bound; the node's skin names two joint nodes.
  doc["accessors"].push_back({{"componentType", 5121}, {"count", 3}, {"type", "VEC4"}, {"min", {0, 0, 0, 0}},
                              {"max", {256, 0, 0, 0}}});
  doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = doc["accessors"].size() - 1;
  doc["nodes"].push_back({{"name", "bone"}});
  doc["skins"] = Json::array({{{"joints", {1}}}});
  doc["nodes"][0]["skin"] = 0;
  const Diagnostics refused = check_document(doc);
  EXPECT_DIAGNOSTIC(refused, "INVALID_GL_VALUE", "/accessors/2/max");
  EXPECT_EQ(count(refused, "NODE_SKIN_WITH_NON_SKINNED_MESH"), 0) << listing(refused);
}

}  // namespace
}  // namespace rdtf
