#include <algorithm>
#include <array>
#include <cstring>
#include <optional>

#include "rdtf/geometry.h"
#include "typed_view.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

constexpr int kByte = 5120;
constexpr int kUnsignedByte = 5121;
constexpr int kShort = 5122;
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kFloat = 5126;

std::size_t component_bytes(int component_type) {
  switch (component_type) {
    case kByte:
    case kUnsignedByte:
      return 1;
    case kShort:
    case kUnsignedShort:
      return 2;
    default:
      return 4;
  }
}

template <typename T>
T load(const std::uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}

// One component as a double, applying glTF's normalisation rules for integers.
double read_component(const std::uint8_t* p, int component_type, bool normalized) {
  switch (component_type) {
    case kByte: {
      const double v = load<std::int8_t>(p);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case kUnsignedByte: {
      const double v = load<std::uint8_t>(p);
      return normalized ? v / 255.0 : v;
    }
    case kShort: {
      const double v = load<std::int16_t>(p);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case kUnsignedShort: {
      const double v = load<std::uint16_t>(p);
      return normalized ? v / 65535.0 : v;
    }
    case kUnsignedInt:
      return load<std::uint32_t>(p);
    case kFloat:
      return load<float>(p);
    default:
      return 0;
  }
}

// Reads `count` elements of `components` components from a buffer view into out (row-major).
void read_elements(const GltfAsset& asset, std::size_t view_index, std::uint64_t byte_offset,
                   std::uint64_t count, int components, int component_type, bool normalized,
                   std::size_t default_stride, double* out) {
  const Json& view = asset.document["bufferViews"][view_index];
  const auto& buffer = asset.buffers[view["buffer"].get<std::size_t>()];
  const std::uint64_t view_offset = view.value("byteOffset", std::uint64_t{0});
  const std::uint64_t stride = view.value("byteStride", std::uint64_t{default_stride});
  const std::size_t size = component_bytes(component_type);
  const std::uint8_t* base = buffer.data() + view_offset + byte_offset;
  for (std::uint64_t i = 0; i < count; ++i) {
    const std::uint8_t* element = base + i * stride;
    for (int c = 0; c < components; ++c) {
      out[i * components + c] = read_component(element + c * size, component_type, normalized);
    }
  }
}

std::vector<std::uint32_t> read_unsigned(const GltfAsset& asset, std::size_t view_index,
                                         std::uint64_t byte_offset, std::uint64_t count,
                                         int component_type) {
  std::vector<double> values(count);
  read_elements(asset, view_index, byte_offset, count, 1, component_type, false,
                component_bytes(component_type), values.data());
  return {values.begin(), values.end()};
}

// Where a dense accessor's elements start, and the distance between them; nothing for a sparse
// one or one without a buffer view (those take read_accessor's general path).
struct DenseView {
  const std::uint8_t* first = nullptr;
  std::uint64_t stride = 0;
  std::uint64_t count = 0;
  int component_type = 0;
  bool normalized = false;
};

std::optional<DenseView> dense_view(const GltfAsset& asset, const Json& accessor, int components) {
  if (accessor.contains("sparse") || !accessor.contains("bufferView")) return std::nullopt;
  const Json& view = asset.document["bufferViews"][accessor["bufferView"].get<std::size_t>()];
  const auto& buffer = asset.buffers[view["buffer"].get<std::size_t>()];
  DenseView dense;
  dense.component_type = accessor["componentType"].get<int>();
  dense.normalized = accessor.value("normalized", false);
  dense.count = accessor["count"].get<std::uint64_t>();
  dense.stride = view.value("byteStride", component_bytes(dense.component_type) * components);
  dense.first = buffer.data() + view.value("byteOffset", std::uint64_t{0}) +
                accessor.value("byteOffset", std::uint64_t{0});
  return dense;
}

// POSITION as points. Float positions, nearly every file's, convert in one pass with no
// intermediate array (issue 6: the reading of a million-triangle model was a large cost).
std::vector<Eigen::Vector3d> read_points(const GltfAsset& asset, std::size_t index) {
  const Json& accessor = asset.document["accessors"][index];
  const auto dense = dense_view(asset, accessor, 3);
  std::vector<Eigen::Vector3d> points;
  if (dense && dense->component_type == kFloat) {
    points.resize(dense->count);
    for (std::uint64_t i = 0; i < dense->count; ++i) {
      float xyz[3];
      std::memcpy(xyz, dense->first + i * dense->stride, sizeof(xyz));
      points[i] = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
    }
    return points;
  }
  const auto values = read_accessor(asset, index);
  points.resize(values.size() / 3);
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i] = Eigen::Vector3d(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
  }
  return points;
}

template <typename T>
void copy_indices(const DenseView& dense, std::uint32_t* out) {
  for (std::uint64_t i = 0; i < dense.count; ++i) out[i] = load<T>(dense.first + i * dense.stride);
}

template <typename T>
void copy_triangles(const DenseView& dense, std::vector<std::array<std::uint32_t, 3>>& triangles) {
  triangles.resize(dense.count / 3);
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const std::uint8_t* first = dense.first + 3 * i * dense.stride;
    triangles[i] = {load<T>(first), load<T>(first + dense.stride), load<T>(first + 2 * dense.stride)};
  }
}

// Triangles (mode TRIANGLES) straight from a dense index accessor, with no array of indices in
// between; false when the accessor needs the general path.
bool read_indexed_triangles(const GltfAsset& asset, std::size_t index,
                            std::vector<std::array<std::uint32_t, 3>>& triangles) {
  const auto dense = dense_view(asset, asset.document["accessors"][index], 1);
  if (!dense) return false;
  switch (dense->component_type) {
    case kUnsignedByte:
      copy_triangles<std::uint8_t>(*dense, triangles);
      return true;
    case kUnsignedShort:
      copy_triangles<std::uint16_t>(*dense, triangles);
      return true;
    case kUnsignedInt:
      copy_triangles<std::uint32_t>(*dense, triangles);
      return true;
    default:
      return false;
  }
}

// An index accessor as unsigned integers, straight from the buffer when it is dense.
std::vector<std::uint32_t> read_indices(const GltfAsset& asset, std::size_t index) {
  const Json& accessor = asset.document["accessors"][index];
  std::vector<std::uint32_t> order;
  if (const auto dense = dense_view(asset, accessor, 1)) {
    order.resize(dense->count);
    switch (dense->component_type) {
      case kUnsignedByte:
        copy_indices<std::uint8_t>(*dense, order.data());
        return order;
      case kUnsignedShort:
        copy_indices<std::uint16_t>(*dense, order.data());
        return order;
      case kUnsignedInt:
        copy_indices<std::uint32_t>(*dense, order.data());
        return order;
      default:
        break;
    }
  }
  const auto values = read_accessor(asset, index);
  order.assign(values.begin(), values.end());
  return order;
}

void warn_incomplete_triangle(std::uint64_t n, const std::string& pointer, Diagnostics& diag) {
  if (n % 3 != 0) {
    diag.warning(codes::MESH_PRIMITIVE_INCOMPATIBLE_MODE, pointer,
                 std::to_string(n) + " vertices is not a multiple of 3; the last " +
                     std::to_string(n % 3) + " are ignored");
  }
}

// The primitive's triangles where they lie when that is possible: mode TRIANGLES, POSITION as
// dense floats, indices dense unsigned integers or none. Nothing otherwise (and no diagnostics:
// read_primitive_triangles then reads the primitive, with its diagnostics).
std::optional<TriangleMeshView> view_in_place(const GltfAsset& asset, const Json& prim) {
  if (prim.value("mode", 4) != 4 || !prim["attributes"].contains("POSITION")) return std::nullopt;
  const Json& accessors = asset.document["accessors"];
  const auto points = dense_view(asset, accessors[prim["attributes"]["POSITION"].get<std::size_t>()], 3);
  if (!points || points->component_type != kFloat) return std::nullopt;
  TriangleMeshView view;
  view.positions = points->first;
  view.position_stride = points->stride;
  view.vertex_count = points->count;
  view.position_type = TriangleMeshView::Positions::kFloat32;
  if (!prim.contains("indices")) {
    view.triangle_count = points->count / 3;
    view.index_type = TriangleMeshView::Indices::kNone;
    return view;
  }
  const auto indices = dense_view(asset, accessors[prim["indices"].get<std::size_t>()], 1);
  if (!indices) return std::nullopt;
  switch (indices->component_type) {
    case kUnsignedByte:
      view.index_type = TriangleMeshView::Indices::kUint8;
      break;
    case kUnsignedShort:
      view.index_type = TriangleMeshView::Indices::kUint16;
      break;
    case kUnsignedInt:
      view.index_type = TriangleMeshView::Indices::kUint32;
      break;
    default:
      return std::nullopt;
  }
  view.indices = indices->first;
  view.index_stride = indices->stride;
  view.triangle_count = indices->count / 3;
  return view;
}

// Whether a non-zero weight falls on a morph target that moves POSITION.
bool morphs_positions(const Json& prim, std::span<const double> weights) {
  if (weights.empty() || !prim.contains("targets")) return false;
  const Json& targets = prim["targets"];
  for (std::size_t t = 0; t < targets.size() && t < weights.size(); ++t) {
    if (weights[t] != 0.0 && targets[t].contains("POSITION")) return true;
  }
  return false;
}

}  // namespace

TriangleMesh PrimitiveTriangles::mesh() const {
  if (copy) return *copy;
  TriangleMesh mesh;
  internal::with_typed_view(in_place, [&](const auto& view) {
    mesh.positions.resize(view.vertex_count);
    for (std::size_t v = 0; v < view.vertex_count; ++v) {
      view.vertex(static_cast<std::uint32_t>(v), mesh.positions[v].data());
    }
    mesh.triangles.resize(view.triangle_count);
    for (std::size_t t = 0; t < view.triangle_count; ++t) {
      mesh.triangles[t] = {view.index(3 * t), view.index(3 * t + 1), view.index(3 * t + 2)};
    }
  });
  return mesh;
}

std::vector<double> morph_weights(const Json& document, std::size_t node) {
  const Json& n = document["nodes"][node];
  const Json* weights = nullptr;
  if (n.contains("weights")) {
    weights = &n["weights"];
  } else if (n.contains("mesh")) {
    const Json& mesh = document["meshes"][n["mesh"].get<std::size_t>()];
    if (mesh.contains("weights")) weights = &mesh["weights"];
  }
  std::vector<double> values;
  if (weights == nullptr) return values;
  for (const Json& w : *weights) values.push_back(w.get<double>());
  if (std::all_of(values.begin(), values.end(), [](double w) { return w == 0.0; })) values.clear();
  return values;
}

void add_morph_displacements(const GltfAsset& asset, const Json& primitive, std::span<const double> weights,
                             std::vector<Eigen::Vector3d>& positions) {
  if (!morphs_positions(primitive, weights)) return;
  const Json& targets = primitive["targets"];
  // Target by target, in order: base + w0 t0 + w1 t1 + ..., as the spec writes the sum.
  for (std::size_t t = 0; t < targets.size() && t < weights.size(); ++t) {
    if (weights[t] == 0.0 || !targets[t].contains("POSITION")) continue;
    const auto displacements = read_points(asset, targets[t]["POSITION"].get<std::size_t>());
    const std::size_t n = std::min(displacements.size(), positions.size());  // Equal once validated.
    for (std::size_t i = 0; i < n; ++i) positions[i] += weights[t] * displacements[i];
  }
}

std::optional<PrimitiveTriangles> read_primitive_in_place(const GltfAsset& asset, std::size_t mesh,
                                                          std::size_t primitive, Diagnostics& diag,
                                                          std::span<const double> weights) {
  const Json& prim = asset.document["meshes"][mesh]["primitives"][primitive];
  if (const auto view = morphs_positions(prim, weights) ? std::nullopt : view_in_place(asset, prim)) {
    // What read_primitive_triangles says of the same primitive: the index count (or vertex
    // count, without indices) that is not a multiple of 3.
    const Json& accessors = asset.document["accessors"];
    const std::uint64_t n =
        prim.contains("indices")
            ? accessors[prim["indices"].get<std::size_t>()]["count"].get<std::uint64_t>()
            : view->vertex_count;
    warn_incomplete_triangle(
        n, json_pointer(json_pointer("/meshes", mesh) + "/primitives", primitive), diag);
    return PrimitiveTriangles{*view, std::nullopt};
  }
  auto copy = read_primitive_triangles(asset, mesh, primitive, diag, weights);
  if (!copy) return std::nullopt;
  return PrimitiveTriangles{{}, std::move(copy)};
}

int component_count(const std::string& type) {
  if (type == "SCALAR") return 1;
  if (type == "VEC2") return 2;
  if (type == "VEC3") return 3;
  if (type == "VEC4" || type == "MAT2") return 4;
  if (type == "MAT3") return 9;
  if (type == "MAT4") return 16;
  return 0;
}

std::vector<double> read_accessor(const GltfAsset& asset, std::size_t index) {
  const Json& accessor = asset.document["accessors"][index];
  const auto count = accessor["count"].get<std::uint64_t>();
  const int components = component_count(accessor["type"].get<std::string>());
  const int component_type = accessor["componentType"].get<int>();
  const bool normalized = accessor.value("normalized", false);
  std::vector<double> values(count * components, 0.0);
  if (accessor.contains("bufferView")) {
    read_elements(asset, accessor["bufferView"].get<std::size_t>(),
                  accessor.value("byteOffset", std::uint64_t{0}), count, components,
                  component_type, normalized, component_bytes(component_type) * components,
                  values.data());
  }
  if (accessor.contains("sparse")) {
    const Json& sparse = accessor["sparse"];
    const auto sparse_count = sparse["count"].get<std::uint64_t>();
    const Json& indices = sparse["indices"];
    const auto rows = read_unsigned(asset, indices["bufferView"].get<std::size_t>(),
                                    indices.value("byteOffset", std::uint64_t{0}), sparse_count,
                                    indices["componentType"].get<int>());
    const Json& sparse_values = sparse["values"];
    std::vector<double> replacement(sparse_count * components);
    // Sparse value views are tightly packed: no byteStride applies.
    read_elements(asset, sparse_values["bufferView"].get<std::size_t>(),
                  sparse_values.value("byteOffset", std::uint64_t{0}), sparse_count, components,
                  component_type, normalized, component_bytes(component_type) * components,
                  replacement.data());
    for (std::uint64_t i = 0; i < sparse_count; ++i) {
      std::copy_n(replacement.begin() + static_cast<std::ptrdiff_t>(i * components), components,
                  values.begin() + static_cast<std::ptrdiff_t>(rows[i] * components));
    }
  }
  return values;
}

std::optional<TriangleMesh> read_primitive_triangles(const GltfAsset& asset, std::size_t mesh,
                                                     std::size_t primitive, Diagnostics& diag,
                                                     std::span<const double> weights) {
  const Json& prim = asset.document["meshes"][mesh]["primitives"][primitive];
  const std::string pointer =
      json_pointer(json_pointer("/meshes", mesh) + "/primitives", primitive);
  const int mode = prim.value("mode", 4);
  if (mode < 4) {
    static const char* const kNames[] = {"POINTS", "LINES", "LINE_LOOP", "LINE_STRIP"};
    diag.info(codes::PRIMITIVE_SKIPPED, pointer,
              std::string("primitive of mode ") + kNames[mode] + " has no volume; skipped");
    return std::nullopt;
  }
  if (!prim["attributes"].contains("POSITION")) {
    diag.info(codes::PRIMITIVE_SKIPPED, pointer, "primitive has no POSITION attribute; skipped");
    return std::nullopt;
  }
  TriangleMesh result;
  result.positions = read_points(asset, prim["attributes"]["POSITION"].get<std::size_t>());
  add_morph_displacements(asset, prim, weights, result.positions);
  if (mode == 4 && prim.contains("indices")) {
    const auto indices = prim["indices"].get<std::size_t>();
    if (read_indexed_triangles(asset, indices, result.triangles)) {
      warn_incomplete_triangle(asset.document["accessors"][indices]["count"].get<std::uint64_t>(),
                               pointer, diag);
      return result;
    }
  }
  std::vector<std::uint32_t> order;
  if (prim.contains("indices")) {
    order = read_indices(asset, prim["indices"].get<std::size_t>());
  } else {
    order.resize(result.positions.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
  }
  const std::size_t n = order.size();
  if (mode == 4) {
    result.triangles.resize(n / 3);
    for (std::size_t i = 0; i < n / 3; ++i) {
      result.triangles[i] = {order[3 * i], order[3 * i + 1], order[3 * i + 2]};
    }
    warn_incomplete_triangle(n, pointer, diag);
  } else if (n < 3) {
    // The validator's MESH_PRIMITIVE_INCOMPATIBLE_MODE for a strip or fan too short for a triangle.
    diag.warning(codes::MESH_PRIMITIVE_INCOMPATIBLE_MODE, pointer,
                 std::string("a triangle ") + (mode == 5 ? "strip" : "fan") + " of " + std::to_string(n) +
                     (n == 1 ? " vertex" : " vertices") + " has no triangle; it adds nothing");
  } else if (mode == 5) {
    // glTF 2.0 section 3.7.2.1: triangle i is (i, i + 1 + i%2, i + 2 - i%2).
    for (std::size_t i = 0; i + 2 < n; ++i) {
      result.triangles.push_back({order[i], order[i + 1 + i % 2], order[i + 2 - i % 2]});
    }
  } else {
    for (std::size_t i = 1; i + 1 < n; ++i) {
      result.triangles.push_back({order[i], order[i + 1], order[0]});
    }
  }
  return result;
}

}  // namespace rdtf
