// read_accessor and read_primitive_triangles on small glTF assets built in memory (glTF 2.0
// sections 3.6 accessors, 3.7.2.1 primitive topology), and node transforms (section 3.5.3).
//
// Assets are built two ways: a GltfAsset filled directly (document parsed from an inline string,
// buffer bytes packed with memcpy at the offsets the document names), and a whole .gltf with a
// base64 data: URI buffer given to load_gltf_from_memory.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "rdtf/diagnostics.h"
#include "rdtf/geometry.h"
#include "rdtf/gltf.h"
#include "rdtf/triangle_mesh.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

using Eigen::Vector3d;
using Triangle = std::array<std::uint32_t, 3>;

constexpr int kByte = 5120;
constexpr int kUnsignedByte = 5121;
constexpr int kShort = 5122;
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;

// ------------------------------------------------------------------------------------------------
// Building assets.

// Buffer bytes written at explicit offsets; bytes never written hold 0xEE, so reading padding or
// the wrong stride shows up as garbage.
struct Bytes {
  std::vector<std::uint8_t> data;
  template <typename T>
  void put(std::size_t offset, T value) {
    if (data.size() < offset + sizeof(T)) data.resize(offset + sizeof(T), 0xEE);
    std::memcpy(data.data() + offset, &value, sizeof(T));
  }
  // Consecutive values of one type from `offset`, each `stride` bytes apart (0: tightly packed).
  template <typename T>
  void put_all(std::size_t offset, const std::vector<T>& values, std::size_t stride = 0) {
    if (stride == 0) stride = sizeof(T);
    for (std::size_t i = 0; i < values.size(); ++i) put(offset + i * stride, values[i]);
  }
  // Float VEC3 elements from `offset`, `stride` bytes apart (0: tightly packed).
  void put_vec3(std::size_t offset, const std::vector<Vector3d>& values, std::size_t stride = 0) {
    if (stride == 0) stride = 12;
    for (std::size_t i = 0; i < values.size(); ++i) {
      for (int c = 0; c < 3; ++c) {
        put(offset + i * stride + 4 * static_cast<std::size_t>(c), static_cast<float>(values[i][c]));
      }
    }
  }
  void pad_to(std::size_t size) {
    if (data.size() < size) data.resize(size, 0xEE);
  }
};

std::string substitute(std::string text, const std::vector<std::pair<std::string, std::string>>& values) {
  for (const auto& [key, value] : values) {
    for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at)) {
      text.replace(at, key.size(), value);
      at += value.size();
    }
  }
  return text;
}

// The document (whose single buffer's byteLength must equal the bytes' size) and its buffer.
GltfAsset make_asset(const std::string& json, const Bytes& bytes) {
  GltfAsset asset;
  asset.document = Json::parse(json);
  asset.buffers.push_back(bytes.data);
  EXPECT_EQ(asset.document["buffers"][0]["byteLength"].get<std::size_t>(), bytes.data.size())
      << "fixture's byteLength does not match its bytes";
  return asset;
}

TriangleMesh read_triangles(const GltfAsset& asset, std::size_t mesh, std::size_t primitive) {
  Diagnostics diag;
  auto triangles = read_primitive_triangles(asset, mesh, primitive, diag);
  EXPECT_TRUE(triangles.has_value());
  EXPECT_TRUE(diag.all().empty()) << (diag.all().empty() ? "" : format(diag.all().front()));
  return triangles ? *triangles : TriangleMesh{};
}

// Triangles compared in order; each up to a cyclic rotation of its corners (which keeps the
// winding), never up to a swap (which reverses it).
void expect_triangles(const std::vector<Triangle>& actual, const std::vector<Triangle>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < actual.size(); ++i) {
    const Triangle& e = expected[i];
    const bool same = actual[i] == e || actual[i] == Triangle{e[1], e[2], e[0]} ||
                      actual[i] == Triangle{e[2], e[0], e[1]};
    EXPECT_TRUE(same) << "triangle " << i << ": (" << actual[i][0] << ", " << actual[i][1] << ", "
                      << actual[i][2] << ") expected (" << e[0] << ", " << e[1] << ", " << e[2]
                      << ") or a rotation of it";
  }
}

void expect_positions(const TriangleMesh& mesh, const std::vector<Vector3d>& expected) {
  ASSERT_EQ(mesh.positions.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(mesh.positions[i], expected[i]) << "position " << i << ": ["
                                              << mesh.positions[i].transpose() << "]";
  }
}

// z component of each triangle's normal (b - a) x (c - a).
std::vector<double> normal_z(const TriangleMesh& mesh) {
  std::vector<double> z;
  for (const Triangle& t : mesh.triangles) {
    const Vector3d& a = mesh.positions[t[0]];
    z.push_back((mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).z());
  }
  return z;
}

// ------------------------------------------------------------------------------------------------
// TRIANGLES.

// Four float positions (48 bytes at 0), then an index view at 48 that starts with 4 bytes the
// accessor skips (accessor byteOffset 4), then six indices.
TEST(Triangles, IndexedTrianglesWithEveryIndexType) {
  const std::vector<Vector3d> positions{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.5}};
  for (const int type : {kUnsignedByte, kUnsignedShort, kUnsignedInt}) {
    SCOPED_TRACE(::testing::Message() << "componentType " << type);
    const std::size_t size = type == kUnsignedByte ? 1 : type == kUnsignedShort ? 2 : 4;
    Bytes bytes;
    bytes.put_vec3(0, positions);
    const std::vector<std::uint32_t> indices{3, 1, 0, 0, 2, 3};
    for (std::size_t i = 0; i < indices.size(); ++i) {
      const std::size_t at = 52 + i * size;
      if (size == 1) bytes.put(at, static_cast<std::uint8_t>(indices[i]));
      if (size == 2) bytes.put(at, static_cast<std::uint16_t>(indices[i]));
      if (size == 4) bytes.put(at, indices[i]);
    }
    const std::size_t length = 52 + 6 * size;
    const auto asset = make_asset(substitute(R"({
      "asset": {"version": "2.0"},
      "buffers": [{"byteLength": @LENGTH@}],
      "bufferViews": [
        {"buffer": 0, "byteOffset": 0, "byteLength": 48},
        {"buffer": 0, "byteOffset": 48, "byteLength": @VIEW@}],
      "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
         "min": [0, 0, 0], "max": [1, 1, 0.5]},
        {"bufferView": 1, "byteOffset": 4, "componentType": @TYPE@, "count": 6, "type": "SCALAR"}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}]
    })", {{"@LENGTH@", std::to_string(length)}, {"@VIEW@", std::to_string(length - 48)},
          {"@TYPE@", std::to_string(type)}}), bytes);
    const TriangleMesh mesh = read_triangles(asset, 0, 0);
    expect_positions(mesh, positions);
    expect_triangles(mesh.triangles, {{3, 1, 0}, {0, 2, 3}});
  }
}

// The widths of the index types: values that only fit the wider types come back exactly.
TEST(Triangles, ReadAccessorUnsignedIntegerWidths) {
  Bytes bytes;
  bytes.put_all<std::uint8_t>(0, {0, 200, 255});
  bytes.put_all<std::uint16_t>(4, {0, 40000, 65535});
  bytes.put_all<std::uint32_t>(12, {0, 70000, 4294967295u});
  const auto asset = make_asset(R"({
    "asset": {"version": "2.0"},
    "buffers": [{"byteLength": 24}],
    "bufferViews": [
      {"buffer": 0, "byteOffset": 0, "byteLength": 3},
      {"buffer": 0, "byteOffset": 4, "byteLength": 6},
      {"buffer": 0, "byteOffset": 12, "byteLength": 12}],
    "accessors": [
      {"bufferView": 0, "componentType": 5121, "count": 3, "type": "SCALAR"},
      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
      {"bufferView": 2, "componentType": 5125, "count": 3, "type": "SCALAR"}]
  })", bytes);
  EXPECT_EQ(read_accessor(asset, 0), (std::vector<double>{0, 200, 255}));
  EXPECT_EQ(read_accessor(asset, 1), (std::vector<double>{0, 40000, 65535}));
  EXPECT_EQ(read_accessor(asset, 2), (std::vector<double>{0, 70000, 4294967295.0}));
}

TEST(Triangles, NonIndexedTriangles) {
  const std::vector<Vector3d> positions{{0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                                        {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  Bytes bytes;
  bytes.put_vec3(0, positions);
  const auto asset = make_asset(R"({
    "asset": {"version": "2.0"},
    "buffers": [{"byteLength": 72}],
    "bufferViews": [{"buffer": 0, "byteLength": 72}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3",
                   "min": [0, 0, 0], "max": [1, 1, 1]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]
  })", bytes);
  const TriangleMesh mesh = read_triangles(asset, 0, 0);
  expect_positions(mesh, positions);
  expect_triangles(mesh.triangles, {{0, 1, 2}, {3, 4, 5}});
}

// ------------------------------------------------------------------------------------------------
// TRIANGLE_STRIP and TRIANGLE_FAN.

// A primitive over `logical` vertices v_0..v_{n-1}, either non-indexed (stored in order) or
// indexed through the permutation `order` (position order[j] holds v_j, index j is order[j]).
GltfAsset topology_asset(int mode, const std::vector<Vector3d>& logical,
                         const std::vector<std::uint32_t>& order) {
  const std::size_t n = logical.size();
  std::vector<Vector3d> stored(n);
  for (std::size_t j = 0; j < n; ++j) stored[order.empty() ? j : order[j]] = logical[j];
  Bytes bytes;
  bytes.put_vec3(0, stored);
  const std::size_t positions_length = 12 * n;
  // The index data is always there (the identity for a non-indexed primitive), and referenced
  // only when indexed.
  std::vector<std::uint16_t> values(n);
  for (std::size_t j = 0; j < n; ++j) values[j] = static_cast<std::uint16_t>(order.empty() ? j : order[j]);
  bytes.put_all(positions_length, values);
  bytes.pad_to(positions_length + ((2 * n + 3) / 4) * 4);
  const std::string indices = order.empty() ? "" : R"(, "indices": 1)";
  Eigen::Vector3d lo = logical[0], hi = logical[0];
  for (const Vector3d& p : logical) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return make_asset(
      substitute(R"({
    "asset": {"version": "2.0"},
    "buffers": [{"byteLength": @LENGTH@}],
    "bufferViews": [{"buffer": 0, "byteLength": @POSITIONS@},
                    {"buffer": 0, "byteOffset": @POSITIONS@, "byteLength": @INDEX_BYTES@}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": @N@, "type": "VEC3",
                   "min": [@MIN@], "max": [@MAX@]},
                  {"bufferView": 1, "componentType": 5123, "count": @N@, "type": "SCALAR"}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": @MODE@@INDICES@}]}]
  })",
                 {{"@LENGTH@", std::to_string(bytes.data.size())},
                  {"@POSITIONS@", std::to_string(positions_length)},
                  {"@INDEX_BYTES@", std::to_string(2 * n)},
                  {"@N@", std::to_string(n)},
                  {"@MIN@", std::to_string(lo.x()) + "," + std::to_string(lo.y()) + "," +
                                std::to_string(lo.z())},
                  {"@MAX@", std::to_string(hi.x()) + "," + std::to_string(hi.y()) + "," +
                                std::to_string(hi.z())},
                  {"@MODE@", std::to_string(mode)},
                  {"@INDICES@", indices}}),
      bytes);
}

// glTF 2.0 section 3.7.2.1: strip triangle i is (i, i + 1 + i%2, i + 2 - i%2), so that every
// other triangle is flipped back and the whole strip keeps the first triangle's winding. The
// zig-zag below is counter-clockwise seen from +z when wound by that rule.
TEST(Triangles, TriangleStripWindingRule) {
  const std::vector<Vector3d> strip{{0, 1, 0}, {0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {2, 1, 0}};
  // Expected in logical vertex numbers: i = 0: (0, 1, 2); i = 1: (1, 3, 2); i = 2: (2, 3, 4).
  const std::vector<Triangle> logical{{0, 1, 2}, {1, 3, 2}, {2, 3, 4}};
  for (const std::vector<std::uint32_t>& order :
       {std::vector<std::uint32_t>{}, std::vector<std::uint32_t>{2, 4, 0, 3, 1}}) {
    SCOPED_TRACE(order.empty() ? "non-indexed" : "indexed");
    const TriangleMesh mesh = read_triangles(topology_asset(5, strip, order), 0, 0);
    std::vector<Triangle> expected = logical;
    if (!order.empty()) {
      for (Triangle& t : expected) t = {order[t[0]], order[t[1]], order[t[2]]};
    }
    expect_triangles(mesh.triangles, expected);
    for (double z : normal_z(mesh)) EXPECT_GT(z, 0) << "strip triangle wound clockwise";
  }
}

TEST(Triangles, TriangleStripShortInputs) {
  const std::vector<Vector3d> three{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  expect_triangles(read_triangles(topology_asset(5, three, {}), 0, 0).triangles, {{0, 1, 2}});
  const std::vector<Vector3d> four{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  expect_triangles(read_triangles(topology_asset(5, four, {}), 0, 0).triangles,
                   {{0, 1, 2}, {1, 3, 2}});
}

// A strip or fan of fewer than 3 vertices has no triangle: a warning, as the validator's
// MESH_PRIMITIVE_INCOMPATIBLE_MODE, not silence.
TEST(Triangles, AStripOrFanTooShortForATriangleIsAWarning) {
  const std::vector<Vector3d> two{{0, 0, 0}, {1, 0, 0}};
  for (int mode : {5, 6}) {
    for (const std::vector<std::uint32_t>& order : {std::vector<std::uint32_t>{}, std::vector<std::uint32_t>{1, 0}}) {
      Diagnostics diag;
      const auto triangles = read_primitive_triangles(topology_asset(mode, two, order), 0, 0, diag);
      ASSERT_TRUE(triangles.has_value());
      EXPECT_TRUE(triangles->triangles.empty());
      ASSERT_EQ(diag.all().size(), 1u);
      EXPECT_EQ(diag.all()[0].code, "MESH_PRIMITIVE_INCOMPATIBLE_MODE");
      EXPECT_EQ(diag.all()[0].severity, Severity::kWarning);
      EXPECT_EQ(diag.all()[0].pointer, "/meshes/0/primitives/0");
      EXPECT_EQ(diag.all()[0].message,
                std::string("a triangle ") + (mode == 5 ? "strip" : "fan") + " of 2 vertices has no triangle; it adds nothing");
    }
  }
}

// Section 3.7.2.1: fan triangle i is (i + 1, i + 2, 0).
TEST(Triangles, TriangleFan) {
  const std::vector<Vector3d> fan{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {-1, 1, 0}};
  const std::vector<Triangle> logical{{1, 2, 0}, {2, 3, 0}, {3, 4, 0}};
  for (const std::vector<std::uint32_t>& order :
       {std::vector<std::uint32_t>{}, std::vector<std::uint32_t>{4, 0, 1, 2, 3}}) {
    SCOPED_TRACE(order.empty() ? "non-indexed" : "indexed");
    const TriangleMesh mesh = read_triangles(topology_asset(6, fan, order), 0, 0);
    std::vector<Triangle> expected = logical;
    if (!order.empty()) {
      for (Triangle& t : expected) t = {order[t[0]], order[t[1]], order[t[2]]};
    }
    expect_triangles(mesh.triangles, expected);
    for (double z : normal_z(mesh)) EXPECT_GT(z, 0) << "fan triangle wound clockwise";
  }
}

TEST(Triangles, IndexedTrianglesThroughPermutation) {
  const std::vector<Vector3d> v{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 0, 0}, {2, 1, 0}};
  const std::vector<std::uint32_t> order{5, 3, 1, 0, 2, 4};
  const TriangleMesh mesh = read_triangles(topology_asset(4, v, order), 0, 0);
  expect_triangles(mesh.triangles, {{5, 3, 1}, {0, 2, 4}});
  for (std::size_t j = 0; j < v.size(); ++j) EXPECT_EQ(mesh.positions[order[j]], v[j]);
}

// ------------------------------------------------------------------------------------------------
// byteStride, byteOffset.

// Interleaved POSITION and NORMAL, 32 bytes per vertex (12 + 12 + 8 bytes of padding), in a view
// that starts 16 bytes into the buffer.
TEST(Triangles, InterleavedByteStride) {
  const std::vector<Vector3d> positions{{0.5, 0, 0}, {1, 0.25, 0}, {0, 1, -2}};
  const std::vector<Vector3d> normals{{0, 0, 1}, {0, 1, 0}, {1, 0, 0}};
  Bytes bytes;
  bytes.put_vec3(16, positions, 32);
  bytes.put_vec3(16 + 12, normals, 32);
  bytes.pad_to(16 + 96);
  const auto asset = make_asset(R"({
    "asset": {"version": "2.0"},
    "buffers": [{"byteLength": 112}],
    "bufferViews": [{"buffer": 0, "byteOffset": 16, "byteLength": 96, "byteStride": 32,
                     "target": 34962}],
    "accessors": [
      {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3",
       "min": [0, 0, -2], "max": [1, 1, 0]},
      {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 3, "type": "VEC3"}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}}]}]
  })", bytes);
  const TriangleMesh mesh = read_triangles(asset, 0, 0);
  expect_positions(mesh, positions);
  expect_triangles(mesh.triangles, {{0, 1, 2}});
  EXPECT_EQ(read_accessor(asset, 1), (std::vector<double>{0, 0, 1, 0, 1, 0, 1, 0, 0}));
}

// ------------------------------------------------------------------------------------------------
// Sparse accessors (section 3.6.2.3).

// Base: four positions; sparse: rows 1 and 3 replaced. The base view is strided (16 bytes per
// element) while the sparse values are tightly packed, as the spec requires of them.
TEST(Triangles, SparseWithBufferView) {
  const std::vector<Vector3d> base{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<Vector3d> replacement{{5, 6, 7}, {-1, -2, -3}};
  for (const int type : {kUnsignedByte, kUnsignedShort, kUnsignedInt}) {
    SCOPED_TRACE(::testing::Message() << "sparse index componentType " << type);
    Bytes bytes;
    bytes.put_vec3(0, base, 16);  // 0..64
    // Indices view at 64, the accessor's indices at byteOffset 4 into it.
    if (type == kUnsignedByte) bytes.put_all<std::uint8_t>(68, {1, 3});
    if (type == kUnsignedShort) bytes.put_all<std::uint16_t>(68, {1, 3});
    if (type == kUnsignedInt) bytes.put_all<std::uint32_t>(68, {1, 3});
    bytes.pad_to(80);
    bytes.put_vec3(80, replacement);  // 80..104
    const auto asset = make_asset(substitute(R"({
      "asset": {"version": "2.0"},
      "buffers": [{"byteLength": 104}],
      "bufferViews": [
        {"buffer": 0, "byteOffset": 0, "byteLength": 64, "byteStride": 16},
        {"buffer": 0, "byteOffset": 64, "byteLength": 16},
        {"buffer": 0, "byteOffset": 80, "byteLength": 24}],
      "accessors": [{
        "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
        "min": [-1, -2, -3], "max": [5, 6, 7],
        "sparse": {"count": 2,
                   "indices": {"bufferView": 1, "byteOffset": 4, "componentType": @TYPE@},
                   "values": {"bufferView": 2}}}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 5}]}]
    })", {{"@TYPE@", std::to_string(type)}}), bytes);
    EXPECT_EQ(read_accessor(asset, 0),
              (std::vector<double>{0, 0, 0, 5, 6, 7, 0, 1, 0, -1, -2, -3}));
    const TriangleMesh mesh = read_triangles(asset, 0, 0);
    expect_positions(mesh, {base[0], replacement[0], base[2], replacement[1]});
    expect_triangles(mesh.triangles, {{0, 1, 2}, {1, 3, 2}});
  }
}

// Without a bufferView the base values are all zeros; values land on the rows the indices name.
TEST(Triangles, SparseWithoutBufferView) {
  Bytes bytes;
  bytes.put_all<std::uint16_t>(0, {0, 2, 4});
  bytes.pad_to(8);
  bytes.put_all<float>(8, {1.5f, -2.0f, 0.25f, 3.0f, 4.0f, 5.0f, -6.0f, 7.0f, 8.0f});
  const auto asset = make_asset(R"({
    "asset": {"version": "2.0"},
    "buffers": [{"byteLength": 44}],
    "bufferViews": [
      {"buffer": 0, "byteOffset": 0, "byteLength": 6},
      {"buffer": 0, "byteOffset": 8, "byteLength": 36}],
    "accessors": [{
      "componentType": 5126, "count": 5, "type": "VEC3",
      "min": [-6, -2, 0], "max": [3, 7, 8],
      "sparse": {"count": 3,
                 "indices": {"bufferView": 0, "componentType": 5123},
                 "values": {"bufferView": 1}}}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 6}]}]
  })", bytes);
  EXPECT_EQ(read_accessor(asset, 0),
            (std::vector<double>{1.5, -2, 0.25, 0, 0, 0, 3, 4, 5, 0, 0, 0, -6, 7, 8}));
  const TriangleMesh mesh = read_triangles(asset, 0, 0);
  expect_positions(mesh, {{1.5, -2, 0.25}, {0, 0, 0}, {3, 4, 5}, {0, 0, 0}, {-6, 7, 8}});
  expect_triangles(mesh.triangles, {{1, 2, 0}, {2, 3, 0}, {3, 4, 0}});
}

// ------------------------------------------------------------------------------------------------
// Normalized integers (section 3.11): signed f = max(c / (2^(b-1) - 1), -1), unsigned
// f = c / (2^b - 1). VEC3 vertex elements padded to 4-byte boundaries (byteStride 4 and 8).

struct IntegerCase {
  int type;
  std::vector<int> values;  // 3 elements x 3 components.
};

double normalized(int type, int c) {
  switch (type) {
    case kByte:
      return std::max(c / 127.0, -1.0);
    case kUnsignedByte:
      return c / 255.0;
    case kShort:
      return std::max(c / 32767.0, -1.0);
    default:
      return c / 65535.0;
  }
}

TEST(Triangles, NormalizedAndIntegerPositions) {
  const std::vector<IntegerCase> cases{
      {kByte, {127, -127, -128, 0, 64, -1, 1, -1, 100}},
      {kUnsignedByte, {255, 0, 128, 1, 2, 3, 254, 127, 64}},
      {kShort, {32767, -32768, -32767, 0, 1000, -1, 16384, -16384, 2}},
      {kUnsignedShort, {65535, 0, 32768, 1, 2, 3, 65534, 1000, 7}}};
  // Views: BYTE at 0 (stride 4), UNSIGNED_BYTE at 12 (stride 4), SHORT at 24 (stride 8),
  // UNSIGNED_SHORT at 48 (stride 8); 72 bytes in all.
  const std::size_t offsets[] = {0, 12, 24, 48};
  Bytes bytes;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const auto& [type, values] = cases[k];
    const std::size_t size = (type == kByte || type == kUnsignedByte) ? 1 : 2;
    const std::size_t stride = size == 1 ? 4 : 8;
    for (std::size_t i = 0; i < values.size(); ++i) {
      const std::size_t at = offsets[k] + (i / 3) * stride + (i % 3) * size;
      switch (type) {
        case kByte: bytes.put(at, static_cast<std::int8_t>(values[i])); break;
        case kUnsignedByte: bytes.put(at, static_cast<std::uint8_t>(values[i])); break;
        case kShort: bytes.put(at, static_cast<std::int16_t>(values[i])); break;
        default: bytes.put(at, static_cast<std::uint16_t>(values[i])); break;
      }
    }
  }
  bytes.pad_to(72);
  // Accessors 0-3 normalized, 4-7 the same data as plain integers (KHR_mesh_quantization).
  const auto asset = make_asset(R"({
    "asset": {"version": "2.0"},
    "extensionsUsed": ["KHR_mesh_quantization"],
    "extensionsRequired": ["KHR_mesh_quantization"],
    "buffers": [{"byteLength": 72}],
    "bufferViews": [
      {"buffer": 0, "byteOffset": 0, "byteLength": 12, "byteStride": 4},
      {"buffer": 0, "byteOffset": 12, "byteLength": 12, "byteStride": 4},
      {"buffer": 0, "byteOffset": 24, "byteLength": 24, "byteStride": 8},
      {"buffer": 0, "byteOffset": 48, "byteLength": 24, "byteStride": 8}],
    "accessors": [
      {"bufferView": 0, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"},
      {"bufferView": 1, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC3"},
      {"bufferView": 2, "componentType": 5122, "normalized": true, "count": 3, "type": "VEC3"},
      {"bufferView": 3, "componentType": 5123, "normalized": true, "count": 3, "type": "VEC3"},
      {"bufferView": 0, "componentType": 5120, "count": 3, "type": "VEC3"},
      {"bufferView": 1, "componentType": 5121, "count": 3, "type": "VEC3"},
      {"bufferView": 2, "componentType": 5122, "count": 3, "type": "VEC3"},
      {"bufferView": 3, "componentType": 5123, "normalized": false, "count": 3, "type": "VEC3"}],
    "meshes": [{"primitives": [
      {"attributes": {"POSITION": 0}}, {"attributes": {"POSITION": 1}},
      {"attributes": {"POSITION": 2}}, {"attributes": {"POSITION": 3}},
      {"attributes": {"POSITION": 4}}, {"attributes": {"POSITION": 5}},
      {"attributes": {"POSITION": 6}}, {"attributes": {"POSITION": 7}}]}]
  })", bytes);
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const auto& [type, values] = cases[k];
    SCOPED_TRACE(::testing::Message() << "componentType " << type);
    const auto norm = read_accessor(asset, k);
    const auto plain = read_accessor(asset, k + 4);
    ASSERT_EQ(norm.size(), 9u);
    ASSERT_EQ(plain.size(), 9u);
    for (std::size_t i = 0; i < values.size(); ++i) {
      EXPECT_DOUBLE_EQ(norm[i], normalized(type, values[i])) << "raw " << values[i];
      EXPECT_EQ(plain[i], static_cast<double>(values[i]));
    }
    // The spec's edge cases, written out.
    if (type == kByte) {
      EXPECT_EQ(norm[0], 1.0);   // 127
      EXPECT_EQ(norm[1], -1.0);  // -127
      EXPECT_EQ(norm[2], -1.0);  // -128 clamps
    }
    if (type == kShort) {
      EXPECT_EQ(norm[0], 1.0);   // 32767
      EXPECT_EQ(norm[1], -1.0);  // -32768 clamps
      EXPECT_EQ(norm[2], -1.0);  // -32767
    }
    if (type == kUnsignedByte || type == kUnsignedShort) {
      EXPECT_EQ(norm[0], 1.0);
      EXPECT_EQ(norm[1], 0.0);
    }
    // As positions of a primitive.
    const TriangleMesh mesh = read_triangles(asset, 0, k);
    ASSERT_EQ(mesh.positions.size(), 3u);
    for (std::size_t v = 0; v < 3; ++v) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_DOUBLE_EQ(mesh.positions[v][c], normalized(type, values[3 * v + c]));
      }
    }
    expect_triangles(mesh.triangles, {{0, 1, 2}});
    const TriangleMesh integer_mesh = read_triangles(asset, 0, k + 4);
    ASSERT_EQ(integer_mesh.positions.size(), 3u);
    EXPECT_EQ(integer_mesh.positions[2],
              Vector3d(values[6], values[7], values[8]));
  }
}

// ------------------------------------------------------------------------------------------------
// Modes without volume.

TEST(Triangles, PointsAndLinesAreSkippedWithInfo) {
  Bytes bytes;
  bytes.put_vec3(0, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}});
  const auto asset = make_asset(R"({
    "asset": {"version": "2.0"},
    "buffers": [{"byteLength": 48}],
    "bufferViews": [{"buffer": 0, "byteLength": 48}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                   "min": [0, 0, 0], "max": [1, 1, 1]}],
    "meshes": [{"primitives": [
      {"attributes": {"POSITION": 0}, "mode": 0},
      {"attributes": {"POSITION": 0}, "mode": 1},
      {"attributes": {"POSITION": 0}, "mode": 2},
      {"attributes": {"POSITION": 0}, "mode": 3},
      {"attributes": {}, "mode": 4},
      {"attributes": {"POSITION": 0}, "mode": 4}]}]
  })", bytes);
  for (std::size_t p = 0; p < 5; ++p) {
    SCOPED_TRACE(::testing::Message() << "primitive " << p);
    Diagnostics diag;
    EXPECT_FALSE(read_primitive_triangles(asset, 0, p, diag).has_value());
    ASSERT_EQ(diag.all().size(), 1u);
    const Diagnostic& d = diag.all()[0];
    EXPECT_EQ(d.severity, Severity::kInfo);
    EXPECT_EQ(d.code, "PRIMITIVE_SKIPPED");
    EXPECT_EQ(d.pointer, "/meshes/0/primitives/" + std::to_string(p));
    EXPECT_FALSE(diag.has_errors());
  }
  // The one TRIANGLES primitive: 4 vertices, one triangle, the extra vertex ignored.
  Diagnostics diag;
  const auto mesh = read_primitive_triangles(asset, 0, 5, diag);
  ASSERT_TRUE(mesh.has_value());
  expect_triangles(mesh->triangles, {{0, 1, 2}});
  EXPECT_FALSE(diag.has_errors());
}

// ------------------------------------------------------------------------------------------------
// Through the loader: a whole .gltf with its buffer in a base64 data: URI.

TEST(Triangles, LoadedFromMemoryWithDataUri) {
  // Tetrahedron: positions 0..48, u16 indices 48..72 (12 indices), then a sparse accessor's
  // indices (u8 {2}, at 72, padded to 76) and values (one VEC3 at 76..88).
  const std::vector<Vector3d> positions{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Bytes bytes;
  bytes.put_vec3(0, positions);
  bytes.put_all<std::uint16_t>(48, {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3});
  bytes.put<std::uint8_t>(72, 2);
  bytes.pad_to(76);
  bytes.put_vec3(76, {{0, 2, 0}});
  ASSERT_EQ(bytes.data.size(), 88u);
  const std::string json = substitute(R"({
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0}],
    "buffers": [{"byteLength": 88, "uri": "data:application/octet-stream;base64,@DATA@"}],
    "bufferViews": [
      {"buffer": 0, "byteOffset": 0, "byteLength": 48, "target": 34962},
      {"buffer": 0, "byteOffset": 48, "byteLength": 24, "target": 34963},
      {"buffer": 0, "byteOffset": 72, "byteLength": 1},
      {"buffer": 0, "byteOffset": 76, "byteLength": 12}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
       "min": [0, 0, 0], "max": [1, 1, 1]},
      {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"},
      {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
       "min": [0, 0, 0], "max": [1, 2, 1],
       "sparse": {"count": 1, "indices": {"bufferView": 2, "componentType": 5121},
                  "values": {"bufferView": 3}}}],
    "meshes": [{"primitives": [
      {"attributes": {"POSITION": 0}, "indices": 1},
      {"attributes": {"POSITION": 0}, "mode": 5},
      {"attributes": {"POSITION": 2}, "indices": 1}]}]
  })", {{"@DATA@", testing::base64(bytes.data)}});
  Diagnostics diag;
  const std::vector<std::uint8_t> file(json.begin(), json.end());
  const auto asset = load_gltf_from_memory(file, "in-memory.gltf", {}, LoadLimits{}, diag);
  for (const Diagnostic& d : diag.all()) ADD_FAILURE() << format(d);
  ASSERT_TRUE(asset.has_value());
  ASSERT_EQ(asset->buffers.size(), 1u);
  EXPECT_EQ(asset->buffers[0], bytes.data);

  const TriangleMesh indexed = read_triangles(*asset, 0, 0);
  expect_positions(indexed, positions);
  expect_triangles(indexed.triangles, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});

  const TriangleMesh strip = read_triangles(*asset, 0, 1);
  expect_positions(strip, positions);
  expect_triangles(strip.triangles, {{0, 1, 2}, {1, 3, 2}});

  const TriangleMesh sparse = read_triangles(*asset, 0, 2);
  expect_positions(sparse, {positions[0], positions[1], {0, 2, 0}, positions[3]});
}

// ------------------------------------------------------------------------------------------------
// Node transforms (section 3.5.3).

TEST(Transforms, NodeWithoutTransformIsIdentity) {
  EXPECT_TRUE(node_local_transform(Json::parse(R"({"mesh": 0})")).matrix().isIdentity(0.0));
}

// glTF stores `matrix` column-major: element 4 * column + row.
TEST(Transforms, MatrixIsColumnMajor) {
  const Json node = Json::parse(
      R"({"matrix": [1, 2, 3, 0,  4, 5, 6, 0,  7, 8, 10, 0,  11, 12, 13, 1]})");
  const Eigen::Affine3d X = node_local_transform(node);
  Eigen::Matrix3d linear;
  linear << 1, 4, 7, 2, 5, 8, 3, 6, 10;
  EXPECT_EQ(X.linear(), linear);
  EXPECT_EQ(X.translation(), Vector3d(11, 12, 13));
  EXPECT_EQ(X * Vector3d(1, 0, 0), Vector3d(12, 14, 16));
}

// The local transform is T * R * S: scale first, then rotate, then translate.
TEST(Transforms, TrsOrderIsTranslationRotationScale) {
  const double h = std::sqrt(0.5);  // 90 degrees about z: (x, y, z, w) = (0, 0, h, h).
  Json node = Json::parse(R"({"translation": [10, 20, 30], "scale": [2, 3, 4]})");
  node["rotation"] = Json::array({0.0, 0.0, h, h});
  const Eigen::Affine3d X = node_local_transform(node);
  // (1, 1, 1) -> scaled (2, 3, 4) -> rotated (-3, 2, 4) -> translated (7, 22, 34).
  const Vector3d p = X * Vector3d(1, 1, 1);
  EXPECT_NEAR(p.x(), 7, 1e-13);
  EXPECT_NEAR(p.y(), 22, 1e-13);
  EXPECT_NEAR(p.z(), 34, 1e-13);
  const Eigen::Affine3d expected = Eigen::Translation3d(10, 20, 30) *
                                   Eigen::Quaterniond(h, 0, 0, h).normalized() *
                                   Eigen::Scaling(Vector3d(2, 3, 4));
  EXPECT_TRUE(X.matrix().isApprox(expected.matrix(), 1e-15)) << X.matrix();
  // A general rotation: glTF's (x, y, z, w) order against Eigen's (w, x, y, z) constructor.
  const Eigen::Quaterniond q = Eigen::Quaterniond(0.5, -0.1, 0.7, 0.3).normalized();
  Json rotated;
  rotated["rotation"] = Json::array({q.x(), q.y(), q.z(), q.w()});
  EXPECT_TRUE(node_local_transform(rotated).linear().isApprox(q.toRotationMatrix(), 1e-15));
}

TEST(Transforms, WorldTransformsComposeParentThenChild) {
  const Json document = Json::parse(R"({
    "scenes": [{"nodes": [0]}],
    "nodes": [
      {"translation": [1, 0, 0], "scale": [2, 2, 2], "children": [1]},
      {"translation": [0, 1, 0], "rotation": [0, 0, 1, 0], "children": [2]},
      {"matrix": [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 3, 1]}]
  })");
  const auto parents = node_parents(document);
  EXPECT_EQ(parents, (std::vector<int>{-1, 0, 1}));
  const auto world = node_world_transforms(document);
  ASSERT_EQ(world.size(), 3u);
  const auto local = [&](std::size_t i) { return node_local_transform(document["nodes"][i]); };
  EXPECT_TRUE(world[1].matrix().isApprox((local(0) * local(1)).matrix(), 1e-15));
  EXPECT_TRUE(world[2].matrix().isApprox((local(0) * local(1) * local(2)).matrix(), 1e-15));
  // The origin of node 2: (0, 0, 3) -> rotated 180 about z, + (0, 1, 0) -> (0, 1, 3);
  // scaled by 2, + (1, 0, 0) -> (1, 2, 6).
  EXPECT_TRUE(world[2].translation().isApprox(Vector3d(1, 2, 6), 1e-15));
}

Eigen::Matrix3d test_rotation() {
  return Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
}

double max_abs(const Eigen::Matrix3d& m) { return m.cwiseAbs().maxCoeff(); }

TEST(Transforms, RigidPartOfIdentityAndPureRotationIsExact) {
  Eigen::Affine3d X = Eigen::Affine3d::Identity();
  X.translation() = Vector3d(0.1, -2, 3e5);
  const Eigen::Isometry3d identity = rigid_part(X);
  EXPECT_EQ(identity.linear(), Eigen::Matrix3d::Identity());
  EXPECT_EQ(identity.translation(), X.translation());
  // A rotation (orthonormal up to rounding) comes back bit for bit.
  for (const Eigen::Matrix3d& R :
       {test_rotation(), Eigen::Quaterniond(0.5, -0.1, 0.7, 0.3).normalized().toRotationMatrix(),
        Eigen::Matrix3d(Eigen::AngleAxisd(std::numbers::pi, Vector3d::UnitX()))}) {
    X.linear() = R;
    const Eigen::Isometry3d rigid = rigid_part(X);
    EXPECT_EQ(rigid.linear(), R);
    EXPECT_EQ(rigid.translation(), X.translation());
  }
}

// Scale (uniform or not) and, more generally, a symmetric positive definite stretch P: the
// rotation nearest R P is R (polar decomposition).
TEST(Transforms, RigidPartOfScaledRotationIsTheRotation) {
  const Eigen::Matrix3d R = test_rotation();
  Eigen::Matrix3d B;
  B << 0.3, 0.1, -0.2, 0.0, 0.4, 0.1, 0.2, -0.1, 0.5;
  const Eigen::Matrix3d stretch = B * B.transpose() + Eigen::Matrix3d::Identity();
  for (const Eigen::Matrix3d& P :
       {Eigen::Matrix3d(2.5 * Eigen::Matrix3d::Identity()),
        Eigen::Matrix3d(Vector3d(2, 3, 0.5).asDiagonal()),
        Eigen::Matrix3d(Vector3d(0.01, 1, 100).asDiagonal()), stretch}) {
    SCOPED_TRACE(::testing::Message() << "stretch\n" << P);
    Eigen::Affine3d X = Eigen::Affine3d::Identity();
    X.linear() = R * P;
    X.translation() = Vector3d(4, 5, 6);
    const Eigen::Isometry3d rigid = rigid_part(X);
    EXPECT_LE(max_abs(rigid.linear() - R), 1e-12) << rigid.linear();
    EXPECT_LE(max_abs(rigid.linear().transpose() * rigid.linear() - Eigen::Matrix3d::Identity()),
              1e-14);
    EXPECT_NEAR(rigid.linear().determinant(), 1.0, 1e-14);
    EXPECT_EQ(rigid.translation(), X.translation());
  }
}

// A mirrored frame: its axes with the scale removed (the signs of the scale kept), then its own Z
// axis reversed, whatever the scales (s101fmt D4: with the scales tied, as Blender's mirrored
// wheel's -1, 1, 1, the axis reversed was the SVD's choice).
TEST(Transforms, RigidPartOfMirroredFrameReversesItsZAxis) {
  const Eigen::Matrix3d R = test_rotation();
  Eigen::Affine3d X = Eigen::Affine3d::Identity();
  for (const Vector3d& s : {Vector3d(2, 3, -0.5), Vector3d(-1, 1, 1), Vector3d(1, -1, 1), Vector3d(-1, -1, -1),
                            Vector3d(-3, 2, 1), Vector3d(0.01, -100, 1)}) {
    SCOPED_TRACE(::testing::Message() << "scale " << s.transpose());
    X.linear() = R * s.asDiagonal();
    const Eigen::Matrix3d Q = rigid_part(X).linear();
    const Vector3d signs(s.x() > 0 ? 1 : -1, s.y() > 0 ? 1 : -1, s.z() > 0 ? -1 : 1);
    EXPECT_LE(max_abs(Q - R * signs.asDiagonal()), 1e-12) << Q;
    EXPECT_NEAR(Q.determinant(), 1.0, 1e-14);
    EXPECT_LE(max_abs(orthogonal_part(X.linear()) - R * s.cwiseSign().asDiagonal()), 1e-12);
  }
}

}  // namespace
}  // namespace rdtf
