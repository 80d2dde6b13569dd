// Checks of the buffer data the converter reads (contract: rdtf/validate.h).
//
// Runs after validate_document, but stays safe without it: every property is read through
// type-checked getters and every element's bytes are bounds-checked against the loaded buffer,
// so an inconsistent asset gives an error, never an out-of-bounds read. Elements are streamed,
// never gathered: checking costs no memory beyond the buffers already loaded.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "rdtf/validate.h"

namespace rdtf {
namespace {

constexpr std::uint64_t kFloat = 5126;
constexpr int kMaxComponents = 16;

std::optional<std::uint64_t> uint_at(const Json& object, const char* key) {
  if (!object.is_object() || !object.contains(key)) return std::nullopt;
  const Json& value = object[key];
  if (value.is_number_unsigned()) return value.get<std::uint64_t>();
  if (value.is_number_integer() && value.get<std::int64_t>() >= 0) return value.get<std::uint64_t>();
  if (value.is_number_float() && value.get<double>() >= 0 && value.get<double>() < 1.8e19 &&
      value.get<double>() == std::floor(value.get<double>())) {
    return static_cast<std::uint64_t>(value.get<double>());
  }
  return std::nullopt;
}

const Json* element_at(const Json& document, const char* array, std::optional<std::uint64_t> index) {
  if (!index || !document.contains(array) || !document[array].is_array() || *index >= document[array].size()) {
    return nullptr;
  }
  const Json& element = document[array][static_cast<std::size_t>(*index)];
  return element.is_object() ? &element : nullptr;
}

std::uint64_t component_size(std::uint64_t type) {
  return type == 5120 || type == 5121 ? 1 : type == 5122 || type == 5123 ? 2 : type == 5125 || type == 5126 ? 4 : 0;
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

// The raw value of one component (not normalized: glTF's min/max bound raw values).
double read_component(const std::uint8_t* bytes, std::uint64_t type) {
  switch (type) {
    case 5120: { std::int8_t v; std::memcpy(&v, bytes, 1); return v; }
    case 5121: return *bytes;
    case 5122: { std::int16_t v; std::memcpy(&v, bytes, 2); return v; }
    case 5123: { std::uint16_t v; std::memcpy(&v, bytes, 2); return v; }
    case 5125: { std::uint32_t v; std::memcpy(&v, bytes, 4); return v; }
    default: { float v; std::memcpy(&v, bytes, 4); return v; }
  }
}

// Where `count` elements lie: each `stride` bytes apart from `first`, within a loaded buffer.
struct Run {
  const std::uint8_t* first = nullptr;  // Null: every element is zero (no bufferView).
  std::uint64_t stride = 0;
  std::uint64_t count = 0;
  std::uint64_t component_type = 0;
  int components = 0;
  // Column layout of MAT2/MAT3 of small components: columns start on 4-byte boundaries.
  int rows = 0;
  std::uint64_t column_stride = 0;

  void read(std::uint64_t i, double* out) const {
    if (first == nullptr) {
      std::fill(out, out + components, 0.0);
      return;
    }
    const std::uint8_t* element = first + i * stride;
    const std::uint64_t size = component_size(component_type);
    for (int c = 0; c < components; ++c) {
      out[c] = read_component(element + (c / rows) * column_stride + (c % rows) * size, component_type);
    }
  }
};

struct AccessorRuns {
  Run base;
  std::optional<Run> sparse_indices;
  std::optional<Run> sparse_values;
};

class DataCheck {
 public:
  DataCheck(const GltfAsset& asset, Diagnostics& diag) : asset_(asset), doc_(asset.document), diag_(diag) {}

  void run() {
    if (!doc_.is_object() || !buffers_hold_their_bytes()) return;
    const std::size_t accessors = doc_.contains("accessors") && doc_["accessors"].is_array() ? doc_["accessors"].size() : 0;
    runs_.resize(accessors);
    for (std::size_t i = 0; i < accessors; ++i) runs_[i] = locate_accessor(i);
    for (std::size_t i = 0; i < accessors; ++i) {
      if (runs_[i] && !check_values(i, *runs_[i])) runs_[i].reset();
    }
    check_mesh_indices();
  }

 private:
  bool buffers_hold_their_bytes() {
    if (!doc_.contains("buffers") || !doc_["buffers"].is_array()) return true;
    bool ok = true;
    for (std::size_t i = 0; i < doc_["buffers"].size(); ++i) {
      const auto declared = uint_at(doc_["buffers"][i], "byteLength");
      const std::uint64_t actual = i < asset_.buffers.size() ? asset_.buffers[i].size() : 0;
      if (declared && actual >= *declared) continue;
      diag_.error("BUFFER_BYTE_LENGTH_MISMATCH", json_pointer("/buffers", i),
                  "the buffer holds " + std::to_string(actual) + " bytes, less than its byteLength " +
                      (declared ? std::to_string(*declared) : std::string("(missing)")));
      ok = false;
    }
    return ok;
  }

  // The bytes of `count` elements of `size` bytes, `stride` apart, at `offset` in a buffer view.
  std::optional<Run> locate(std::optional<std::uint64_t> view_index, std::uint64_t offset, std::uint64_t count,
                            std::uint64_t stride, std::uint64_t size) {
    const Json* view = element_at(doc_, "bufferViews", view_index);
    if (view == nullptr || count == 0) return std::nullopt;
    const auto buffer = uint_at(*view, "buffer");
    const auto length = uint_at(*view, "byteLength");
    const std::uint64_t view_offset = uint_at(*view, "byteOffset").value_or(0);
    if (!buffer || *buffer >= asset_.buffers.size() || !length) return std::nullopt;
    const std::uint64_t available = asset_.buffers[*buffer].size();
    const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() / 4;
    // Every operand is below 2^62 here, so none of the sums or the product below can overflow.
    if (view_offset > limit || *length > limit || offset > limit || stride > 256 || size > 256 || count > limit / 256 ||
        view_offset + *length > available || offset + (count - 1) * stride + size > *length) {
      return std::nullopt;
    }
    Run run;
    run.first = asset_.buffers[*buffer].data() + view_offset + offset;
    run.stride = stride;
    run.count = count;
    return run;
  }

  std::optional<AccessorRuns> locate_accessor(std::size_t index) {
    const Json& accessor = doc_["accessors"][index];
    const auto type = uint_at(accessor, "componentType");
    const auto count = uint_at(accessor, "count");
    const int components = accessor.is_object() && accessor.contains("type") && accessor["type"].is_string()
                               ? component_count(accessor["type"].get<std::string>()) : 0;
    if (!type || component_size(*type) == 0 || !count || *count == 0 || components == 0) return unreadable(index);
    AccessorRuns runs;
    const int columns = components == 4 && accessor["type"] == "MAT2" ? 2 : components == 9 ? 3 : components == 16 ? 4 : 1;
    const int rows = components / columns;
    const std::uint64_t size = component_size(*type);
    const std::uint64_t column_stride = columns > 1 ? (rows * size + 3) / 4 * 4 : rows * size;
    const std::uint64_t element = columns * column_stride;
    if (accessor.contains("bufferView")) {
      const Json* view = element_at(doc_, "bufferViews", uint_at(accessor, "bufferView"));
      const std::uint64_t stride = view == nullptr ? 0 : uint_at(*view, "byteStride").value_or(element);
      auto run = locate(uint_at(accessor, "bufferView"), uint_at(accessor, "byteOffset").value_or(0), *count, stride, element);
      if (!run || stride < element) return unreadable(index);
      runs.base = *run;
    }
    runs.base.count = *count;
    runs.base.component_type = *type;
    runs.base.components = components;
    runs.base.rows = rows;
    runs.base.column_stride = column_stride;
    if (accessor.contains("sparse") && !locate_sparse(accessor["sparse"], runs)) return unreadable(index);
    return runs;
  }

  bool locate_sparse(const Json& sparse, AccessorRuns& runs) {
    const auto count = uint_at(sparse, "count");
    if (!count || !sparse.contains("indices") || !sparse.contains("values")) return false;
    const Json& indices = sparse["indices"];
    const auto index_type = uint_at(indices, "componentType");
    if (!index_type || (*index_type != 5121 && *index_type != 5123 && *index_type != 5125)) return false;
    const std::uint64_t index_size = component_size(*index_type);
    runs.sparse_indices = locate(uint_at(indices, "bufferView"), uint_at(indices, "byteOffset").value_or(0), *count,
                                 index_size, index_size);
    const std::uint64_t element = runs.base.components * component_size(runs.base.component_type);
    const Json& values = sparse["values"];
    runs.sparse_values = locate(uint_at(values, "bufferView"), uint_at(values, "byteOffset").value_or(0), *count,
                                element, element);
    if (!runs.sparse_indices || !runs.sparse_values) return false;
    runs.sparse_indices->component_type = *index_type;
    runs.sparse_indices->components = runs.sparse_indices->rows = 1;
    runs.sparse_indices->column_stride = index_size;
    runs.sparse_values->component_type = runs.base.component_type;
    runs.sparse_values->components = runs.sparse_values->rows = runs.base.components;
    runs.sparse_values->column_stride = element;
    return true;
  }

  std::optional<AccessorRuns> unreadable(std::size_t index) {
    diag_.error("ACCESSOR_DATA_UNREADABLE", json_pointer("/accessors", index),
                "the accessor's data cannot be located in its buffer; the document did not pass validation");
    return std::nullopt;
  }

  // Sparse indices must rise strictly and stay below the accessor's count, or substitution
  // would write outside the accessor.
  bool sparse_indices_sound(std::size_t index, const AccessorRuns& runs) {
    const std::string pointer = json_pointer("/accessors", index) + "/sparse";
    double previous = -1;
    for (std::uint64_t k = 0; k < runs.sparse_indices->count; ++k) {
      double value;
      runs.sparse_indices->read(k, &value);
      if (value <= previous) {
        diag_.error("ACCESSOR_SPARSE_INDICES_NON_INCREASING", pointer,
                    "sparse index " + std::to_string(k) + " is " + std::to_string(static_cast<std::uint64_t>(value)) +
                        ", not greater than the one before (" + std::to_string(static_cast<std::uint64_t>(previous)) + ")");
        return false;
      }
      if (value >= static_cast<double>(runs.base.count)) {
        diag_.error("ACCESSOR_SPARSE_INDEX_OOB", pointer,
                    "sparse index " + std::to_string(k) + " is " + std::to_string(static_cast<std::uint64_t>(value)) +
                        ", but the accessor has only " + std::to_string(runs.base.count) + " elements");
        return false;
      }
      previous = value;
    }
    return true;
  }

  // Calls visit(i, components, repeats) for every element, sparse substitution applied. An
  // accessor without a bufferView is zeros: all its zero elements come in one visit.
  template <typename Visit>
  void for_each_element(const AccessorRuns& runs, Visit&& visit) {
    double values[kMaxComponents];
    const std::uint64_t sparse_count = runs.sparse_indices ? runs.sparse_indices->count : 0;
    if (runs.base.first == nullptr) {
      std::uint64_t first_zero = 0;  // Sparse indices rise strictly (checked first).
      for (std::uint64_t k = 0; k < sparse_count; ++k) {
        double row;
        runs.sparse_indices->read(k, &row);
        if (row == static_cast<double>(first_zero)) ++first_zero;
        runs.sparse_values->read(k, values);
        visit(static_cast<std::uint64_t>(row), values, std::uint64_t{1});
      }
      runs.base.read(0, values);
      if (runs.base.count > sparse_count) visit(first_zero, values, runs.base.count - sparse_count);
      return;
    }
    double next_sparse = -1;
    std::uint64_t sparse = 0;
    if (sparse_count > 0) runs.sparse_indices->read(0, &next_sparse);
    for (std::uint64_t i = 0; i < runs.base.count; ++i) {
      if (sparse < sparse_count && next_sparse == static_cast<double>(i)) {
        runs.sparse_values->read(sparse, values);
        if (++sparse < sparse_count) runs.sparse_indices->read(sparse, &next_sparse);
      } else {
        runs.base.read(i, values);
      }
      visit(i, values, std::uint64_t{1});
    }
  }

  // NaN or infinite floats, and values outside the accessor's declared min/max.
  // False when the accessor cannot be read at all (its sparse indices are wrong).
  bool check_values(std::size_t index, const AccessorRuns& runs) {
    if (runs.sparse_indices && !sparse_indices_sound(index, runs)) return false;
    const Json& accessor = doc_["accessors"][index];
    const int n = runs.base.components;
    const bool is_float = runs.base.component_type == kFloat;
    std::vector<double> actual_min(n, std::numeric_limits<double>::infinity());
    std::vector<double> actual_max(n, -std::numeric_limits<double>::infinity());
    std::uint64_t non_finite = 0, first_non_finite = 0;
    for_each_element(runs, [&](std::uint64_t i, const double* values, std::uint64_t repeats) {
      for (int c = 0; c < n; ++c) {
        if (!std::isfinite(values[c])) {
          if (non_finite == 0) first_non_finite = i;
          non_finite += repeats;
          continue;
        }
        actual_min[c] = std::min(actual_min[c], values[c]);
        actual_max[c] = std::max(actual_max[c], values[c]);
      }
    });
    const std::string pointer = json_pointer("/accessors", index);
    if (non_finite > 0) {
      diag_.error("ACCESSOR_INVALID_FLOAT", pointer,
                  std::to_string(non_finite) + " components are NaN or infinite, the first in element " +
                      std::to_string(first_non_finite));
      return true;
    }
    check_bound(accessor, "min", pointer, actual_min, is_float, runs);
    check_bound(accessor, "max", pointer, actual_max, is_float, runs);
    return true;
  }

  void check_bound(const Json& accessor, const char* key, const std::string& pointer, const std::vector<double>& actual,
                   bool is_float, const AccessorRuns& runs) {
    if (!accessor.contains(key) || !accessor[key].is_array() || accessor[key].size() != actual.size()) return;
    const bool is_min = std::string(key) == "min";
    for (std::size_t c = 0; c < actual.size(); ++c) {
      const Json& value = accessor[key][c];
      if (!value.is_number()) continue;
      // Float data is single precision: compare with the declared bound as the file's float.
      const double declared = is_float ? static_cast<double>(static_cast<float>(value.get<double>())) : value.get<double>();
      const std::string here = json_pointer(pointer + "/" + key, c);
      const bool outside = is_min ? actual[c] < declared : actual[c] > declared;
      if (outside) {
        diag_.error(is_min ? "ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND" : "ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND", here,
                    std::to_string(count_outside(runs, c, declared, is_min)) + " elements have component " +
                        std::to_string(c) + " " + (is_min ? "below" : "above") + " the declared " + key + " " +
                        value.dump() + " (actual " + key + " " + std::to_string(actual[c]) + ")");
      } else if (actual[c] != declared) {
        // A loose bound misleads no one here: the validator calls it an error, we only warn.
        diag_.warning(is_min ? "ACCESSOR_MIN_MISMATCH" : "ACCESSOR_MAX_MISMATCH", here,
                      std::string("declared ") + key + " " + value.dump() + " is not the actual " + key + " " +
                          std::to_string(actual[c]));
      }
    }
  }

  std::uint64_t count_outside(const AccessorRuns& runs, std::size_t component, double bound, bool is_min) {
    std::uint64_t outside = 0;
    for_each_element(runs, [&](std::uint64_t, const double* values, std::uint64_t repeats) {
      outside += (is_min ? values[component] < bound : values[component] > bound) ? repeats : 0;
    });
    return outside;
  }

  // Every index of a primitive names one of its vertices; none is a primitive restart value.
  void check_mesh_indices() {
    if (!doc_.contains("meshes") || !doc_["meshes"].is_array()) return;
    std::set<std::pair<std::uint64_t, std::uint64_t>> checked;  // (indices accessor, vertex count)
    for (std::size_t m = 0; m < doc_["meshes"].size(); ++m) {
      const Json& mesh = doc_["meshes"][m];
      if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
      for (std::size_t p = 0; p < mesh["primitives"].size(); ++p) {
        const Json& primitive = mesh["primitives"][p];
        const auto indices = uint_at(primitive, "indices");
        const auto vertices = vertex_count(primitive);
        if (!indices || *indices >= runs_.size() || !runs_[*indices] || !vertices ||
            !checked.emplace(*indices, *vertices).second) {
          continue;
        }
        check_indices(*runs_[*indices], *vertices, json_pointer(json_pointer("/meshes", m) + "/primitives", p) + "/indices");
      }
    }
  }

  // POSITION's count, else any attribute's (the validator requires them all equal).
  std::optional<std::uint64_t> vertex_count(const Json& primitive) {
    if (!primitive.is_object() || !primitive.contains("attributes") || !primitive["attributes"].is_object() ||
        primitive["attributes"].empty()) {
      return std::nullopt;
    }
    const Json& attributes = primitive["attributes"];
    const Json* accessor = element_at(doc_, "accessors", uint_at(attributes, attributes.contains("POSITION") ? "POSITION" : attributes.begin().key().c_str()));
    return accessor == nullptr ? std::nullopt : uint_at(*accessor, "count");
  }

  void check_indices(const AccessorRuns& runs, std::uint64_t vertices, const std::string& pointer) {
    if (runs.base.components != 1 || runs.base.component_type == kFloat) return;  // validate_document reports it
    const double restart = std::ldexp(1.0, 8 * static_cast<int>(component_size(runs.base.component_type))) - 1;
    std::uint64_t out_of_range = 0, restarts = 0, first_bad = 0;
    double first_value = 0;
    for_each_element(runs, [&](std::uint64_t i, const double* value, std::uint64_t repeats) {
      const bool is_restart = *value == restart;
      if (!is_restart && *value < static_cast<double>(vertices)) return;
      if (out_of_range + restarts == 0) {
        first_bad = i;
        first_value = *value;
      }
      (is_restart ? restarts : out_of_range) += repeats;
    });
    const std::string first = "element " + std::to_string(first_bad) + " is " + std::to_string(static_cast<std::uint64_t>(first_value));
    if (restarts > 0) {
      diag_.error("ACCESSOR_INDEX_PRIMITIVE_RESTART", pointer,
                  std::to_string(restarts) + " indices are the primitive restart value " +
                      std::to_string(static_cast<std::uint64_t>(restart)) + ", which glTF forbids (first: " + first + ")");
    }
    if (out_of_range > 0) {
      diag_.error("ACCESSOR_INDEX_OOB", pointer,
                  std::to_string(out_of_range) + " indices are not below the vertex count " + std::to_string(vertices) +
                      " (first: " + first + ")");
    }
  }

  const GltfAsset& asset_;
  const Json& doc_;
  Diagnostics& diag_;
  std::vector<std::optional<AccessorRuns>> runs_;  // Per accessor; nothing when unreadable.
};

}  // namespace

void validate_data(const GltfAsset& asset, Diagnostics& diagnostics) { DataCheck(asset, diagnostics).run(); }

}  // namespace rdtf
