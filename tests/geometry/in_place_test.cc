// Issue 6's fast paths against the general ones they stand in for, on the same data:
// - a GLB whose only buffer is its BIN chunk is loaded without tinygltf, from a file (the chunk
//   moved to the front of the file's bytes) or from memory (copied): the same buffer bytes, and
//   the same diagnostics as tinygltf's whenever it would refuse the chunk;
// - read_primitive_in_place (triangles read where they lie in the buffers) against
//   read_primitive_triangles: the same triangles, positions and diagnostics, read in place
//   exactly where the layout allows it;
// - validate_data's packed index and float scans against its element-by-element path, reached
//   by giving the same accessor a sparse part that substitutes the values it already has: the
//   same diagnostics, word for word.

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rdtf/diagnostics.h"
#include "rdtf/geometry.h"
#include "rdtf/glb.h"
#include "rdtf/gltf.h"
#include "rdtf/validate.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

template <typename T>
void put(std::vector<std::uint8_t>& bytes, std::size_t offset, T value) {
  if (bytes.size() < offset + sizeof(T)) bytes.resize(offset + sizeof(T), 0xEE);
  std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

GltfAsset make_asset(const Json& document, std::vector<std::uint8_t> bytes) {
  GltfAsset asset;
  asset.path = "inline.gltf";
  asset.document = document;
  bytes.resize((bytes.size() + 3) / 4 * 4, 0xEE);
  asset.document["buffers"] = Json::array({{{"byteLength", bytes.size()}}});
  asset.buffers.push_back(std::move(bytes));
  return asset;
}

std::string listing(const Diagnostics& diag) {
  std::string text;
  for (const Diagnostic& d : diag.all()) text += "  " + format(d) + "\n";
  return text.empty() ? "  (none)\n" : text;
}

void expect_same_diagnostics(const Diagnostics& got, const Diagnostics& want) {
  EXPECT_EQ(listing(got), listing(want));
}

// ------------------------------------------------------------------------------------------------
// The GLB's BIN chunk as the only buffer.

// A one-triangle GLB whose buffer declares `byte_length` bytes; the BIN chunk holds `bin` (padded
// to 4 bytes by make_glb), or there is none.
std::vector<std::uint8_t> triangle_glb(std::uint64_t byte_length, const std::vector<std::uint8_t>& bin) {
  const Json document = Json::parse(R"({
    "asset": {"version": "2.0"},
    "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                   "min": [0, 0, 0], "max": [1, 1, 0]}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}]
  })");
  Json with_buffer = document;
  with_buffer["buffers"] = Json::array({{{"byteLength", byte_length}}});
  return make_glb(with_buffer.dump(), bin);
}

std::vector<std::uint8_t> triangle_bin(std::size_t extra) {
  std::vector<std::uint8_t> bytes;
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  for (int k = 0; k < 9; ++k) put(bytes, 4 * k, xyz[k]);
  for (std::size_t k = 0; k < extra; ++k) bytes.push_back(static_cast<std::uint8_t>(0xC0 + k));
  return bytes;
}

struct Loaded {
  std::optional<GltfAsset> asset;
  std::string diagnostics;
};

Loaded load_from_file(const std::vector<std::uint8_t>& glb) {
  const testing::TempDir folder;
  testing::write_file(folder / "model.glb", std::string(glb.begin(), glb.end()));
  Diagnostics diag;
  Loaded loaded{load_gltf(folder / "model.glb", LoadLimits{}, diag), {}};
  const std::string path = (folder / "model.glb").string();
  for (const Diagnostic& d : diag.all()) {
    std::string line = format(d);
    // Named as the in-memory load names it.
    if (line.rfind(path, 0) == 0) line = "model.glb" + line.substr(path.size());
    loaded.diagnostics += line + "\n";
  }
  return loaded;
}

Loaded load_from_memory(const std::vector<std::uint8_t>& glb) {
  Diagnostics diag;
  Loaded loaded{load_gltf_from_memory(glb, "model.glb", {}, LoadLimits{}, diag), {}};
  for (const Diagnostic& d : diag.all()) loaded.diagnostics += format(d) + "\n";
  return loaded;
}

TEST(Triangles, GlbBinChunkBecomesTheBufferWithoutACopyThroughTinygltf) {
  // byteLength 36 of a 40-byte chunk (4 bytes the buffer does not claim), and exactly 36.
  for (const std::size_t extra : {std::size_t{4}, std::size_t{0}}) {
    SCOPED_TRACE(::testing::Message() << extra << " bytes past byteLength");
    const auto bin = triangle_bin(extra);
    const auto glb = triangle_glb(36, bin);
    for (const Loaded& loaded : {load_from_file(glb), load_from_memory(glb)}) {
      ASSERT_TRUE(loaded.asset.has_value()) << loaded.diagnostics;
      ASSERT_EQ(loaded.asset->buffers.size(), 1u);
      EXPECT_EQ(loaded.asset->buffers[0], std::vector<std::uint8_t>(bin.begin(), bin.begin() + 36));
      EXPECT_EQ(loaded.diagnostics, "");
      Diagnostics diag;
      const auto mesh = read_primitive_in_place(*loaded.asset, 0, 0, diag);
      ASSERT_TRUE(mesh.has_value());
      EXPECT_FALSE(mesh->copy.has_value());
      EXPECT_EQ(mesh->mesh().positions[1], Eigen::Vector3d(1, 0, 0));
    }
  }
}

// What tinygltf refuses still goes to tinygltf, which says why, from a file or from memory alike.
TEST(Triangles, GlbBinChunksTinygltfRefusesAreRefusedAsBefore) {
  const auto bin = triangle_bin(0);
  for (const auto& glb : {triangle_glb(40, bin), triangle_glb(36, {})}) {
    const Loaded from_file = load_from_file(glb), from_memory = load_from_memory(glb);
    EXPECT_FALSE(from_file.asset.has_value());
    EXPECT_FALSE(from_memory.asset.has_value());
    EXPECT_EQ(from_file.diagnostics, from_memory.diagnostics);
    EXPECT_NE(from_memory.diagnostics, "");
  }
}

// ------------------------------------------------------------------------------------------------
// read_primitive_in_place.

// Checks primitive p both ways; returns whether it was read in place.
bool read_both_ways(const GltfAsset& asset, std::size_t p) {
  SCOPED_TRACE(::testing::Message() << "primitive " << p);
  Diagnostics copied_diag("inline.gltf"), in_place_diag("inline.gltf");
  const auto copied = read_primitive_triangles(asset, 0, p, copied_diag);
  const auto in_place = read_primitive_in_place(asset, 0, p, in_place_diag);
  expect_same_diagnostics(in_place_diag, copied_diag);
  EXPECT_EQ(in_place.has_value(), copied.has_value());
  if (!in_place || !copied) return false;
  const TriangleMesh mesh = in_place->mesh();
  EXPECT_EQ(mesh.positions, copied->positions);
  EXPECT_EQ(mesh.triangles, copied->triangles);
  const TriangleMeshView view = in_place->view();
  EXPECT_EQ(view.vertex_count, copied->positions.size());
  EXPECT_EQ(view.triangle_count, copied->triangles.size());
  return !in_place->copy.has_value();
}

// Five vertices (interleaved with a normal: stride 24 from byte 8) and 8/16/32-bit index views,
// used by primitives of every kind.
GltfAsset primitives_asset() {
  std::vector<std::uint8_t> bytes;
  const float xyz[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  for (int v = 0; v < 5; ++v)
    for (int c = 0; c < 3; ++c) put(bytes, 8 + 24 * v + 4 * c, xyz[v][c]);
  const std::uint32_t order[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 4};  // 13: one too many for 4 triangles.
  for (int k = 0; k < 13; ++k) {
    put(bytes, 128 + k, static_cast<std::uint8_t>(order[k]));
    put(bytes, 144 + 2 * k, static_cast<std::uint16_t>(order[k]));
    put(bytes, 172 + 4 * k, order[k]);
  }
  put(bytes, 224, std::uint8_t{3});  // A sparse index (row 3) ...
  put(bytes, 228, 2.0f), put(bytes, 232, 2.0f), put(bytes, 236, 2.0f);  // ... and its value.
  const Json document = Json::parse(R"({
    "asset": {"version": "2.0"},
    "bufferViews": [
      {"buffer": 0, "byteOffset": 8, "byteLength": 120, "byteStride": 24},
      {"buffer": 0, "byteOffset": 128, "byteLength": 13},
      {"buffer": 0, "byteOffset": 144, "byteLength": 26},
      {"buffer": 0, "byteOffset": 172, "byteLength": 52},
      {"buffer": 0, "byteOffset": 224, "byteLength": 1},
      {"buffer": 0, "byteOffset": 228, "byteLength": 12}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3"},
      {"bufferView": 1, "componentType": 5121, "count": 12, "type": "SCALAR"},
      {"bufferView": 2, "componentType": 5123, "count": 12, "type": "SCALAR"},
      {"bufferView": 3, "componentType": 5125, "count": 12, "type": "SCALAR"},
      {"bufferView": 3, "byteOffset": 4, "componentType": 5125, "count": 10, "type": "SCALAR"},
      {"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3",
       "sparse": {"count": 1, "indices": {"bufferView": 4, "componentType": 5121},
                  "values": {"bufferView": 5}}},
      {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
    "meshes": [{"primitives": [
      {"attributes": {"POSITION": 0}, "indices": 1},
      {"attributes": {"POSITION": 0}, "indices": 2, "mode": 4},
      {"attributes": {"POSITION": 0}, "indices": 3},
      {"attributes": {"POSITION": 0}, "indices": 4},
      {"attributes": {"POSITION": 0}},
      {"attributes": {"POSITION": 6}},
      {"attributes": {"POSITION": 0}, "indices": 2, "mode": 5},
      {"attributes": {"POSITION": 0}, "indices": 2, "mode": 6},
      {"attributes": {"POSITION": 5}, "indices": 2},
      {"attributes": {"POSITION": 0}, "indices": 2, "mode": 1},
      {"attributes": {"NORMAL": 0}, "indices": 2}]}]
  })");
  return make_asset(document, bytes);
}

TEST(Triangles, ReadInPlaceWhereTheLayoutAllows) {
  const GltfAsset asset = primitives_asset();
  // TRIANGLES over dense float positions (strided) and dense unsigned indices of each width,
  // from an offset, with a count that is not a multiple of 3 (the same warning), or no indices.
  EXPECT_TRUE(read_both_ways(asset, 0));
  EXPECT_TRUE(read_both_ways(asset, 1));
  EXPECT_TRUE(read_both_ways(asset, 2));
  EXPECT_TRUE(read_both_ways(asset, 3));
  EXPECT_TRUE(read_both_ways(asset, 4));
  EXPECT_TRUE(read_both_ways(asset, 5));
  // Copied out: strips, fans, sparse positions; nothing (with the same info) for lines and for
  // a primitive without POSITION.
  EXPECT_FALSE(read_both_ways(asset, 6));
  EXPECT_FALSE(read_both_ways(asset, 7));
  EXPECT_FALSE(read_both_ways(asset, 8));
  EXPECT_FALSE(read_both_ways(asset, 9));
  EXPECT_FALSE(read_both_ways(asset, 10));
}

// ------------------------------------------------------------------------------------------------
// validate_data: packed scans against the element-by-element path.

// One primitive: `vertices` float positions (accessor 0, bounds as given) and indices of type T
// (accessor 1). With `general`, each accessor gets a sparse part that puts back the value its
// element 0 already has, which sends it down validate_data's element-by-element path.
template <typename T>
GltfAsset data_asset(const std::vector<std::array<float, 3>>& vertices, const std::vector<T>& indices,
                     const Json& min, const Json& max, bool general) {
  std::vector<std::uint8_t> bytes;
  for (std::size_t v = 0; v < vertices.size(); ++v)
    for (int c = 0; c < 3; ++c) put(bytes, 12 * v + 4 * c, vertices[v][c]);
  const std::size_t index_at = (bytes.size() + 3) / 4 * 4;
  for (std::size_t k = 0; k < indices.size(); ++k) put(bytes, index_at + sizeof(T) * k, indices[k]);
  const std::size_t sparse_at = (index_at + sizeof(T) * indices.size() + 3) / 4 * 4;
  put(bytes, sparse_at, std::uint8_t{0});  // Row 0, for both sparse parts.
  for (int c = 0; c < 3; ++c) put(bytes, sparse_at + 4 + 4 * c, vertices[0][c]);
  put(bytes, sparse_at + 16, indices[0]);
  constexpr int kType = sizeof(T) == 1 ? 5121 : sizeof(T) == 2 ? 5123 : 5125;
  Json document = {
      {"asset", {{"version", "2.0"}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 12 * vertices.size()}},
        {{"buffer", 0}, {"byteOffset", index_at}, {"byteLength", sizeof(T) * indices.size()}},
        {{"buffer", 0}, {"byteOffset", sparse_at}, {"byteLength", 1}},
        {{"buffer", 0}, {"byteOffset", sparse_at + 4}, {"byteLength", 12}},
        {{"buffer", 0}, {"byteOffset", sparse_at + 16}, {"byteLength", sizeof(T)}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", vertices.size()}, {"type", "VEC3"},
         {"min", min}, {"max", max}},
        {{"bufferView", 1}, {"componentType", kType}, {"count", indices.size()}, {"type", "SCALAR"}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}}};
  if (general) {
    document["accessors"][0]["sparse"] = {{"count", 1},
                                          {"indices", {{"bufferView", 2}, {"componentType", 5121}}},
                                          {"values", {{"bufferView", 3}}}};
    document["accessors"][1]["sparse"] = {{"count", 1},
                                          {"indices", {{"bufferView", 2}, {"componentType", 5121}}},
                                          {"values", {{"bufferView", 4}}}};
  }
  return make_asset(document, bytes);
}

template <typename T>
Diagnostics check_data(const std::vector<std::array<float, 3>>& vertices, const std::vector<T>& indices,
                       const Json& min, const Json& max, bool general) {
  Diagnostics diag("inline.gltf");
  validate_data(data_asset(vertices, indices, min, max, general), diag);
  return diag;
}

template <typename T>
void expect_both_paths_agree(const std::vector<std::array<float, 3>>& vertices, const std::vector<T>& indices,
                             const Json& min, const Json& max, const std::vector<std::string>& must_say) {
  const Diagnostics fast = check_data(vertices, indices, min, max, false);
  const Diagnostics general = check_data(vertices, indices, min, max, true);
  expect_same_diagnostics(fast, general);
  const std::string text = listing(fast);
  for (const std::string& phrase : must_say) EXPECT_NE(text.find(phrase), std::string::npos) << phrase << " in\n" << text;
}

const std::vector<std::array<float, 3>> kFour = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

TEST(ValidateData, PackedIndexScanSaysWhatTheGeneralPathSays) {
  const Json lo = {0, 0, 0}, hi = {1, 1, 1};
  // Clean, for every width.
  expect_both_paths_agree<std::uint8_t>(kFour, {0, 1, 2, 3, 2, 1}, lo, hi, {});
  expect_both_paths_agree<std::uint16_t>(kFour, {0, 1, 2, 3, 2, 1}, lo, hi, {});
  expect_both_paths_agree<std::uint32_t>(kFour, {0, 1, 2, 3, 2, 1}, lo, hi, {});
  // Out of range: the first element holding the largest index is named.
  expect_both_paths_agree<std::uint16_t>(kFour, {0, 1, 9, 3, 9, 1}, lo, hi,
                                         {"ACCESSOR_INDEX_OOB", "refers to vertex 9 (element 2)"});
  // Restart values (the type's largest), counted, the first one named; the largest other index
  // is still checked.
  expect_both_paths_agree<std::uint16_t>(kFour, {0, 1, 2, 2, 65535, 7, 65535, 1, 3}, lo, hi,
                                         {"2 times, first at element 4", "refers to vertex 7 (element 5)"});
  expect_both_paths_agree<std::uint8_t>(kFour, {0, 255, 2}, lo, hi, {"1 time, first at element 1"});
  expect_both_paths_agree<std::uint32_t>(kFour, {0, 1, 4294967295u}, lo, hi, {"first at element 2"});
  // Nothing but restart values: no index to compare with the vertex count.
  expect_both_paths_agree<std::uint16_t>(kFour, {65535, 65535, 65535}, lo, hi, {"3 times, first at element 0"});
}

TEST(ValidateData, PackedFloatScanSaysWhatTheGeneralPathSays) {
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::nanf("");
  const std::vector<std::uint16_t> triangle = {0, 1, 2};
  // Clean, exact bounds.
  expect_both_paths_agree(kFour, triangle, Json{0, 0, 0}, Json{1, 1, 1}, {});
  // Loose bounds: warnings naming the actual ones.
  expect_both_paths_agree(kFour, triangle, Json{-1, 0, 0}, Json{1, 2, 1},
                          {"ACCESSOR_MIN_MISMATCH", "ACCESSOR_MAX_MISMATCH"});
  // Elements outside the bounds, counted per component.
  expect_both_paths_agree<std::uint16_t>({{0, 0, 0}, {1.5f, 0, -2}, {0, 1, 0}, {3, 0, 1}}, triangle, Json{0, 0, 0},
                                         Json{1, 1, 1},
                                         {"2 elements have component 0 above the declared max",
                                          "1 element has component 2 below the declared min"});
  // NaN and infinities: counted, the first element named; they take no part in min and max.
  expect_both_paths_agree<std::uint16_t>({{0, 0, 0}, {1, 0, 0}, {0, nan, 0}, {inf, 0, -inf}}, triangle,
                                         Json{0, 0, 0}, Json{1, 1, 1},
                                         {"3 components are NaN or infinite, the first in element 2"});
  // Signed zeros: -0 and 0 both within [0, 1]; the actual min printed as the first one met.
  expect_both_paths_agree<std::uint16_t>({{-0.0f, 0, 0}, {0, 0, 0}, {1, 1, 1}}, triangle, Json{-1, 0, 0},
                                         Json{1, 1, 1}, {"ACCESSOR_MIN_MISMATCH"});
}

}  // namespace
}  // namespace rdtf
