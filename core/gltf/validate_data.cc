// validate_data (rdtf/validate.h): the buffer data the converter reads.
//
// Runs after validate_document, but stays safe without it: every property is read through
// type-checked getters and every element's bytes are bounds-checked against the loaded buffer,
// so an inconsistent asset gives an error, never an out-of-bounds read. Elements are streamed,
// never gathered, and each accessor is read once: the cost is one pass over the data.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <set>

#include "rdtf/geometry.h"
#include "rdtf/validate.h"
#include "validate_semantics.h"
#include "validate_util.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace internal {
namespace {

constexpr int kMaxComponents = 16;

// The float nearest a JSON number (which is a double), kept as it is beyond the float range.
double nearest_float(double number) {
  if (!(std::abs(number) <= std::numeric_limits<float>::max())) return number;
  // Through a volatile float: g++ 12.2's SLP vectoriser deletes double -> float -> double round
  // trips that sit side by side (`p[0] = (float)p[0]; p[1] = (float)p[1];` compiles to nothing at
  // -O2), and this one must round.
  const volatile float rounded = static_cast<float>(number);
  return rounded;
}

// "1 index is", "3 indices are".
std::string counted(std::uint64_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// Columns and rows of an accessor's type; {0, 0} when unknown or missing.
std::pair<int, int> type_shape(const Json& accessor) {
  if (!accessor.contains("type") || !accessor["type"].is_string()) return {0, 0};
  const auto [columns, rows] = accessor_type_shape(accessor["type"].get<std::string>());
  return {static_cast<int>(columns), static_cast<int>(rows)};
}

// Calls f(T{}), T being the C++ type of glTF component type `type` (float when unknown).
template <typename F>
void with_component_type(std::uint64_t type, F&& f) {
  switch (type) {
    case kByte:
      return f(std::int8_t{});
    case kUnsignedByte:
      return f(std::uint8_t{});
    case kShort:
      return f(std::int16_t{});
    case kUnsignedShort:
      return f(std::uint16_t{});
    case kUnsignedInt:
      return f(std::uint32_t{});
    default:
      return f(float{});
  }
}

// Where `count` elements lie: each `stride` bytes apart from `first`, within a loaded buffer.
// Values are raw, not normalized: glTF's min and max bound raw values.
struct Run {
  const std::uint8_t* first = nullptr;  // Null: every element is zero (no bufferView).
  std::uint64_t stride = 0;
  std::uint64_t count = 0;
  std::uint64_t component_type = 0;
  int components = 0;
  std::array<std::uint8_t, kMaxComponents> offsets{};  // Of each component in an element.

  // Matrix columns of 1- and 2-byte components start on 4-byte boundaries (`column_stride`).
  void set_layout(std::uint64_t type, int columns, int rows, std::uint64_t column_stride) {
    component_type = type;
    components = columns * rows;
    for (int c = 0; c < components; ++c) {
      offsets[c] =
          static_cast<std::uint8_t>((c / rows) * column_stride + (c % rows) * component_size(type));
    }
  }

  template <typename T>
  void read_as(std::uint64_t i, double* out) const {
    if (first == nullptr) {
      std::fill(out, out + components, 0.0);
      return;
    }
    const std::uint8_t* element = first + i * stride;
    for (int c = 0; c < components; ++c) {
      T value;
      std::memcpy(&value, element + offsets[c], sizeof(T));
      out[c] = static_cast<double>(value);
    }
  }

  void read(std::uint64_t i, double* out) const {
    with_component_type(component_type, [&](auto zero) { read_as<decltype(zero)>(i, out); });
  }
};

struct AccessorRuns {
  Run base;
  std::optional<Run> sparse_indices;
  std::optional<Run> sparse_values;
};

// What an indices accessor holds, found in one pass and compared with each primitive's vertices.
struct IndexSummary {
  double largest = -1;
  std::uint64_t largest_at = 0;
  std::uint64_t restarts = 0, first_restart = 0;
  std::uint64_t component_type = 0;
  // Dense unsigned indices (nearly every file's) are summarised without the element positions,
  // which only an error message needs: they are found in `dense` when one is reported.
  std::optional<Run> dense;
};

// Index of the first element of a dense run of unsigned T equal to `value` (there is one).
template <typename T>
std::uint64_t first_equal(const Run& run, std::uint64_t value) {
  for (std::uint64_t i = 0; i < run.count; ++i) {
    T v;
    std::memcpy(&v, run.first + i * run.stride, sizeof(T));
    if (v == value) return i;
  }
  return 0;
}

std::uint64_t first_equal(const Run& run, std::uint64_t value) {
  switch (run.component_type) {
    case kUnsignedByte:
      return first_equal<std::uint8_t>(run, value);
    case kUnsignedShort:
      return first_equal<std::uint16_t>(run, value);
    default:
      return first_equal<std::uint32_t>(run, value);
  }
}

// Largest index other than the restart value (the type's largest) and how many restarts. First
// the plain largest value, a reduction the compiler vectorises when the indices are packed: when
// it is not the restart value (always, in a valid file) there are no restarts and that is the
// answer. Otherwise one exact pass. (Issue 6: element by element through doubles, this check was
// 6% of converting a 1M-triangle model.)
template <typename T>
void summarize_dense(const Run& run, IndexSummary& summary) {
  constexpr T kRestart = std::numeric_limits<T>::max();
  summary.dense = run;
  T largest = 0;
  if (run.stride == sizeof(T)) {
    for (std::uint64_t i = 0; i < run.count; ++i) {
      T v;
      std::memcpy(&v, run.first + i * sizeof(T), sizeof(T));
      largest = v > largest ? v : largest;
    }
  } else {
    for (std::uint64_t i = 0; i < run.count; ++i) {
      T v;
      std::memcpy(&v, run.first + i * run.stride, sizeof(T));
      largest = v > largest ? v : largest;
    }
  }
  if (largest != kRestart) {
    summary.largest = static_cast<double>(largest);
    return;
  }
  std::uint64_t restarts = 0;
  largest = 0;
  for (std::uint64_t i = 0; i < run.count; ++i) {
    T v;
    std::memcpy(&v, run.first + i * run.stride, sizeof(T));
    if (v == kRestart) {
      ++restarts;
    } else {
      largest = std::max(largest, v);
    }
  }
  summary.restarts = restarts;
  summary.largest = restarts == run.count ? -1.0 : static_cast<double>(largest);
}

class DataCheck {
 public:
  DataCheck(const GltfAsset& asset, Diagnostics& diag)
      : asset_(asset), doc_(asset.document), diag_(diag) {}

  void run() {
    if (!doc_.is_object() || !buffers_hold_their_bytes()) return;
    const bool listed = doc_.contains("accessors") && doc_["accessors"].is_array();
    readable_.assign(listed ? doc_["accessors"].size() : 0, 0);
    for (std::size_t i = 0; i < readable_.size(); ++i) {
      const auto runs = locate_accessor(i);
      readable_[i] = runs && check_values(i, *runs);
    }
    check_mesh_indices();
    check_skin_joint_indices();
    check_animation_rotations();
    check_skin_influences(asset_, readable_, diag_);
    check_inverse_bind_matrices(asset_, readable_, diag_);
    check_animation_inputs(asset_, readable_, diag_);
  }

 private:
  bool buffers_hold_their_bytes();
  std::optional<Run> locate(std::optional<std::uint64_t> view_index, std::uint64_t offset,
                            std::uint64_t count, std::uint64_t stride, std::uint64_t size);
  std::optional<AccessorRuns> locate_accessor(std::size_t index);
  bool locate_sparse(const Json& sparse, AccessorRuns& runs);
  bool sparse_indices_sound(std::size_t index, const AccessorRuns& runs);
  bool check_values(std::size_t index, const AccessorRuns& runs);
  void report_bounds(std::size_t index, const char* key, int components, const double* declared,
                     const double* actual, const std::uint64_t* outside);
  void check_mesh_indices();
  std::optional<std::uint64_t> vertex_count(const Json& primitive);
  IndexSummary summarize_indices(const AccessorRuns& runs);
  void check_indices(std::uint64_t accessor, std::uint64_t vertices, const std::string& pointer);
  void check_skin_joint_indices();
  void check_animation_rotations();

  // Calls visit(i, components, repeats) for every element, sparse substitution applied. An
  // accessor without a bufferView is zeros: all its zero elements come in one visit.
  template <typename Visit>
  void for_each_element(const AccessorRuns& runs, Visit&& visit) {
    // One switch per accessor, not per component: this loop is the cost of validate_data.
    with_component_type(runs.base.component_type,
                        [&](auto zero) { for_each_element_as<decltype(zero)>(runs, visit); });
  }

  // Sparse indices rise strictly here (sparse_indices_sound ran first).
  template <typename T, typename Visit>
  void for_each_element_as(const AccessorRuns& runs, Visit& visit) {
    double values[kMaxComponents] = {};
    const std::uint64_t sparse_count = runs.sparse_indices ? runs.sparse_indices->count : 0;
    if (runs.base.first == nullptr) {
      std::uint64_t first_zero = 0;
      for (std::uint64_t k = 0; k < sparse_count; ++k) {
        double row = 0;
        runs.sparse_indices->read(k, &row);
        if (row == static_cast<double>(first_zero)) ++first_zero;
        runs.sparse_values->read_as<T>(k, values);
        visit(static_cast<std::uint64_t>(row), values, std::uint64_t{1});
      }
      runs.base.read_as<T>(0, values);
      if (runs.base.count > sparse_count) visit(first_zero, values, runs.base.count - sparse_count);
      return;
    }
    double next_sparse = -1;
    std::uint64_t sparse = 0;
    if (sparse_count > 0) runs.sparse_indices->read(0, &next_sparse);
    for (std::uint64_t i = 0; i < runs.base.count; ++i) {
      if (sparse < sparse_count && next_sparse == static_cast<double>(i)) {
        runs.sparse_values->read_as<T>(sparse, values);
        if (++sparse < sparse_count) runs.sparse_indices->read(sparse, &next_sparse);
      } else {
        runs.base.read_as<T>(i, values);
      }
      visit(i, values, std::uint64_t{1});
    }
  }

  const GltfAsset& asset_;
  const Json& doc_;
  Diagnostics& diag_;
  std::vector<char> readable_;  // Per accessor: located, and its sparse indices are sound.
  std::map<std::uint64_t, IndexSummary> index_summaries_;  // Per indices accessor.
};

bool DataCheck::buffers_hold_their_bytes() {
  if (!doc_.contains("buffers") || !doc_["buffers"].is_array()) return true;
  bool ok = true;
  for (std::size_t i = 0; i < doc_["buffers"].size(); ++i) {
    const auto declared = uint_at(doc_["buffers"][i], "byteLength");
    const std::uint64_t actual = i < asset_.buffers.size() ? asset_.buffers[i].size() : 0;
    if (declared && actual >= *declared) continue;
    diag_.error(codes::BUFFER_BYTE_LENGTH_MISMATCH, json_pointer("/buffers", i),
                "the buffer holds " + std::to_string(actual) + " bytes, less than its byteLength " +
                    (declared ? std::to_string(*declared) : std::string("(missing)")));
    ok = false;
  }
  return ok;
}

// The bytes of `count` elements of `size` bytes, `stride` apart, at `offset` in a buffer view.
std::optional<Run> DataCheck::locate(std::optional<std::uint64_t> view_index, std::uint64_t offset,
                                     std::uint64_t count, std::uint64_t stride,
                                     std::uint64_t size) {
  const Json* view = element_at(doc_, "bufferViews", view_index);
  if (view == nullptr || count == 0) return std::nullopt;
  const auto buffer = uint_at(*view, "buffer");
  const auto length = uint_at(*view, "byteLength");
  const std::uint64_t view_offset = uint_at(*view, "byteOffset").value_or(0);
  if (!buffer || *buffer >= asset_.buffers.size() || !length) return std::nullopt;
  const std::uint64_t available = asset_.buffers[*buffer].size();
  // Every operand is below 2^62 past this test, so no sum or product below overflows.
  const std::uint64_t limit = std::uint64_t{1} << 62;
  if (view_offset > limit || *length > limit || offset > limit || stride > 256 || size > 256 ||
      count > limit / 256 || view_offset + *length > available ||
      offset + (count - 1) * stride + size > *length) {
    return std::nullopt;
  }
  Run run;
  run.first = asset_.buffers[*buffer].data() + view_offset + offset;
  run.stride = stride;
  run.count = count;
  return run;
}

std::optional<AccessorRuns> DataCheck::locate_accessor(std::size_t index) {
  const Json& accessor = doc_["accessors"][index];
  const auto type = uint_at(accessor, "componentType");
  const auto count = uint_at(accessor, "count");
  const auto [columns, rows] = accessor.is_object() ? type_shape(accessor) : std::pair{0, 0};
  const std::uint64_t size = type ? component_size(*type) : 0;
  const auto unreadable = [&] {
    diag_.error(codes::ACCESSOR_DATA_UNREADABLE, json_pointer("/accessors", index),
                "the accessor's data cannot be located in its buffer; the document did not pass "
                "validation");
    return std::nullopt;
  };
  if (size == 0 || !count || *count == 0 || columns == 0) return unreadable();
  const std::uint64_t column_stride = columns > 1 ? (rows * size + 3) / 4 * 4 : rows * size;
  const std::uint64_t element = columns * column_stride;
  AccessorRuns runs;
  if (accessor.contains("bufferView")) {
    const auto view_index = uint_at(accessor, "bufferView");
    const Json* view = element_at(doc_, "bufferViews", view_index);
    const std::uint64_t stride =
        view == nullptr ? 0 : uint_at(*view, "byteStride").value_or(element);
    const auto run =
        locate(view_index, uint_at(accessor, "byteOffset").value_or(0), *count, stride, element);
    if (!run || stride < element) return unreadable();
    runs.base = *run;
  }
  runs.base.count = *count;
  runs.base.set_layout(*type, columns, rows, column_stride);
  if (accessor.contains("sparse") && !locate_sparse(accessor["sparse"], runs)) return unreadable();
  return runs;
}

bool DataCheck::locate_sparse(const Json& sparse, AccessorRuns& runs) {
  const auto count = uint_at(sparse, "count");
  if (!count || !sparse.contains("indices") || !sparse.contains("values")) return false;
  const Json& indices = sparse["indices"];
  const auto index_type = uint_at(indices, "componentType");
  if (!index_type || (*index_type != kUnsignedByte && *index_type != kUnsignedShort &&
                      *index_type != kUnsignedInt)) {
    return false;
  }
  const std::uint64_t index_size = component_size(*index_type);
  runs.sparse_indices =
      locate(uint_at(indices, "bufferView"), uint_at(indices, "byteOffset").value_or(0), *count,
             index_size, index_size);
  const int components = runs.base.components;
  const std::uint64_t element = components * component_size(runs.base.component_type);
  const Json& values = sparse["values"];
  runs.sparse_values = locate(uint_at(values, "bufferView"),
                              uint_at(values, "byteOffset").value_or(0), *count, element, element);
  if (!runs.sparse_indices || !runs.sparse_values) return false;
  runs.sparse_indices->set_layout(*index_type, 1, 1, index_size);
  runs.sparse_values->set_layout(runs.base.component_type, 1, components, element);
  return true;
}

// Sparse indices must rise strictly and stay below the accessor's count, or substitution would
// write outside the accessor.
bool DataCheck::sparse_indices_sound(std::size_t index, const AccessorRuns& runs) {
  const std::string pointer = json_pointer("/accessors", index) + "/sparse";
  double previous = -1;
  for (std::uint64_t k = 0; k < runs.sparse_indices->count; ++k) {
    double value = 0;
    runs.sparse_indices->read(k, &value);
    const std::string at = "sparse index " + std::to_string(k) + " is " +
                           std::to_string(static_cast<std::uint64_t>(value));
    if (value <= previous) {
      diag_.error(codes::ACCESSOR_SPARSE_INDICES_NON_INCREASING, pointer,
                  at + ", not greater than the one before it, " +
                      std::to_string(static_cast<std::uint64_t>(previous)));
      return false;
    }
    if (value >= static_cast<double>(runs.base.count)) {
      diag_.error(
          codes::ACCESSOR_SPARSE_INDEX_OOB, pointer,
          at + ", but the accessor has only " + std::to_string(runs.base.count) + " elements");
      return false;
    }
    previous = value;
  }
  return true;
}

// NaN or infinite floats, and values outside the accessor's declared min and max. False when
// the accessor cannot be read at all (its sparse indices are wrong).
bool DataCheck::check_values(std::size_t index, const AccessorRuns& runs) {
  if (runs.sparse_indices && !sparse_indices_sound(index, runs)) return false;
  const Json& accessor = doc_["accessors"][index];
  const bool is_float = runs.base.component_type == kFloat;
  if (!is_float && !accessor.contains("min") && !accessor.contains("max")) return true;
  // All zeros, a placeholder: the validator does not check its bounds either.
  if (runs.base.first == nullptr && !runs.sparse_indices) return true;
  const int n = runs.base.components;
  // The declared bounds, NaN where there is none. Float data is single precision: it is
  // bounded by the float nearest the number in the JSON.
  double declared[2][kMaxComponents];
  for (int which = 0; which < 2; ++which) {
    const char* key = which == 0 ? "min" : "max";
    const bool usable = accessor.contains(key) && accessor[key].is_array() &&
                        accessor[key].size() == static_cast<std::size_t>(n);
    for (int c = 0; c < n; ++c) {
      const Json* value = usable ? &accessor[key][c] : nullptr;
      const double number =
          value != nullptr && value->is_number() ? value->get<double>() : std::nan("");
      declared[which][c] = is_float ? nearest_float(number) : number;
    }
  }
  double actual[2][kMaxComponents];
  std::uint64_t outside[2][kMaxComponents] = {};
  std::fill_n(actual[0], n, std::numeric_limits<double>::infinity());
  std::fill_n(actual[1], n, -std::numeric_limits<double>::infinity());
  std::uint64_t non_finite = 0, first_non_finite = 0;
  const auto visit = [&](std::uint64_t i, const double* values, std::uint64_t repeats) {
    for (int c = 0; c < n; ++c) {
      const double v = values[c];
      if (!std::isfinite(v)) {
        if (non_finite == 0) first_non_finite = i;
        non_finite += repeats;
        continue;
      }
      actual[0][c] = std::min(actual[0][c], v);
      actual[1][c] = std::max(actual[1][c], v);
      if (v < declared[0][c]) outside[0][c] += repeats;
      if (v > declared[1][c]) outside[1][c] += repeats;
    }
  };
  // Dense floats of up to four components (positions, normals, texture coordinates): the same
  // visit with the component count known at compile time and the common case (every component
  // finite and within the declared bounds) tested at once, so that it runs at the speed of the
  // memory rather than of a loop over a runtime count (issue 6: it was 3% of a 1M-triangle
  // conversion).
  const bool dense_float = is_float && runs.base.first != nullptr && !runs.sparse_indices;
  const auto dense = [&]<int N>() {
    // v within [lo, hi] says at once that v is finite and within its declared bounds (a missing
    // bound, NaN here, bounds nothing; declared bounds are never infinite: JSON has no infinity).
    double lo[N], hi[N];
    for (int c = 0; c < N; ++c) {
      lo[c] = std::isnan(declared[0][c]) ? -std::numeric_limits<double>::max() : declared[0][c];
      hi[c] = std::isnan(declared[1][c]) ? std::numeric_limits<double>::max() : declared[1][c];
    }
    for (std::uint64_t i = 0; i < runs.base.count; ++i) {
      const std::uint8_t* element = runs.base.first + i * runs.base.stride;
      double values[N];
      bool plain = true;
      for (int c = 0; c < N; ++c) {
        float value;
        std::memcpy(&value, element + runs.base.offsets[c], sizeof(value));
        values[c] = value;
        plain &= values[c] >= lo[c] && values[c] <= hi[c];
      }
      if (plain) [[likely]] {
        for (int c = 0; c < N; ++c) {
          actual[0][c] = std::min(actual[0][c], values[c]);
          actual[1][c] = std::max(actual[1][c], values[c]);
        }
      } else {
        visit(i, values, 1);
      }
    }
  };
  if (dense_float && n == 1) {
    dense.operator()<1>();
  } else if (dense_float && n == 2) {
    dense.operator()<2>();
  } else if (dense_float && n == 3) {
    dense.operator()<3>();
  } else if (dense_float && n == 4) {
    dense.operator()<4>();
  } else {
    for_each_element(runs, visit);
  }
  if (non_finite > 0) {
    diag_.error(codes::ACCESSOR_INVALID_FLOAT, json_pointer("/accessors", index),
                counted(non_finite, "component is", "components are") +
                    " NaN or infinite, the first in element " + std::to_string(first_non_finite));
    return true;
  }
  report_bounds(index, "min", n, declared[0], actual[0], outside[0]);
  report_bounds(index, "max", n, declared[1], actual[1], outside[1]);
  return true;
}

void DataCheck::report_bounds(std::size_t index, const char* key, int components,
                              const double* declared, const double* actual,
                              const std::uint64_t* outside) {
  const bool is_min = std::string(key) == "min";
  for (int c = 0; c < components; ++c) {
    if (std::isnan(declared[c])) continue;
    const std::string pointer = json_pointer(json_pointer("/accessors", index) + "/" + key, c);
    const std::string bound = describe(doc_["accessors"][index][key][c]);
    if (outside[c] > 0) {
      diag_.error(
          is_min ? codes::ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND : codes::ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND,
          pointer,
          counted(outside[c], "element has", "elements have") + " component " + std::to_string(c) +
              (is_min ? " below" : " above") + " the declared " + key + " " + bound +
              "; the actual " + key + " is " + number_text(actual[c]));
    } else if (actual[c] != declared[c]) {
      // A loose bound misleads nothing here: the validator calls it an error, rdtf only warns.
      diag_.warning(is_min ? codes::ACCESSOR_MIN_MISMATCH : codes::ACCESSOR_MAX_MISMATCH, pointer,
                    std::string("the declared ") + key + " " + bound + " is not the actual " + key +
                        " " + number_text(actual[c]));
    }
  }
}

// Every index of a primitive names one of its vertices, and none is a primitive restart value.
void DataCheck::check_mesh_indices() {
  if (!doc_.contains("meshes") || !doc_["meshes"].is_array()) return;
  for (std::size_t m = 0; m < doc_["meshes"].size(); ++m) {
    const Json& mesh = doc_["meshes"][m];
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
      continue;
    for (std::size_t p = 0; p < mesh["primitives"].size(); ++p) {
      const Json& primitive = mesh["primitives"][p];
      const auto indices = uint_at(primitive, "indices");
      const auto vertices = vertex_count(primitive);
      if (!indices || *indices >= readable_.size() || !readable_[*indices] || !vertices) continue;
      const std::string pointer =
          json_pointer(json_pointer("/meshes", m) + "/primitives", p) + "/indices";
      check_indices(*indices, *vertices, pointer);
    }
  }
}

// POSITION's count, else any attribute's (validate_document requires them all equal).
std::optional<std::uint64_t> DataCheck::vertex_count(const Json& primitive) {
  if (!primitive.is_object() || !primitive.contains("attributes") ||
      !primitive["attributes"].is_object() || primitive["attributes"].empty()) {
    return std::nullopt;
  }
  const Json& attributes = primitive["attributes"];
  const std::string name = attributes.contains("POSITION") ? "POSITION" : attributes.begin().key();
  const Json* accessor = element_at(doc_, "accessors", uint_at(attributes, name.c_str()));
  return accessor == nullptr ? std::nullopt : uint_at(*accessor, "count");
}

IndexSummary DataCheck::summarize_indices(const AccessorRuns& runs) {
  IndexSummary summary;
  summary.component_type = runs.base.component_type;
  if (runs.base.first != nullptr && !runs.sparse_indices) {
    switch (runs.base.component_type) {
      case kUnsignedByte:
        summarize_dense<std::uint8_t>(runs.base, summary);
        return summary;
      case kUnsignedShort:
        summarize_dense<std::uint16_t>(runs.base, summary);
        return summary;
      case kUnsignedInt:
        summarize_dense<std::uint32_t>(runs.base, summary);
        return summary;
      default:
        break;
    }
  }
  const double restart =
      std::ldexp(1.0, 8 * static_cast<int>(component_size(runs.base.component_type))) - 1;
  for_each_element(runs, [&](std::uint64_t i, const double* value, std::uint64_t repeats) {
    if (*value == restart) {
      if (summary.restarts == 0) summary.first_restart = i;
      summary.restarts += repeats;
    } else if (*value > summary.largest) {
      summary.largest = *value;
      summary.largest_at = i;
    }
  });
  return summary;
}

// Reported where the validator reports it, at the primitive's "indices"; the message names the
// accessor too, which is what a modeller's tools show.
void DataCheck::check_indices(std::uint64_t accessor, std::uint64_t vertices,
                              const std::string& pointer) {
  auto found = index_summaries_.find(accessor);
  if (found == index_summaries_.end()) {
    const auto runs = locate_accessor(accessor);  // Located once already: cannot fail now.
    if (!runs || runs->base.components != 1 || runs->base.component_type == kFloat) return;
    found = index_summaries_.emplace(accessor, summarize_indices(*runs)).first;
  }
  IndexSummary& summary = found->second;
  if (summary.dense &&
      (summary.restarts > 0 || summary.largest >= static_cast<double>(vertices))) {
    // An error is reported: find where (once per accessor).
    const auto restart = (std::uint64_t{1} << (8 * component_size(summary.component_type))) - 1;
    if (summary.restarts > 0) summary.first_restart = first_equal(*summary.dense, restart);
    if (summary.largest >= 0) {
      summary.largest_at = first_equal(*summary.dense, static_cast<std::uint64_t>(summary.largest));
    }
    summary.dense.reset();
  }
  const std::string where = "indices accessor " + std::to_string(accessor) + " (" +
                            json_pointer("/accessors", accessor) + ")";
  if (summary.restarts > 0) {
    const auto restart = (std::uint64_t{1} << (8 * component_size(summary.component_type))) - 1;
    diag_.error(codes::ACCESSOR_INDEX_PRIMITIVE_RESTART, pointer,
                where + " holds the primitive restart value " + std::to_string(restart) + " " +
                    counted(summary.restarts, "time", "times") + ", first at element " +
                    std::to_string(summary.first_restart) + "; glTF forbids it");
  }
  if (summary.largest >= static_cast<double>(vertices)) {
    diag_.error(codes::ACCESSOR_INDEX_OOB, pointer,
                where + " refers to vertex " +
                    std::to_string(static_cast<std::uint64_t>(summary.largest)) + " (element " +
                    std::to_string(summary.largest_at) + "), but the primitive has only " +
                    std::to_string(vertices) + " vertices");
  }
}

// Each rotation key of a node's animation is a unit quaternion, within the validator's tolerance
// (0.00769 of length, as for a node's rotation); a CUBICSPLINE's tangents are not keys. Reported
// once per channel, at its sampler, as the validator does.
void DataCheck::check_animation_rotations() {
  if (!doc_.contains("animations") || !doc_["animations"].is_array()) return;
  const Json& animations = doc_["animations"];
  // The first key that is no unit quaternion, per (output accessor, CUBICSPLINE): many channels may
  // share one sampler, whose keys are read once.
  std::map<std::pair<std::uint64_t, bool>, std::optional<std::pair<std::size_t, double>>> first_bad;  // key, length
  for (std::size_t a = 0; a < animations.size(); ++a) {
    const Json& animation = animations[a];
    if (!animation.is_object() || !animation.contains("channels") || !animation.contains("samplers")) continue;
    const Json& channels = animation["channels"];
    const Json& samplers = animation["samplers"];
    for (std::size_t c = 0; channels.is_array() && c < channels.size(); ++c) {
      const Json& channel = channels[c];
      if (!channel.is_object() || !channel.contains("target") || !channel["target"].is_object() ||
          channel["target"].value("path", "") != "rotation" || !channel.contains("sampler")) {
        continue;
      }
      const auto sampler = uint_at(channel, "sampler");
      if (!sampler || !samplers.is_array() || *sampler >= samplers.size() || !samplers[*sampler].is_object()) continue;
      const auto output = uint_at(samplers[*sampler], "output");
      if (!output || *output >= readable_.size() || !readable_[*output]) continue;
      const Json& accessor = doc_["accessors"][*output];
      if (accessor.value("type", "") != "VEC4") continue;  // reported by validate_document
      const bool cubic = samplers[*sampler].value("interpolation", "") == "CUBICSPLINE";
      const auto [known, added] = first_bad.try_emplace({*output, cubic});
      if (added) {
        const std::vector<double> values = read_accessor(asset_, static_cast<std::size_t>(*output));
        for (std::size_t k = 0; k + 4 <= values.size() && !known->second; k += 4) {
          if (cubic && (k / 4) % 3 != 1) continue;
          const double length = std::sqrt(values[k] * values[k] + values[k + 1] * values[k + 1] +
                                          values[k + 2] * values[k + 2] + values[k + 3] * values[k + 3]);
          if (!(std::abs(length - 1) <= 0.00769)) known->second = std::pair{k, length};
        }
      }
      if (!known->second) continue;
      const auto [k, length] = *known->second;
      diag_.error(codes::ACCESSOR_ANIMATION_SAMPLER_OUTPUT_NON_NORMALIZED_QUATERNION,
                  json_pointer(json_pointer("/animations", a) + "/channels", c) + "/sampler",
                  "rotation key " + std::to_string(k / 4) + " of accessor " + std::to_string(*output) +
                      " (components " + std::to_string(k) + ".." + std::to_string(k + 3) + ") has length " +
                      number_text(length) + "; each key must be a unit quaternion (x, y, z, w)");
    }
  }
}

// Every JOINTS_n value of a skinned mesh names one of its skin's joints (the Khronos validator's
// ACCESSOR_JOINTS_INDEX_OOB): rdtf splits the mesh by the joints' weights, and wrote such an
// index unchanged into an output the validator then refused.
void DataCheck::check_skin_joint_indices() {
  std::set<std::pair<std::uint64_t, std::uint64_t>> checked;  // (accessor, joint count)
  for (const SkinnedPrimitive& skinned : skinned_primitives(doc_)) {
    const std::uint64_t joints = skinned.joint_count;
    for (int set = 0;; ++set) {
      const std::string name = "JOINTS_" + std::to_string(set);
      const auto accessor = uint_at(*skinned.attributes, name.c_str());
      if (!accessor) break;
      if (*accessor >= readable_.size() || !readable_[*accessor] || !checked.emplace(*accessor, joints).second) continue;
      const auto runs = locate_accessor(*accessor);
      if (!runs) continue;
      double largest = -1;
      std::uint64_t largest_at = 0;
      const int components = runs->base.components;
      for_each_element(*runs, [&](std::uint64_t i, const double* value, std::uint64_t) {
        for (int c = 0; c < components; ++c) {
          if (value[c] > largest) {
            largest = value[c];
            largest_at = i;
          }
        }
      });
      if (largest < static_cast<double>(joints)) continue;
      diag_.error(codes::ACCESSOR_JOINTS_INDEX_OOB,
                  json_pointer(json_pointer("/meshes", skinned.mesh) + "/primitives", skinned.primitive) + "/attributes/" +
                      name,
                  name + " accessor " + std::to_string(*accessor) + " (" + json_pointer("/accessors", *accessor) +
                      ") names joint " + std::to_string(static_cast<std::uint64_t>(largest)) + " (element " +
                      std::to_string(largest_at) + "), but the skin of " + node_named(doc_, skinned.node) + " has only " +
                      counted(joints, "joint", "joints"));
    }
  }
}

}  // namespace
}  // namespace internal

void validate_data(const GltfAsset& asset, Diagnostics& diagnostics) {
  internal::DataCheck(asset, diagnostics).run();
}

}  // namespace rdtf
