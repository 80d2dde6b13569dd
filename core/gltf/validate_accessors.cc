// Where the bytes are: buffers, buffer views and accessors (including sparse ones), each checked
// to lie within the one it refers to before anything is allocated. See document_check.h.
#include "document_check.h"
#include "validate_util.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::internal {
namespace {

// glTF 2.0 section 3.6.2.4: matrix columns start on 4-byte boundaries, so MAT2 and MAT3 of 1-
// and 2-byte components are padded.
std::uint64_t element_size(const std::string& type, std::uint64_t component_type) {
  const auto [columns, rows] = accessor_type_shape(type);
  const std::uint64_t column_bytes = rows * component_size(component_type);
  return columns * (columns > 1 ? (column_bytes + 3) / 4 * 4 : column_bytes);
}

// One past the last byte of `count` (>= 1) elements of `size` bytes, `stride` apart from `offset`.
std::optional<std::uint64_t> span_end(std::uint64_t offset, std::uint64_t count,
                                      std::uint64_t stride, std::uint64_t size) {
  const auto steps = checked_mul(count - 1, stride);
  const auto start = steps ? checked_add(offset, *steps) : std::nullopt;
  return start ? checked_add(*start, size) : std::nullopt;
}

}  // namespace

void DocumentCheck::check_buffers() {
  const auto& buffers = entries_["buffers"];
  buffers_.resize(buffers.size());
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    if (buffers[i] == nullptr) continue;
    const std::string pointer = json_pointer("/buffers", i);
    const auto length = read_uint(*buffers[i], "byteLength", pointer, true, 1);
    const auto uri = read_string(*buffers[i], "uri", pointer);
    const bool uri_ok =
        !uri || uri->rfind("data:", 0) != 0 || check_data_uri(*uri, length, pointer);
    buffers_[i] = {length.has_value() && uri_ok, length.value_or(0)};
    total = saturating_add(total, length.value_or(0));
  }
  if (total > limits_.max_buffer_bytes) {
    diag_.error(codes::LIMIT_EXCEEDED, "/buffers",
                "the buffers declare " + std::to_string(total) +
                    " bytes in all, over the limit of " + std::to_string(limits_.max_buffer_bytes) +
                    " bytes");
  }
}

// A buffer's data URI must be base64 of a buffer media type (all the loader decodes), and hold
// exactly byteLength bytes.
bool DocumentCheck::check_data_uri(const std::string& uri, std::optional<std::uint64_t> length,
                                   const std::string& pointer) {
  const auto comma = uri.find(',');
  const std::string header = uri.substr(5, comma == std::string::npos ? comma : comma - 5);
  const std::string suffix = ";base64";
  if (comma == std::string::npos || header.size() < suffix.size() ||
      header.compare(header.size() - suffix.size(), suffix.size(), suffix) != 0) {
    diag_.error(codes::INVALID_URI, pointer + "/uri",
                "a buffer's data URI must be data:<media type>;base64,<data>");
    return false;
  }
  const std::string media_type = header.substr(0, header.size() - suffix.size());
  if (media_type.find(';') != std::string::npos) {
    diag_.error(codes::INVALID_URI, pointer + "/uri",
                "malformed data URI header 'data:" + quote(header) + "'");
    return false;
  }
  if (media_type != "application/octet-stream" && media_type != "application/gltf-buffer") {
    diag_.error(codes::BUFFER_DATA_URI_MIME_TYPE_INVALID, pointer + "/uri",
                "data URI media type '" + quote(media_type) +
                    "' must be application/octet-stream or application/gltf-buffer");
    return false;
  }
  const std::string_view data = std::string_view(uri).substr(comma + 1);
  const auto end =
      data.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/");
  if (end != data.npos && data.substr(end).find_first_not_of('=') != data.npos) {
    diag_.error(
        codes::INVALID_URI, pointer + "/uri",
        "the data URI's payload has a character that is not base64 at " + std::to_string(end));
    return false;
  }
  const std::uint64_t decoded = (end == data.npos ? data.size() : end) * 3 / 4;
  if (length && decoded != *length) {
    diag_.error(codes::BUFFER_BYTE_LENGTH_MISMATCH, pointer + "/byteLength",
                "the data URI holds " + std::to_string(decoded) + " bytes but byteLength is " +
                    std::to_string(*length));
    return false;
  }
  return true;
}

void DocumentCheck::check_buffer_views() {
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
    // A negative target is, for the validator, one more value not in the list (a warning).
    const bool negative_target = view.contains("target") && view["target"].is_number_integer() &&
                                 view["target"].get<std::int64_t>() < 0;
    const auto target = negative_target ? std::nullopt : read_uint(view, "target", pointer);
    const bool known_target = target && (*target == kArrayBuffer || *target == kElementArrayBuffer);
    if (negative_target || (target && !known_target)) {
      diag_.warning(codes::VALUE_NOT_IN_LIST, pointer + "/target",
                    "target " + view["target"].dump() +
                        " is neither 34962 (vertices) nor 34963 (indices); ignored");
    }
    ViewFacts& facts = views_[i];
    const ViewUsage usage = !known_target ? ViewUsage::kUnused
                            : *target == kArrayBuffer ? ViewUsage::kVertexBuffer
                                                      : ViewUsage::kIndexBuffer;
    facts = {false, offset.value_or(0), length.value_or(0), stride.value_or(0), usage};
    if (buffer == kNone || !length || !stride || (view.contains("byteOffset") && !offset) ||
        !buffers_[buffer].valid) {
      continue;
    }
    const std::uint64_t capacity = buffers_[buffer].byte_length;
    const auto end = checked_add(facts.byte_offset, facts.byte_length);
    if (facts.byte_offset >= capacity || !end || *end > capacity) {
      diag_.error(codes::BUFFER_VIEW_TOO_LONG,
                  pointer + (facts.byte_offset >= capacity ? "/byteOffset" : "/byteLength"),
                  "the view (offset " + std::to_string(facts.byte_offset) + ", " +
                      std::to_string(facts.byte_length) + " bytes) does not fit buffer " +
                      std::to_string(buffer) + " of " + std::to_string(capacity) + " bytes");
      continue;
    }
    facts.valid = true;
  }
}

// The byteStride (0 when not given), or nothing when it is wrong.
std::optional<std::uint64_t> DocumentCheck::read_stride(const Json& view,
                                                        const std::string& pointer,
                                                        std::uint64_t length) {
  if (!view.contains("byteStride")) return 0;
  const auto stride = read_uint(view, "byteStride", pointer);
  if (!stride) return std::nullopt;
  const std::string here = pointer + "/byteStride";
  const std::string text = "byteStride " + std::to_string(*stride);
  if (*stride < 4 || *stride > 252) {
    diag_.error(codes::VALUE_NOT_IN_RANGE, here, text + " must be between 4 and 252");
  } else if (*stride % 4 != 0) {
    diag_.error(codes::VALUE_MULTIPLE_OF, here, text + " must be a multiple of 4");
  } else if (length != 0 && *stride > length) {
    diag_.error(codes::BUFFER_VIEW_TOO_BIG_BYTE_STRIDE, here,
                text + " is greater than byteLength " + std::to_string(length));
  } else {
    return stride;
  }
  return std::nullopt;
}

// `count` elements of `size` bytes, `stride` apart from `offset`, lie within buffer view `view`.
bool DocumentCheck::fits_view(std::size_t view, std::uint64_t offset, std::uint64_t count,
                              std::uint64_t stride, std::uint64_t size,
                              const std::string& pointer) {
  const std::uint64_t length = views_[view].byte_length;
  const auto end = span_end(offset, count, stride, size);
  if (end && *end <= length) return true;
  diag_.error(codes::ACCESSOR_TOO_LONG, offset >= length ? pointer + "/byteOffset" : pointer,
              std::to_string(count) + " elements of " + std::to_string(size) + " bytes, " +
                  std::to_string(stride) + " bytes apart from offset " + std::to_string(offset) +
                  ", need " + (end ? std::to_string(*end) : std::string("more than 2^64")) +
                  " bytes, but buffer view " + std::to_string(view) + " has " +
                  std::to_string(length));
  return false;
}

void DocumentCheck::check_accessors() {
  const auto& accessors = entries_["accessors"];
  accessors_.resize(accessors.size());
  for (std::size_t i = 0; i < accessors.size(); ++i) {
    if (accessors[i] == nullptr) continue;
    accessors_[i].valid =
        check_accessor(*accessors[i], json_pointer("/accessors", i), accessors_[i]);
  }
}

bool DocumentCheck::check_accessor(const Json& accessor, const std::string& pointer,
                                   AccessorFacts& facts) {
  const auto component_type = read_uint(accessor, "componentType", pointer, true);
  const bool known_component = component_type && component_size(*component_type) != 0;
  if (component_type && !known_component) {
    diag_.error(codes::VALUE_NOT_IN_LIST, pointer + "/componentType",
                "componentType " + std::to_string(*component_type) +
                    " is not one of 5120 (BYTE), 5121 (UNSIGNED_BYTE), 5122 (SHORT), "
                    "5123 (UNSIGNED_SHORT), 5125 (UNSIGNED_INT), 5126 (FLOAT)");
  }
  const auto type = read_string(accessor, "type", pointer, true);
  const bool known_type = type && accessor_type_shape(*type).first != 0;
  if (type && !known_type) {
    diag_.error(
        codes::VALUE_NOT_IN_LIST, pointer + "/type",
        "type '" + quote(*type) + "' is not one of SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3, MAT4");
  }
  const auto count = read_uint(accessor, "count", pointer, true, 1);
  const bool within_limit = count && *count <= limits_.max_accessor_count;
  if (count && !within_limit) {
    diag_.error(codes::LIMIT_EXCEEDED, pointer + "/count",
                "count " + std::to_string(*count) + " is over the limit of " +
                    std::to_string(limits_.max_accessor_count) + " elements");
  }
  facts.normalized = read_bool(accessor, "normalized", pointer).value_or(false);
  if (facts.normalized && component_type &&
      (*component_type == kUnsignedInt || *component_type == kFloat)) {
    diag_.error(codes::ACCESSOR_NORMALIZED_INVALID, pointer + "/normalized",
                "only BYTE, UNSIGNED_BYTE, SHORT and UNSIGNED_SHORT accessors can be normalized");
  }
  facts.view = read_ref(accessor, "bufferView", pointer, "bufferViews");
  const auto offset = read_uint(accessor, "byteOffset", pointer);
  // The validator asks a matrix's own offset to be a multiple of 4 whatever its components (a
  // float matrix off it is misaligned as floats too, ACCESSOR_OFFSET_ALIGNMENT below).
  if (type && type->rfind("MAT", 0) == 0 && known_type && uint_at(accessor, "bufferView") && offset &&
      *offset % 4 != 0) {
    diag_.error(codes::ACCESSOR_MATRIX_ALIGNMENT, pointer + "/byteOffset",
                "byteOffset " + std::to_string(*offset) + " of a " + *type +
                    " accessor is not a multiple of 4: matrices must start on 4-byte boundaries");
  }
  // An offset into no view (glTF 2.0: byteOffset depends on bufferView) passed into the output,
  // which the Khronos validator refuses (UNSATISFIED_DEPENDENCY).
  const bool offset_without_view = accessor.contains("byteOffset") && !accessor.contains("bufferView");
  if (offset_without_view) {
    diag_.error(codes::UNSATISFIED_DEPENDENCY, pointer + "/byteOffset",
                "byteOffset is given but bufferView is not: an accessor without a buffer view holds zeros "
                "(or only its sparse values) and has no offset; remove byteOffset or give its bufferView");
  }
  if (!known_component || !known_type || !within_limit || offset_without_view ||
      (accessor.contains("bufferView") && facts.view == kNone) ||
      (accessor.contains("byteOffset") && !offset)) {
    return false;
  }
  facts.type = *type;
  facts.component_type = *component_type;
  facts.count = *count;
  const auto [columns, rows] = accessor_type_shape(*type);
  bool ok = true;
  for (const char* key : {"min", "max"}) {
    if (!accessor.contains(key)) continue;
    const auto bounds = read_numbers(accessor, key, pointer, columns * rows);
    ok &= bounds.has_value();
    if (bounds && *component_type != kFloat) ok &= integer_bounds_fit(*bounds, *component_type, json_pointer(pointer, key));
  }
  if (facts.view != kNone) ok &= check_accessor_layout(facts, offset.value_or(0), pointer);
  if (accessor.contains("sparse")) ok &= check_sparse(accessor, facts, pointer);
  return ok;
}

// The min and max of an integer accessor bound raw values of its component type: integers within
// its range (the validator's ARRAY_TYPE_MISMATCH and INVALID_GL_VALUE). A bound no value of the
// type can reach is copied into the output, which the validator then refuses.
bool DocumentCheck::integer_bounds_fit(const std::vector<double>& bounds, std::uint64_t component_type,
                                       const std::string& pointer) {
  double lowest = 0, highest = 0;
  const char* name = "";
  switch (component_type) {
    case kByte: lowest = -128, highest = 127, name = "5120 (BYTE)"; break;
    case kUnsignedByte: highest = 255, name = "5121 (UNSIGNED_BYTE)"; break;
    case kShort: lowest = -32768, highest = 32767, name = "5122 (SHORT)"; break;
    case kUnsignedShort: highest = 65535, name = "5123 (UNSIGNED_SHORT)"; break;
    case kUnsignedInt: highest = 4294967295.0, name = "5125 (UNSIGNED_INT)"; break;
    default: return true;
  }
  for (std::size_t k = 0; k < bounds.size(); ++k) {
    const double value = bounds[k];
    if (value != std::floor(value)) {
      diag_.error(codes::ARRAY_TYPE_MISMATCH, pointer,
                  "element " + std::to_string(k) + " is " + number_text(value) + ", not an integer: the bounds of an accessor of " +
                      "component type " + name + " are raw values of that type, before any normalization");
      return false;
    }
    if (value < lowest || value > highest) {
      diag_.error(codes::INVALID_GL_VALUE, pointer,
                  "element " + std::to_string(k) + " is " + number_text(value) + ", which component type " + name + " cannot hold (" +
                      number_text(lowest) + " to " + number_text(highest) + ")");
      return false;
    }
  }
  return true;
}

bool DocumentCheck::check_accessor_layout(const AccessorFacts& facts, std::uint64_t offset,
                                          const std::string& pointer) {
  const ViewFacts& view = views_[facts.view];
  if (!view.valid) return false;
  const std::uint64_t size = component_size(facts.component_type);
  const std::uint64_t element = element_size(facts.type, facts.component_type);
  bool ok = true;
  if (offset % size != 0) {
    diag_.error(codes::ACCESSOR_OFFSET_ALIGNMENT, pointer + "/byteOffset",
                "byteOffset " + std::to_string(offset) +
                    " is not a multiple of the component size " + std::to_string(size));
    ok = false;
  }
  const auto total = checked_add(view.byte_offset, offset);
  if (total && *total % size != 0) {
    diag_.error(codes::ACCESSOR_TOTAL_OFFSET_ALIGNMENT, pointer,
                "the accessor starts at byte " + std::to_string(*total) +
                    " of its buffer, not a multiple of the component size " + std::to_string(size));
    ok = false;
  }
  if (view.byte_stride != 0 && view.byte_stride < element) {
    diag_.error(codes::ACCESSOR_SMALL_BYTESTRIDE, pointer,
                "buffer view " + std::to_string(facts.view) + " has byteStride " +
                    std::to_string(view.byte_stride) + ", less than the " +
                    std::to_string(element) + " bytes of one element");
    return false;
  }
  const std::uint64_t stride = view.byte_stride != 0 ? view.byte_stride : element;
  return fits_view(facts.view, offset, facts.count, stride, element, pointer) && ok;
}

bool DocumentCheck::check_sparse(const Json& accessor, const AccessorFacts& facts,
                                 const std::string& pointer) {
  const Json* sparse = read_object(accessor, "sparse", pointer);
  if (sparse == nullptr) return false;
  const std::string here = pointer + "/sparse";
  const auto count = read_uint(*sparse, "count", here, true, 1);
  if (count && *count > facts.count) {
    diag_.error(codes::ACCESSOR_SPARSE_COUNT_OUT_OF_RANGE, here + "/count",
                "the sparse part replaces " + std::to_string(*count) +
                    " elements, more than the accessor's " + std::to_string(facts.count));
    return false;
  }
  const Json* indices = read_object(*sparse, "indices", here, true);
  const Json* values = read_object(*sparse, "values", here, true);
  std::uint64_t index_size = 0;
  if (indices != nullptr) {
    const auto type = read_uint(*indices, "componentType", here + "/indices", true);
    if (type && *type != kUnsignedByte && *type != kUnsignedShort && *type != kUnsignedInt) {
      diag_.error(codes::VALUE_NOT_IN_LIST, here + "/indices/componentType",
                  "sparse indices must be 5121 (UNSIGNED_BYTE), 5123 (UNSIGNED_SHORT) or 5125 "
                  "(UNSIGNED_INT), not " +
                      std::to_string(*type));
    } else if (type) {
      index_size = component_size(*type);
    }
  }
  const std::uint64_t element = element_size(facts.type, facts.component_type);
  const bool indices_ok = indices != nullptr && index_size != 0 && count &&
                          check_sparse_part(*indices, here + "/indices", *count, index_size);
  const bool values_ok =
      values != nullptr && count && check_sparse_part(*values, here + "/values", *count, element);
  return indices_ok && values_ok;
}

// Sparse indices and values are tightly packed: their views may not have a byteStride.
bool DocumentCheck::check_sparse_part(const Json& part, const std::string& pointer,
                                      std::uint64_t count, std::uint64_t size) {
  const std::size_t view = read_ref(part, "bufferView", pointer, "bufferViews", true);
  const auto offset = read_uint(part, "byteOffset", pointer);
  if (view == kNone || (part.contains("byteOffset") && !offset) || !views_[view].valid) {
    return false;
  }
  if (views_[view].byte_stride != 0) {
    diag_.error(codes::BUFFER_VIEW_INVALID_BYTE_STRIDE, pointer + "/bufferView",
                "buffer view " + std::to_string(view) +
                    " holds sparse data, so it must not have a byteStride");
    return false;
  }
  return fits_view(view, offset.value_or(0), count, size, size, pointer);
}

}  // namespace rdtf::internal
