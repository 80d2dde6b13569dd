// Structural checks of a glTF document before any buffer is loaded (contract: rdtf/validate.h).
//
// The document is untrusted and may be fuzzed: every property is type-checked before it is read
// (nlohmann::json throws on a wrong-type access), and every offset or length is an unsigned
// 64-bit value combined only through overflow-checked arithmetic. Each top-level entry is first
// reduced to the few facts later checks need, so that a check never reads a value that an
// earlier one found broken; a broken entry is reported once, not again by everything using it.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include "rdtf/validate.h"

namespace rdtf {
namespace {

constexpr std::uint64_t kUnsignedByte = 5121, kUnsignedShort = 5123, kUnsignedInt = 5125,
                        kFloat = 5126;
constexpr std::uint64_t kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr double kFloatMax = 3.4028234663852886e38;  // glTF numbers are single precision.
constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

std::uint64_t component_size(std::uint64_t component_type) {
  switch (component_type) {
    case 5120: case 5121: return 1;
    case 5122: case 5123: return 2;
    case 5125: case 5126: return 4;
    default: return 0;
  }
}

// Columns and rows of an accessor type ("VEC3": 1 x 3, "MAT4": 4 x 4); {0, 0} when unknown.
std::pair<int, int> type_shape(const std::string& type) {
  if (type == "SCALAR") return {1, 1};
  if (type == "VEC2") return {1, 2};
  if (type == "VEC3") return {1, 3};
  if (type == "VEC4") return {1, 4};
  if (type == "MAT2") return {2, 2};
  if (type == "MAT3") return {3, 3};
  if (type == "MAT4") return {4, 4};
  return {0, 0};
}

// glTF 2.0 section 3.6.2.4: matrix columns start on 4-byte boundaries, so MAT2 and MAT3 of
// 1- and 2-byte components are padded.
std::uint64_t element_size(const std::string& type, std::uint64_t component_type) {
  const auto [columns, rows] = type_shape(type);
  const std::uint64_t column_bytes = rows * component_size(component_type);
  return columns * (columns > 1 ? (column_bytes + 3) / 4 * 4 : column_bytes);
}

std::optional<std::uint64_t> checked_add(std::uint64_t a, std::uint64_t b) {
  if (b > std::numeric_limits<std::uint64_t>::max() - a) return std::nullopt;
  return a + b;
}

std::optional<std::uint64_t> checked_mul(std::uint64_t a, std::uint64_t b) {
  if (a != 0 && b > std::numeric_limits<std::uint64_t>::max() / a) return std::nullopt;
  return a * b;
}

// One past the last byte of `count` (>= 1) elements of `size` bytes, `stride` apart from `offset`.
std::optional<std::uint64_t> span_end(std::uint64_t offset, std::uint64_t count,
                                      std::uint64_t stride, std::uint64_t size) {
  const auto steps = checked_mul(count - 1, stride);
  if (!steps) return std::nullopt;
  const auto start = checked_add(offset, *steps);
  return start ? checked_add(*start, size) : std::nullopt;
}

std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b) {
  return checked_add(a, b).value_or(std::numeric_limits<std::uint64_t>::max());
}

// A non-negative integer; an integral float (3.0) counts, as JavaScript readers see it.
std::optional<std::uint64_t> as_uint(const Json& value) {
  if (value.is_number_unsigned()) return value.get<std::uint64_t>();
  if (value.is_number_integer() && value.get<std::int64_t>() >= 0) return value.get<std::uint64_t>();
  if (value.is_number_float()) {
    const double d = value.get<double>();
    if (d >= 0 && d < 18446744073709551616.0 && d == std::floor(d)) {
      return static_cast<std::uint64_t>(d);
    }
  }
  return std::nullopt;
}

std::string describe(const Json& value) {
  std::string text = value.dump();
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  return text;
}

// "POSITION", "TEXCOORD_0", "_CUSTOM": the attribute semantics glTF defines, split into name
// and set index (-1 for unindexed). Morph targets allow fewer.
std::optional<std::pair<std::string, long>> parse_semantic(const std::string& name, bool target) {
  if (name.size() > 1 && name[0] == '_') return std::pair{name, -1L};
  if (name == "POSITION" || name == "NORMAL" || name == "TANGENT") return std::pair{name, -1L};
  const auto underscore = name.rfind('_');
  if (underscore == std::string::npos) return std::nullopt;
  const std::string base = name.substr(0, underscore);
  const std::string digits = name.substr(underscore + 1);
  const bool indexed = base == "TEXCOORD" || base == "COLOR" ||
                       (!target && (base == "JOINTS" || base == "WEIGHTS"));
  if (!indexed || digits.empty() || digits.size() > 6 || (digits.size() > 1 && digits[0] == '0') ||
      digits.find_first_not_of("0123456789") != std::string::npos) {
    return std::nullopt;
  }
  return std::pair{base, std::stol(digits)};
}

// Extensions that change nothing the converter reads (geometry, node tree): a model may require
// them. Any other required extension may store geometry where plain accessors do not (Draco,
// meshopt) or multiply it (instancing), so the model is refused rather than misread.
bool extension_is_harmless(const std::string& name) {
  for (const char* prefix : {"KHR_materials_", "KHR_texture_", "EXT_texture_", "KHR_lights_"}) {
    if (name.rfind(prefix, 0) == 0) return true;
  }
  return name == "KHR_mesh_quantization" || name == "KHR_animation_pointer" ||
         name == "KHR_node_visibility" || name == "KHR_xmp_json_ld";
}

struct BufferFacts { bool valid = false; std::uint64_t byte_length = 0; };
struct ViewFacts {
  bool valid = false;
  std::uint64_t byte_offset = 0, byte_length = 0, byte_stride = 0;  // stride 0: not given
  std::uint64_t usage = 0;  // target, or how a mesh first used it (34962 vertices, 34963 indices)
};
struct AccessorFacts {
  bool valid = false;
  std::size_t view = kNone;
  std::string type;
  std::uint64_t component_type = 0, count = 0;
  bool normalized = false;
};
struct MeshFacts { bool valid = false; std::size_t targets = 0; bool skinned = false; std::uint64_t triangles = 0; };
struct NodeFacts { std::vector<std::size_t> children; std::size_t mesh = kNone, skin = kNone; };

class DocumentCheck {
 public:
  DocumentCheck(const Json& document, const LoadLimits& limits, Diagnostics& diag)
      : doc_(document), limits_(limits), diag_(diag) {}

  void run() {
    if (!doc_.is_object()) {
      diag_.error("TYPE_MISMATCH", "", "the glTF JSON must be an object, found " + std::string(doc_.type_name()));
      return;
    }
    check_asset();
    check_extensions_required();
    for (const char* key : {"buffers", "bufferViews", "accessors", "meshes", "nodes", "scenes",
                            "skins", "cameras", "materials", "images", "animations"}) {
      entries_[key] = top_level(key);
    }
    check_buffers();
    check_buffer_views();
    check_accessors();
    check_meshes();
    check_nodes();
    check_node_graph();
    check_skins();
    check_scenes();
    check_images_and_animations();
    check_triangle_limit();
  }

 private:
  // ---- Reading properties, each reporting what is wrong with it --------------------------------

  // The elements of a top-level array, null for those that are not objects.
  std::vector<const Json*> top_level(const char* key) {
    std::vector<const Json*> elements;
    const Json* array = read_array(doc_, key, "");
    if (array == nullptr) return elements;
    for (std::size_t i = 0; i < array->size(); ++i) elements.push_back(object_at(*array, i, json_pointer("", key)));
    return elements;
  }

  const Json* object_at(const Json& array, std::size_t i, const std::string& pointer) {
    if (array[i].is_object()) return &array[i];
    diag_.error("TYPE_MISMATCH", json_pointer(pointer, i),
                "must be an object, found " + std::string(array[i].type_name()) + " " + describe(array[i]));
    return nullptr;
  }

  const Json* find(const Json& object, const char* key, const std::string& pointer, bool required) {
    const auto it = object.find(key);
    if (it != object.end()) return &*it;
    if (required) diag_.error("UNDEFINED_PROPERTY", pointer, std::string("property '") + key + "' must be defined");
    return nullptr;
  }

  const Json* read_typed(const Json& object, const char* key, const std::string& pointer, bool required,
                         bool (Json::*is_type)() const noexcept, const char* type) {
    const Json* value = find(object, key, pointer, required);
    if (value == nullptr || ((*value).*is_type)()) return value;
    diag_.error("TYPE_MISMATCH", json_pointer(pointer, key),
                std::string("must be ") + type + ", found " + value->type_name() + " " + describe(*value));
    return nullptr;
  }

  // An array property; an empty one is reported (glTF arrays have at least one element).
  const Json* read_array(const Json& object, const char* key, const std::string& pointer, bool required = false) {
    const Json* array = read_typed(object, key, pointer, required, &Json::is_array, "an array");
    if (array == nullptr || !array->empty()) return array;
    diag_.error("EMPTY_ENTITY", json_pointer(pointer, key), "the array is empty; leave it out instead");
    return nullptr;
  }

  const Json* read_object(const Json& object, const char* key, const std::string& pointer, bool required = false) {
    return read_typed(object, key, pointer, required, &Json::is_object, "an object");
  }

  std::optional<std::string> read_string(const Json& object, const char* key, const std::string& pointer,
                                         bool required = false) {
    const Json* value = read_typed(object, key, pointer, required, &Json::is_string, "a string");
    return value == nullptr ? std::nullopt : std::optional(value->get<std::string>());
  }

  std::optional<bool> read_bool(const Json& object, const char* key, const std::string& pointer) {
    const Json* value = read_typed(object, key, pointer, false, &Json::is_boolean, "true or false");
    return value == nullptr ? std::nullopt : std::optional(value->get<bool>());
  }

  std::optional<std::uint64_t> uint_value(const Json& value, const std::string& pointer) {
    if (auto number = as_uint(value)) return number;
    if (value.is_number_integer()) {  // Negative.
      diag_.error("VALUE_NOT_IN_RANGE", pointer, "must be a non-negative integer, found " + describe(value));
    } else {
      diag_.error("TYPE_MISMATCH", pointer, "must be an integer, found " + std::string(value.type_name()) + " " + describe(value));
    }
    return std::nullopt;
  }

  std::optional<std::uint64_t> read_uint(const Json& object, const char* key, const std::string& pointer,
                                         bool required = false, std::uint64_t minimum = 0) {
    const Json* value = find(object, key, pointer, required);
    if (value == nullptr) return std::nullopt;
    const auto number = uint_value(*value, json_pointer(pointer, key));
    if (!number || *number >= minimum) return number;
    diag_.error("VALUE_NOT_IN_RANGE", json_pointer(pointer, key),
                "is " + std::to_string(*number) + "; it must be at least " + std::to_string(minimum));
    return std::nullopt;
  }

  std::size_t reference(const Json& value, const std::string& pointer, std::size_t count, const char* what) {
    const auto index = uint_value(value, pointer);
    if (!index) return kNone;
    if (*index < count) return static_cast<std::size_t>(*index);
    diag_.error("UNRESOLVED_REFERENCE", pointer,
                "refers to " + std::string(what) + " " + std::to_string(*index) + ", but the file has " +
                    (count == 0 ? std::string("none") : "only " + std::to_string(count) + " (0.." + std::to_string(count - 1) + ")"));
    return kNone;
  }

  // An index into a top-level array; kNone when absent or wrong (reported).
  std::size_t read_ref(const Json& object, const char* key, const std::string& pointer, const char* array,
                       bool required = false) {
    const Json* value = find(object, key, pointer, required);
    return value == nullptr ? kNone : reference(*value, json_pointer(pointer, key), entries_[array].size(), array);
  }

  // An array of distinct indices into a top-level array; the resolved ones, in order.
  std::vector<std::size_t> read_refs(const Json& object, const char* key, const std::string& pointer,
                                     const char* array, bool required = false) {
    std::vector<std::size_t> result;
    const Json* values = read_array(object, key, pointer, required);
    if (values == nullptr) return result;
    const std::string here = json_pointer(pointer, key);
    std::unordered_set<std::size_t> seen;
    for (std::size_t k = 0; k < values->size(); ++k) {
      const std::size_t index = reference((*values)[k], json_pointer(here, k), entries_[array].size(), array);
      if (index == kNone) continue;
      if (!seen.insert(index).second) {
        diag_.error("DUPLICATE_ELEMENTS", json_pointer(here, k), std::to_string(index) + " is listed twice");
        continue;
      }
      result.push_back(index);
    }
    return result;
  }

  // Finite single-precision numbers, as many as `length` says (0: any number of them).
  std::optional<std::vector<double>> read_numbers(const Json& object, const char* key, const std::string& pointer,
                                                  std::size_t length) {
    const Json* array = read_typed(object, key, pointer, false, &Json::is_array, "an array");
    if (array == nullptr) return std::nullopt;
    const std::string here = json_pointer(pointer, key);
    if (length != 0 && array->size() != length) {
      diag_.error("ARRAY_LENGTH_NOT_IN_LIST", here,
                  "has " + std::to_string(array->size()) + " elements; it must have " + std::to_string(length));
      return std::nullopt;
    }
    std::vector<double> numbers;
    for (std::size_t k = 0; k < array->size(); ++k) {
      const Json& value = (*array)[k];
      if (!value.is_number()) {
        diag_.error("ARRAY_TYPE_MISMATCH", here, "element " + std::to_string(k) + " is " + describe(value) + ", not a number");
        return std::nullopt;
      }
      const double number = value.get<double>();
      if (!std::isfinite(number) || std::abs(number) > kFloatMax) {
        diag_.error("VALUE_NOT_IN_RANGE", json_pointer(here, k),
                    describe(value) + " is beyond the range of a single-precision float");
        return std::nullopt;
      }
      numbers.push_back(number);
    }
    return numbers;
  }

  // ---- Sections ----------------------------------------------------------------------------------

  // "2.0" -> {2, 0}; PATTERN_MISMATCH when it is not MAJOR.MINOR.
  std::optional<std::pair<int, int>> read_version(const Json& asset, const char* key, bool required) {
    const auto text = read_string(asset, key, "/asset", required);
    if (!text) return std::nullopt;
    const auto dot = text->find('.');
    const auto digits = [](const std::string& s) {
      return !s.empty() && s.size() <= 6 && s.find_first_not_of("0123456789") == std::string::npos;
    };
    if (dot == std::string::npos || !digits(text->substr(0, dot)) || !digits(text->substr(dot + 1))) {
      diag_.error("PATTERN_MISMATCH", std::string("/asset/") + key,
                  "'" + *text + "' is not a version of the form MAJOR.MINOR, such as \"2.0\"");
      return std::nullopt;
    }
    return std::pair{std::stoi(text->substr(0, dot)), std::stoi(text->substr(dot + 1))};
  }

  void check_asset() {
    const Json* asset = read_object(doc_, "asset", "", true);
    if (asset == nullptr) return;
    const auto version = read_version(*asset, "version", true);
    if (version && version->first != 2) {
      diag_.error("UNKNOWN_ASSET_MAJOR_VERSION", "/asset/version",
                  "glTF " + std::to_string(version->first) + " is not supported; the model must be glTF 2.x");
    } else if (version && version->second != 0) {
      diag_.warning("UNKNOWN_ASSET_MINOR_VERSION", "/asset/version",
                    "glTF 2." + std::to_string(version->second) + " is newer than 2.0; read as 2.0");
    }
    const auto minimum = read_version(*asset, "minVersion", false);
    if (version && minimum && *minimum > *version) {
      diag_.error("ASSET_MIN_VERSION_GREATER_THAN_VERSION", "/asset/minVersion",
                  "minVersion is greater than version " + std::to_string(version->first) + "." +
                      std::to_string(version->second));
    }
  }

  void check_extensions_required() {
    for (const char* key : {"extensionsUsed", "extensionsRequired"}) {
      const Json* names = read_array(doc_, key, "");
      if (names == nullptr) continue;
      for (std::size_t k = 0; k < names->size(); ++k) {
        const std::string pointer = json_pointer(json_pointer("", key), k);
        if (!(*names)[k].is_string()) {
          diag_.error("TYPE_MISMATCH", pointer, "an extension name must be a string, found " + describe((*names)[k]));
        } else if (std::string(key) == "extensionsUsed" && (*names)[k] == "KHR_mesh_quantization") {
          quantization_ = true;
        } else if (std::string(key) == "extensionsRequired" && !extension_is_harmless((*names)[k])) {
          diag_.error("UNSUPPORTED_EXTENSION", pointer,
                      "the model requires " + (*names)[k].get<std::string>() +
                          ", which rdtf cannot read; export the model without it");
        }
      }
    }
  }

  void check_buffers() {
    const auto& buffers = entries_["buffers"];
    buffers_.resize(buffers.size());
    std::uint64_t total = 0;
    for (std::size_t i = 0; i < buffers.size(); ++i) {
      if (buffers[i] == nullptr) continue;
      const std::string pointer = json_pointer("/buffers", i);
      const auto length = read_uint(*buffers[i], "byteLength", pointer, true, 1);
      const auto uri = read_string(*buffers[i], "uri", pointer);
      const bool uri_ok = !uri || uri->rfind("data:", 0) != 0 || check_data_uri(*uri, length, pointer);
      buffers_[i] = {length.has_value() && uri_ok, length.value_or(0)};
      total = saturating_add(total, length.value_or(0));
    }
    if (total > limits_.max_buffer_bytes) {
      diag_.error("LIMIT_EXCEEDED", "/buffers",
                  "the buffers declare " + std::to_string(total) + " bytes in all, over the limit of " +
                      std::to_string(limits_.max_buffer_bytes) + " bytes");
    }
  }

  // Only base64 data URIs of a buffer media type are readable; their size must be byteLength.
  bool check_data_uri(const std::string& uri, std::optional<std::uint64_t> length, const std::string& pointer) {
    const auto comma = uri.find(',');
    const std::string header = uri.substr(5, comma == std::string::npos ? std::string::npos : comma - 5);
    const std::string suffix = ";base64";
    if (comma == std::string::npos || header.size() < suffix.size() ||
        header.compare(header.size() - suffix.size(), suffix.size(), suffix) != 0) {
      diag_.error("INVALID_URI", pointer + "/uri", "a buffer's data URI must be data:<type>;base64,<data>");
      return false;
    }
    const std::string media_type = header.substr(0, header.size() - suffix.size());
    if (media_type != "application/octet-stream" && media_type != "application/gltf-buffer") {
      diag_.error("BUFFER_DATA_URI_MIME_TYPE_INVALID", pointer + "/uri",
                  "data URI media type '" + media_type + "' must be application/octet-stream or application/gltf-buffer");
      return false;
    }
    const std::string_view data = std::string_view(uri).substr(comma + 1);
    const auto end = data.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/");
    if (end != std::string_view::npos && data.substr(end).find_first_not_of('=') != std::string_view::npos) {
      diag_.error("INVALID_URI", pointer + "/uri", "the data URI has a character that is not base64 at " + std::to_string(end));
      return false;
    }
    const std::uint64_t decoded = (end == std::string_view::npos ? data.size() : end) * 3 / 4;
    if (length && decoded != *length) {
      diag_.error("BUFFER_BYTE_LENGTH_MISMATCH", pointer + "/byteLength",
                  "the data URI holds " + std::to_string(decoded) + " bytes but byteLength is " + std::to_string(*length));
      return false;
    }
    return true;
  }

  void check_buffer_views() {
    const auto& views = entries_["bufferViews"];
    views_.resize(views.size());
    for (std::size_t i = 0; i < views.size(); ++i) {
      if (views[i] == nullptr) continue;
      const Json& view = *views[i];
      const std::string pointer = json_pointer("/bufferViews", i);
      const std::size_t buffer = read_ref(view, "buffer", pointer, "buffers", true);
      const auto offset = read_uint(view, "byteOffset", pointer);
      const auto length = read_uint(view, "byteLength", pointer, true, 1);
      const auto stride = read_stride(view, pointer, length.value_or(0));
      const auto target = read_uint(view, "target", pointer);
      if (target && *target != kArrayBuffer && *target != kElementArrayBuffer) {
        diag_.warning("VALUE_NOT_IN_LIST", pointer + "/target",
                      "target " + std::to_string(*target) + " is neither 34962 (vertices) nor 34963 (indices); ignored");
      }
      ViewFacts& facts = views_[i];
      facts.byte_offset = offset.value_or(0);
      facts.byte_length = length.value_or(0);
      facts.byte_stride = stride.value_or(0);
      facts.usage = target && (*target == kArrayBuffer || *target == kElementArrayBuffer) ? *target : 0;
      if (buffer == kNone || !length || !stride || (view.contains("byteOffset") && !offset) ||
          !buffers_[buffer].valid) {
        continue;
      }
      const std::uint64_t capacity = buffers_[buffer].byte_length;
      const auto end = checked_add(facts.byte_offset, facts.byte_length);
      if (facts.byte_offset >= capacity || !end || *end > capacity) {
        diag_.error("BUFFER_VIEW_TOO_LONG", pointer + (facts.byte_offset >= capacity ? "/byteOffset" : "/byteLength"),
                    "the view (offset " + std::to_string(facts.byte_offset) + ", " + std::to_string(facts.byte_length) +
                        " bytes) does not fit buffer " + std::to_string(buffer) + " of " + std::to_string(capacity) + " bytes");
        continue;
      }
      facts.valid = true;
    }
  }

  // The byteStride (0 when not given), or nothing when it is wrong.
  std::optional<std::uint64_t> read_stride(const Json& view, const std::string& pointer, std::uint64_t length) {
    if (!view.contains("byteStride")) return 0;
    const auto stride = read_uint(view, "byteStride", pointer);
    if (!stride) return std::nullopt;
    const std::string here = pointer + "/byteStride";
    if (*stride < 4 || *stride > 252) {
      diag_.error("VALUE_NOT_IN_RANGE", here, "byteStride " + std::to_string(*stride) + " must be between 4 and 252");
    } else if (*stride % 4 != 0) {
      diag_.error("VALUE_MULTIPLE_OF", here, "byteStride " + std::to_string(*stride) + " must be a multiple of 4");
    } else if (length != 0 && *stride > length) {
      diag_.error("BUFFER_VIEW_TOO_BIG_BYTE_STRIDE", here,
                  "byteStride " + std::to_string(*stride) + " is greater than byteLength " + std::to_string(length));
    } else {
      return stride;
    }
    return std::nullopt;
  }

  // `count` elements of `size` bytes, `stride` apart from `offset`, lie within view `view`.
  bool fits_view(std::size_t view, std::uint64_t offset, std::uint64_t count, std::uint64_t stride,
                 std::uint64_t size, const std::string& pointer) {
    const std::uint64_t length = views_[view].byte_length;
    const auto end = span_end(offset, count, stride, size);
    if (end && *end <= length) return true;
    diag_.error("ACCESSOR_TOO_LONG", offset >= length ? pointer + "/byteOffset" : pointer,
                std::to_string(count) + " elements of " + std::to_string(size) + " bytes, " + std::to_string(stride) +
                    " bytes apart from offset " + std::to_string(offset) + ", need " +
                    (end ? std::to_string(*end) + " bytes" : std::string("more than 2^64 bytes")) + " but buffer view " +
                    std::to_string(view) + " has " + std::to_string(length));
    return false;
  }

  void check_accessors() {
    const auto& accessors = entries_["accessors"];
    accessors_.resize(accessors.size());
    for (std::size_t i = 0; i < accessors.size(); ++i) {
      if (accessors[i] != nullptr) accessors_[i].valid = check_accessor(*accessors[i], json_pointer("/accessors", i), accessors_[i]);
    }
  }

  bool check_accessor(const Json& accessor, const std::string& pointer, AccessorFacts& facts) {
    const auto component_type = read_uint(accessor, "componentType", pointer, true);
    if (component_type && component_size(*component_type) == 0) {
      diag_.error("VALUE_NOT_IN_LIST", pointer + "/componentType",
                  "componentType " + std::to_string(*component_type) +
                      " is not one of 5120 (BYTE), 5121 (UNSIGNED_BYTE), 5122 (SHORT), 5123 (UNSIGNED_SHORT), "
                      "5125 (UNSIGNED_INT), 5126 (FLOAT)");
    }
    const auto type = read_string(accessor, "type", pointer, true);
    if (type && type_shape(*type).first == 0) {
      diag_.error("VALUE_NOT_IN_LIST", pointer + "/type",
                  "type '" + *type + "' is not one of SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3, MAT4");
    }
    const auto count = read_uint(accessor, "count", pointer, true, 1);
    if (count && *count > limits_.max_accessor_count) {
      diag_.error("LIMIT_EXCEEDED", pointer + "/count",
                  "count " + std::to_string(*count) + " is over the limit of " + std::to_string(limits_.max_accessor_count) + " elements");
    }
    facts.normalized = read_bool(accessor, "normalized", pointer).value_or(false);
    if (facts.normalized && component_type && (*component_type == kUnsignedInt || *component_type == kFloat)) {
      diag_.error("ACCESSOR_NORMALIZED_INVALID", pointer + "/normalized",
                  "only BYTE, UNSIGNED_BYTE, SHORT and UNSIGNED_SHORT accessors can be normalized");
    }
    facts.view = read_ref(accessor, "bufferView", pointer, "bufferViews");
    const auto offset = read_uint(accessor, "byteOffset", pointer);
    if (!component_type || component_size(*component_type) == 0 || !type || type_shape(*type).first == 0 || !count ||
        *count > limits_.max_accessor_count || (accessor.contains("bufferView") && facts.view == kNone) ||
        (accessor.contains("byteOffset") && !offset)) {
      return false;
    }
    facts.type = *type;
    facts.component_type = *component_type;
    facts.count = *count;
    const auto [columns, rows] = type_shape(*type);
    bool ok = check_bounds_arrays(accessor, pointer, static_cast<std::size_t>(columns * rows));
    if (facts.view != kNone) ok &= check_accessor_layout(facts, offset.value_or(0), pointer);
    if (accessor.contains("sparse")) ok &= check_sparse(accessor, facts, pointer);
    return ok;
  }

  bool check_bounds_arrays(const Json& accessor, const std::string& pointer, std::size_t components) {
    bool ok = true;
    for (const char* key : {"min", "max"}) {
      if (accessor.contains(key)) ok &= read_numbers(accessor, key, pointer, components).has_value();
    }
    return ok;
  }

  bool check_accessor_layout(const AccessorFacts& facts, std::uint64_t offset, const std::string& pointer) {
    const ViewFacts& view = views_[facts.view];
    if (!view.valid) return false;
    const std::uint64_t size = component_size(facts.component_type);
    const std::uint64_t element = element_size(facts.type, facts.component_type);
    bool ok = true;
    if (offset % size != 0) {
      diag_.error("ACCESSOR_OFFSET_ALIGNMENT", pointer + "/byteOffset",
                  "byteOffset " + std::to_string(offset) + " is not a multiple of the component size " + std::to_string(size));
      ok = false;
    }
    const auto total = checked_add(view.byte_offset, offset);
    if (total && *total % size != 0) {
      diag_.error("ACCESSOR_TOTAL_OFFSET_ALIGNMENT", pointer,
                  "the accessor starts at byte " + std::to_string(*total) + " of its buffer, not a multiple of the component size " +
                      std::to_string(size));
      ok = false;
    }
    if (view.byte_stride != 0 && view.byte_stride < element) {
      diag_.error("ACCESSOR_SMALL_BYTESTRIDE", pointer,
                  "buffer view " + std::to_string(facts.view) + " has byteStride " + std::to_string(view.byte_stride) +
                      ", less than the " + std::to_string(element) + " bytes of one element");
      return false;
    }
    const std::uint64_t stride = view.byte_stride != 0 ? view.byte_stride : element;
    return fits_view(facts.view, offset, facts.count, stride, element, pointer) && ok;
  }

  bool check_sparse(const Json& accessor, const AccessorFacts& facts, const std::string& pointer) {
    const Json* sparse = read_object(accessor, "sparse", pointer);
    if (sparse == nullptr) return false;
    const std::string here = pointer + "/sparse";
    const auto count = read_uint(*sparse, "count", here, true, 1);
    if (count && *count > facts.count) {
      diag_.error("ACCESSOR_SPARSE_COUNT_OUT_OF_RANGE", here + "/count",
                  "the sparse part replaces " + std::to_string(*count) + " elements, more than the accessor's " +
                      std::to_string(facts.count));
      return false;
    }
    const Json* indices = read_object(*sparse, "indices", here, true);
    const Json* values = read_object(*sparse, "values", here, true);
    std::uint64_t index_size = 0;
    if (indices != nullptr) {
      const auto type = read_uint(*indices, "componentType", here + "/indices", true);
      if (type && *type != kUnsignedByte && *type != kUnsignedShort && *type != kUnsignedInt) {
        diag_.error("VALUE_NOT_IN_LIST", here + "/indices/componentType",
                    "sparse indices must be 5121 (UNSIGNED_BYTE), 5123 (UNSIGNED_SHORT) or 5125 (UNSIGNED_INT), found " +
                        std::to_string(*type));
      } else if (type) {
        index_size = component_size(*type);
      }
    }
    const bool indices_ok = indices != nullptr && index_size != 0 && count &&
                            check_sparse_part(*indices, here + "/indices", *count, index_size);
    const bool values_ok = values != nullptr && count &&
                           check_sparse_part(*values, here + "/values", *count, element_size(facts.type, facts.component_type));
    return indices_ok && values_ok;
  }

  // Sparse indices and values are tightly packed: their views may not have a byteStride.
  bool check_sparse_part(const Json& part, const std::string& pointer, std::uint64_t count, std::uint64_t size) {
    const std::size_t view = read_ref(part, "bufferView", pointer, "bufferViews", true);
    const auto offset = read_uint(part, "byteOffset", pointer);
    if (view == kNone || (part.contains("byteOffset") && !offset) || !views_[view].valid) return false;
    if (views_[view].byte_stride != 0) {
      diag_.error("BUFFER_VIEW_INVALID_BYTE_STRIDE", pointer + "/bufferView",
                  "buffer view " + std::to_string(view) + " holds sparse data, so it must not have a byteStride");
      return false;
    }
    return fits_view(view, offset.value_or(0), count, size, size, pointer);
  }

  void check_meshes() {
    const auto& meshes = entries_["meshes"];
    meshes_.resize(meshes.size());
    for (std::size_t m = 0; m < meshes.size(); ++m) {
      if (meshes[m] != nullptr) check_mesh(*meshes[m], json_pointer("/meshes", m), meshes_[m]);
    }
  }

  void check_mesh(const Json& mesh, const std::string& pointer, MeshFacts& facts) {
    const Json* primitives = read_array(mesh, "primitives", pointer, true);
    const auto weights = read_numbers(mesh, "weights", pointer, 0);
    if (primitives == nullptr) return;
    facts.valid = true;
    for (std::size_t p = 0; p < primitives->size(); ++p) {
      const std::string here = json_pointer(pointer + "/primitives", p);
      const Json* primitive = object_at(*primitives, p, pointer + "/primitives");
      if (primitive == nullptr || !check_primitive(*primitive, here, facts)) {
        facts.valid = false;
        continue;
      }
      const std::size_t targets = primitive->contains("targets") ? (*primitive)["targets"].size() : 0;
      if (p == 0) facts.targets = targets;
      if (targets != facts.targets) {
        diag_.error("MESH_PRIMITIVES_UNEQUAL_TARGETS_COUNT", here + (targets != 0 ? "/targets" : ""),
                    "the primitive has " + std::to_string(targets) + " morph targets but the first has " +
                        std::to_string(facts.targets) + "; all primitives of a mesh must have the same number");
      }
    }
    if (weights && facts.valid && weights->size() != facts.targets) {
      diag_.error("MESH_INVALID_WEIGHTS_COUNT", pointer + "/weights",
                  "the mesh has " + std::to_string(weights->size()) + " weights for " + std::to_string(facts.targets) +
                      " morph targets");
    }
  }

  bool check_primitive(const Json& primitive, const std::string& pointer, MeshFacts& mesh) {
    const std::size_t errors = diag_.error_count();
    const Json* attributes = read_object(primitive, "attributes", pointer, true);
    std::map<std::string, std::size_t> accessors;  // Resolved attributes.
    if (attributes != nullptr) accessors = check_attributes(*attributes, pointer + "/attributes", false);
    const std::size_t indices = read_ref(primitive, "indices", pointer, "accessors");
    if (indices != kNone && accessors_[indices].valid) check_indices(indices, pointer + "/indices");
    const auto mode = read_uint(primitive, "mode", pointer).value_or(4);
    if (mode > 6) {
      diag_.error("VALUE_NOT_IN_RANGE", pointer + "/mode",
                  "mode " + std::to_string(mode) + " is not a glTF primitive mode (0 POINTS .. 6 TRIANGLE_FAN)");
    }
    read_ref(primitive, "material", pointer, "materials");
    if (const Json* targets = read_array(primitive, "targets", pointer)) {
      for (std::size_t t = 0; t < targets->size(); ++t) {
        const Json* target = object_at(*targets, t, pointer + "/targets");
        if (target != nullptr) check_target(*target, json_pointer(pointer + "/targets", t), accessors);
      }
    }
    mesh.skinned |= accessors.count("JOINTS_0") > 0;
    const auto position = accessors.find("POSITION");
    const std::uint64_t vertices = indices != kNone ? accessors_[indices].count
                                   : position != accessors.end() ? accessors_[position->second].count : 0;
    if (mode == 4) mesh.triangles = saturating_add(mesh.triangles, vertices / 3);
    if ((mode == 5 || mode == 6) && vertices >= 3) mesh.triangles = saturating_add(mesh.triangles, vertices - 2);
    return diag_.error_count() == errors;
  }

  // Names, references and formats of a primitive's attributes (or a morph target's).
  std::map<std::string, std::size_t> check_attributes(const Json& attributes, const std::string& pointer, bool target) {
    std::map<std::string, std::size_t> resolved;
    std::map<std::string, std::vector<long>> sets;  // "TEXCOORD" -> {0, 1}
    std::uint64_t count = 0;
    for (const auto& [name, value] : attributes.items()) {
      const std::string here = json_pointer(pointer, name);
      const auto semantic = parse_semantic(name, target);
      if (!semantic) diag_.error("MESH_PRIMITIVE_INVALID_ATTRIBUTE", here, "'" + name + "' is not a glTF attribute name");
      const std::size_t accessor = reference(value, here, accessors_.size(), "accessor");
      if (accessor == kNone || !semantic) continue;
      if (semantic->second >= 0) sets[semantic->first].push_back(semantic->second);
      if (!accessors_[accessor].valid) continue;
      resolved[name] = accessor;
      check_attribute_format(name, accessor, here);
      use_view(accessors_[accessor].view, kArrayBuffer, here);
      if (count != 0 && accessors_[accessor].count != count) {
        diag_.error("MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT", here,
                    "has " + std::to_string(accessors_[accessor].count) + " elements but another attribute has " +
                        std::to_string(count) + "; all attributes of a primitive must have the same count");
      }
      count = accessors_[accessor].count;
    }
    for (auto& [base, indices] : sets) {
      std::sort(indices.begin(), indices.end());
      if (indices.back() + 1 != static_cast<long>(indices.size())) {
        diag_.error("MESH_PRIMITIVE_INDEXED_SEMANTIC_CONTINUITY", pointer,
                    base + "_n attributes must be numbered 0, 1, 2... without gaps; found " + std::to_string(indices.size()) +
                        " up to " + base + "_" + std::to_string(indices.back()));
      }
    }
    if (!target && sets["JOINTS"].size() != sets["WEIGHTS"].size()) {
      diag_.error("MESH_PRIMITIVE_JOINTS_WEIGHTS_MISMATCH", pointer,
                  std::to_string(sets["JOINTS"].size()) + " JOINTS_n attributes but " + std::to_string(sets["WEIGHTS"].size()) +
                      " WEIGHTS_n; they come in pairs");
    }
    return resolved;
  }

  // The formats of the attributes the converter reads: POSITION, JOINTS_n, WEIGHTS_n.
  void check_attribute_format(const std::string& name, std::size_t index, const std::string& pointer) {
    const AccessorFacts& accessor = accessors_[index];
    const std::uint64_t type = accessor.component_type;
    bool ok = true;
    std::string expected;
    if (name == "POSITION") {
      const bool quantized = quantization_ && type != kUnsignedInt && type != kFloat;
      ok = accessor.type == "VEC3" && ((type == kFloat && !accessor.normalized) || quantized);
      expected = quantization_ ? "VEC3 of FLOAT, or of (normalized) BYTE or SHORT with KHR_mesh_quantization" : "VEC3 of FLOAT";
    } else if (name.rfind("JOINTS_", 0) == 0) {
      ok = accessor.type == "VEC4" && (type == kUnsignedByte || type == kUnsignedShort) && !accessor.normalized;
      expected = "VEC4 of UNSIGNED_BYTE or UNSIGNED_SHORT";
    } else if (name.rfind("WEIGHTS_", 0) == 0) {
      ok = accessor.type == "VEC4" &&
           (type == kFloat ? !accessor.normalized : (type == kUnsignedByte || type == kUnsignedShort) && accessor.normalized);
      expected = "VEC4 of FLOAT, or of normalized UNSIGNED_BYTE or UNSIGNED_SHORT";
    }
    if (!ok) {
      diag_.error("MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT", pointer,
                  "the accessor is " + accessor.type + " of component type " + std::to_string(type) +
                      (accessor.normalized ? " (normalized)" : "") + "; " + name + " must be " + expected);
    }
    const Json& json = *entries_["accessors"][index];
    if (name == "POSITION" && ok && (!json.contains("min") || !json.contains("max"))) {
      diag_.error("MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS", pointer,
                  "a POSITION accessor must declare min and max (its bounding box)");
    }
  }

  void check_indices(std::size_t indices, const std::string& pointer) {
    const AccessorFacts& accessor = accessors_[indices];
    const std::uint64_t type = accessor.component_type;
    if (accessor.type != "SCALAR" || accessor.normalized ||
        (type != kUnsignedByte && type != kUnsignedShort && type != kUnsignedInt)) {
      diag_.error("MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT", pointer,
                  "indices must be SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT, not " + accessor.type +
                      " of component type " + std::to_string(type));
    }
    if (accessor.view != kNone && views_[accessor.view].byte_stride != 0) {
      diag_.error("MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE", pointer,
                  "buffer view " + std::to_string(accessor.view) + " holds indices, so it must not have a byteStride");
    }
    use_view(accessor.view, kElementArrayBuffer, pointer);
  }

  // A buffer view holds either vertices or indices (its target, else its first use says which).
  void use_view(std::size_t view, std::uint64_t usage, const std::string& pointer) {
    if (view == kNone) return;
    if (views_[view].usage == 0) views_[view].usage = usage;
    if (views_[view].usage == usage) return;
    const auto name = [](std::uint64_t u) { return u == kArrayBuffer ? std::string("vertex") : std::string("index"); };
    diag_.error("BUFFER_VIEW_TARGET_OVERRIDE", pointer,
                "buffer view " + std::to_string(view) + " holds " + name(views_[view].usage) + " data, but is used here for " +
                    name(usage) + " data");
  }

  void check_target(const Json& target, const std::string& pointer, const std::map<std::string, std::size_t>& base) {
    const auto attributes = check_attributes(target, pointer, true);
    for (const auto& [name, value] : target.items()) {
      if (base.count(name) == 0) {
        diag_.error("MESH_PRIMITIVE_MORPH_TARGET_NO_BASE_ACCESSOR", json_pointer(pointer, name),
                    "the morph target moves " + name + ", which the primitive does not have");
      }
    }
    for (const auto& [name, accessor] : attributes) {
      const auto found = base.find(name);
      if (found != base.end() && accessors_[found->second].count != accessors_[accessor].count) {
        diag_.error("MESH_PRIMITIVE_MORPH_TARGET_INVALID_ATTRIBUTE_COUNT", json_pointer(pointer, name),
                    "has " + std::to_string(accessors_[accessor].count) + " elements but the primitive's " + name + " has " +
                        std::to_string(accessors_[found->second].count));
      }
    }
  }

  void check_nodes() {
    const auto& nodes = entries_["nodes"];
    nodes_.resize(nodes.size());
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if (nodes[i] != nullptr) check_node(*nodes[i], json_pointer("/nodes", i), nodes_[i]);
    }
  }

  void check_node(const Json& node, const std::string& pointer, NodeFacts& facts) {
    facts.children = read_refs(node, "children", pointer, "nodes");
    facts.mesh = read_ref(node, "mesh", pointer, "meshes");
    facts.skin = read_ref(node, "skin", pointer, "skins");
    read_ref(node, "camera", pointer, "cameras");
    if (node.contains("skin") && !node.contains("mesh")) {
      diag_.error("UNSATISFIED_DEPENDENCY", pointer + "/skin", "a node with a skin must have a mesh");
    }
    const MeshFacts* mesh = facts.mesh != kNone && meshes_[facts.mesh].valid ? &meshes_[facts.mesh] : nullptr;
    const auto weights = read_numbers(node, "weights", pointer, 0);
    if (weights && mesh != nullptr && weights->size() != mesh->targets) {
      diag_.error("NODE_WEIGHTS_INVALID", pointer + "/weights",
                  "the node has " + std::to_string(weights->size()) + " weights for " + std::to_string(mesh->targets) +
                      " morph targets of mesh " + std::to_string(facts.mesh));
    }
    if (facts.skin != kNone && mesh != nullptr && !mesh->skinned) {
      diag_.error("NODE_SKIN_WITH_NON_SKINNED_MESH", pointer,
                  "the node has a skin but mesh " + std::to_string(facts.mesh) + " has no JOINTS_0 attribute");
    }
    check_transform(node, pointer);
  }

  void check_transform(const Json& node, const std::string& pointer) {
    const auto matrix = read_numbers(node, "matrix", pointer, 16);
    read_numbers(node, "translation", pointer, 3);
    read_numbers(node, "scale", pointer, 3);
    const auto rotation = read_numbers(node, "rotation", pointer, 4);
    if (node.contains("matrix") && (node.contains("translation") || node.contains("rotation") || node.contains("scale"))) {
      diag_.error("NODE_MATRIX_TRS", pointer + "/matrix", "a node has either a matrix or translation/rotation/scale, not both");
    }
    if (matrix && !decomposable(*matrix)) {
      diag_.error("NODE_MATRIX_NON_TRS", pointer + "/matrix",
                  "the matrix is not a translation, rotation and scale (it shears, projects or collapses space); "
                  "apply the transform in the modeller before export");
    }
    if (!rotation) return;
    double norm2 = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      if (std::abs((*rotation)[k]) > 1) {
        diag_.error("VALUE_NOT_IN_RANGE", json_pointer(pointer + "/rotation", k),
                    "a unit quaternion component must lie in [-1, 1], found " + std::to_string((*rotation)[k]));
      }
      norm2 += (*rotation)[k] * (*rotation)[k];
    }
    // The validator's tolerance for unit quaternions stored as floats.
    if (std::abs(std::sqrt(norm2) - 1) > 0.00769) {
      diag_.error("ROTATION_NON_UNIT", pointer + "/rotation",
                  "the rotation quaternion has length " + std::to_string(std::sqrt(norm2)) + "; it must be 1");
    }
  }

  // Column-major: the last row is (0, 0, 0, 1) and the first three columns are orthogonal and
  // non-zero, as the validator requires (it accepts about 1e-5 of shear).
  static bool decomposable(const std::vector<double>& m) {
    if (m[3] != 0 || m[7] != 0 || m[11] != 0 || m[15] != 1) return false;
    double norm[3];
    for (int c = 0; c < 3; ++c) {
      norm[c] = std::sqrt(m[4 * c] * m[4 * c] + m[4 * c + 1] * m[4 * c + 1] + m[4 * c + 2] * m[4 * c + 2]);
      if (!(norm[c] > 0) || !std::isfinite(norm[c])) return false;
    }
    for (int a = 0; a < 3; ++a) {
      for (int b = a + 1; b < 3; ++b) {
        const double dot = m[4 * a] * m[4 * b] + m[4 * a + 1] * m[4 * b + 1] + m[4 * a + 2] * m[4 * b + 2];
        if (std::abs(dot) > 5e-5 * norm[a] * norm[b]) return false;
      }
    }
    return true;
  }

  // At most one parent per node and no loops: the node graph is a forest.
  void check_node_graph() {
    parents_.assign(nodes_.size(), kNone);
    const std::size_t errors = diag_.error_count();
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      for (std::size_t k = 0; k < nodes_[i].children.size(); ++k) {
        const std::size_t child = nodes_[i].children[k];
        if (parents_[child] == kNone) {
          parents_[child] = i;
          continue;
        }
        diag_.error("NODE_PARENT_OVERRIDE", json_pointer(json_pointer("/nodes", i) + "/children", k),
                    "node " + std::to_string(child) + " is already a child of node " + std::to_string(parents_[child]) +
                        "; a node can have only one parent");
      }
    }
    report_loops();
    forest_ = diag_.error_count() == errors;
  }

  // Depth-first along children: meeting a node that is still on the path closes a loop, whose
  // nodes are those on the path from it.
  void report_loops() {
    std::vector<char> state(nodes_.size(), 0);  // 0 unseen, 1 on the path, 2 done
    std::vector<char> reported(nodes_.size(), 0);
    for (std::size_t start = 0; start < nodes_.size(); ++start) {
      if (state[start] != 0) continue;
      std::vector<std::pair<std::size_t, std::size_t>> path = {{start, 0}};  // (node, next child)
      state[start] = 1;
      while (!path.empty()) {
        const std::size_t node = path.back().first;
        if (path.back().second == nodes_[node].children.size()) {
          state[node] = 2;
          path.pop_back();
          continue;
        }
        const std::size_t child = nodes_[node].children[path.back().second++];
        if (state[child] == 0) {
          state[child] = 1;
          path.emplace_back(child, 0);
          continue;
        }
        for (auto it = path.rbegin(); state[child] == 1 && it != path.rend(); ++it) {
          if (!reported[it->first]) {
            reported[it->first] = 1;
            diag_.error("NODE_LOOP", json_pointer("/nodes", it->first),
                        "node " + std::to_string(it->first) + " is its own descendant: the children lists form a loop");
          }
          if (it->first == child) break;
        }
      }
    }
  }

  std::size_t root_of(std::size_t node) const {
    while (parents_[node] != kNone) node = parents_[node];
    return node;
  }

  bool is_ancestor_or_self(std::size_t ancestor, std::size_t node) const {
    for (; node != kNone; node = parents_[node]) {
      if (node == ancestor) return true;
    }
    return false;
  }

  void check_skins() {
    const auto& skins = entries_["skins"];
    skin_joints_.resize(skins.size());
    for (std::size_t s = 0; s < skins.size(); ++s) {
      if (skins[s] == nullptr) continue;
      const std::string pointer = json_pointer("/skins", s);
      const std::size_t errors = diag_.error_count();
      skin_joints_[s] = read_refs(*skins[s], "joints", pointer, "nodes", true);
      const std::size_t skeleton = read_ref(*skins[s], "skeleton", pointer, "nodes");
      const std::size_t matrices = read_ref(*skins[s], "inverseBindMatrices", pointer, "accessors");
      if (matrices != kNone) check_inverse_bind_matrices(matrices, skin_joints_[s].size(), pointer + "/inverseBindMatrices");
      if (!forest_ || diag_.error_count() != errors) continue;
      const std::vector<std::size_t>& joints = skin_joints_[s];
      const std::size_t root = root_of(joints.front());
      if (std::any_of(joints.begin(), joints.end(), [&](std::size_t j) { return root_of(j) != root; })) {
        diag_.error("SKIN_NO_COMMON_ROOT", pointer + "/joints", "the joints are not all in one node tree");
      } else if (skeleton != kNone &&
                 !std::all_of(joints.begin(), joints.end(), [&](std::size_t j) { return is_ancestor_or_self(skeleton, j); })) {
        diag_.error("SKIN_SKELETON_INVALID", pointer + "/skeleton",
                    "skeleton node " + std::to_string(skeleton) + " is not an ancestor of every joint");
      }
    }
  }

  void check_inverse_bind_matrices(std::size_t index, std::size_t joints, const std::string& pointer) {
    const AccessorFacts& accessor = accessors_[index];
    if (!accessor.valid) return;
    if (accessor.type != "MAT4" || accessor.component_type != kFloat || accessor.normalized) {
      diag_.error("SKIN_IBM_INVALID_FORMAT", pointer, "inverse bind matrices must be MAT4 of FLOAT, not " + accessor.type);
    } else if (accessor.count < joints) {
      diag_.error("INVALID_IBM_ACCESSOR_COUNT", pointer,
                  "the accessor has " + std::to_string(accessor.count) + " matrices for " + std::to_string(joints) + " joints");
    }
    if (accessor.view != kNone && views_[accessor.view].byte_stride != 0) {
      diag_.error("SKIN_IBM_ACCESSOR_WITH_BYTESTRIDE", pointer,
                  "buffer view " + std::to_string(accessor.view) + " holds inverse bind matrices, so it must not have a byteStride");
    }
  }

  void check_scenes() {
    read_ref(doc_, "scene", "", "scenes");
    const auto& scenes = entries_["scenes"];
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      if (scenes[s] == nullptr) continue;
      const std::string pointer = json_pointer("/scenes", s);
      const std::vector<std::size_t> roots = read_refs(*scenes[s], "nodes", pointer, "nodes");
      const Json* listed = scenes[s]->contains("nodes") ? &(*scenes[s])["nodes"] : nullptr;
      for (std::size_t k = 0; listed != nullptr && listed->is_array() && k < listed->size(); ++k) {
        const auto node = as_uint((*listed)[k]);
        if (!node || *node >= parents_.size() || parents_[*node] == kNone) continue;
        diag_.error("SCENE_NON_ROOT_NODE", json_pointer(pointer + "/nodes", k),
                    "node " + std::to_string(*node) + " is a child of node " + std::to_string(parents_[*node]) +
                        ", so it cannot be a root of the scene");
      }
      if (forest_) check_skins_in_scene(roots);
    }
  }

  // A skinned mesh in a scene is posed by its joints, which must be in the same scene.
  void check_skins_in_scene(const std::vector<std::size_t>& roots) {
    std::vector<char> in_scene(nodes_.size(), 0);
    std::vector<std::size_t> stack(roots.begin(), roots.end());
    std::vector<std::size_t> skinned;
    while (!stack.empty()) {
      const std::size_t node = stack.back();
      stack.pop_back();
      if (in_scene[node]) continue;
      in_scene[node] = 1;
      if (nodes_[node].skin != kNone && nodes_[node].mesh != kNone) skinned.push_back(node);
      stack.insert(stack.end(), nodes_[node].children.begin(), nodes_[node].children.end());
    }
    for (std::size_t node : skinned) {
      const auto& joints = skin_joints_[nodes_[node].skin];
      if (std::all_of(joints.begin(), joints.end(), [&](std::size_t j) { return in_scene[j]; })) continue;
      diag_.error("NODE_SKIN_NO_SCENE", json_pointer("/nodes", node),
                  "the node's skinned mesh is in a scene that lacks some joints of skin " + std::to_string(nodes_[node].skin));
    }
  }

  // Not geometry, but the converter walks images (to copy them) and animation channels (to
  // retarget them): their shape must be sound.
  void check_images_and_animations() {
    const auto& images = entries_["images"];
    for (std::size_t i = 0; i < images.size(); ++i) {
      if (images[i] == nullptr) continue;
      read_string(*images[i], "uri", json_pointer("/images", i));
      read_ref(*images[i], "bufferView", json_pointer("/images", i), "bufferViews");
    }
    const auto& animations = entries_["animations"];
    for (std::size_t a = 0; a < animations.size(); ++a) {
      if (animations[a] == nullptr) continue;
      const std::string pointer = json_pointer("/animations", a);
      const Json* channels = read_array(*animations[a], "channels", pointer);
      for (std::size_t c = 0; channels != nullptr && c < channels->size(); ++c) {
        const Json* channel = object_at(*channels, c, pointer + "/channels");
        const std::string here = json_pointer(pointer + "/channels", c);
        const Json* target = channel == nullptr ? nullptr : read_object(*channel, "target", here, true);
        if (target == nullptr) continue;
        read_ref(*target, "node", here + "/target", "nodes");
        read_string(*target, "path", here + "/target", true);
      }
    }
  }

  // Every node that uses a mesh makes the converter read and integrate its triangles once more.
  void check_triangle_limit() {
    std::uint64_t total = 0;
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      if (nodes_[i].mesh == kNone) continue;
      total = saturating_add(total, meshes_[nodes_[i].mesh].triangles);
      if (total <= limits_.max_triangles) continue;
      diag_.error("LIMIT_EXCEEDED", json_pointer("/nodes", i) + "/mesh",
                  "with this node the meshes of the model reach " + std::to_string(total) +
                      " triangles (a mesh counts once per node using it), over the limit of " +
                      std::to_string(limits_.max_triangles));
      return;
    }
  }

  const Json& doc_;
  const LoadLimits& limits_;
  Diagnostics& diag_;
  std::map<std::string, std::vector<const Json*>> entries_;  // Top-level arrays; null: not an object.
  bool quantization_ = false;  // KHR_mesh_quantization is used.
  std::vector<BufferFacts> buffers_;
  std::vector<ViewFacts> views_;
  std::vector<AccessorFacts> accessors_;
  std::vector<MeshFacts> meshes_;
  std::vector<NodeFacts> nodes_;
  std::vector<std::size_t> parents_;
  bool forest_ = false;  // No node has two parents and none is its own ancestor.
  std::vector<std::vector<std::size_t>> skin_joints_;
};

}  // namespace

void validate_document(const Json& document, const LoadLimits& limits, Diagnostics& diagnostics) {
  DocumentCheck(document, limits, diagnostics).run();
}

}  // namespace rdtf
