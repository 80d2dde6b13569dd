// EXT_meshopt_compression: each compressed buffer view is decoded with libmeshoptimizer into the
// bytes its plain description (buffer, byteOffset, byteLength) names, usually in a "fallback"
// buffer that has no data of its own; then the extension is removed and the view is plain.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>

#include <meshoptimizer.h>

#include "decode.h"
#include "rdtf/diagnostic_codes.h"
#include "validate_util.h"

namespace rdtf::internal {
namespace {

// The fields of one view's extension object, type-checked.
struct MeshoptView {
  std::size_t buffer = 0;
  std::uint64_t byte_offset = 0, byte_length = 0, byte_stride = 0, count = 0;
  std::string mode, filter = "NONE";
};

std::optional<std::uint64_t> read_uint(const Json& object, const char* key, const std::string& pointer,
                                       bool required, Diagnostics& diag) {
  if (!object.contains(key)) {
    if (required) diag.error(codes::MESHOPT_INVALID, pointer, std::string("'") + key + "' is missing");
    return required ? std::nullopt : std::optional<std::uint64_t>(0);
  }
  const auto value = as_uint(object[key]);
  if (!value) {
    diag.error(codes::MESHOPT_INVALID, pointer + "/" + key,
               std::string("'") + key + "' must be a non-negative integer, found " + describe(object[key]));
  }
  return value;
}

std::optional<std::string> read_enum(const Json& object, const char* key, const std::string& pointer,
                                     std::initializer_list<const char*> allowed, bool required,
                                     Diagnostics& diag) {
  if (!object.contains(key) && !required) return std::string(*allowed.begin());
  if (object.contains(key) && object[key].is_string()) {
    for (const char* name : allowed) {
      if (object[key] == name) return std::string(name);
    }
  }
  std::string list;
  for (const char* name : allowed) list += (list.empty() ? "" : ", ") + std::string(name);
  diag.error(codes::MESHOPT_INVALID, pointer + "/" + key,
             std::string("'") + key + "' must be one of " + list + ", found " +
                 (object.contains(key) ? describe(object[key]) : std::string("nothing")));
  return std::nullopt;
}

std::optional<MeshoptView> read_extension(const Json& extension, const std::string& pointer,
                                          std::size_t buffer_count, Diagnostics& diag) {
  if (!extension.is_object()) {
    diag.error(codes::MESHOPT_INVALID, pointer, "the extension must be an object, found " + describe(extension));
    return std::nullopt;
  }
  MeshoptView view;
  const auto buffer = read_uint(extension, "buffer", pointer, true, diag);
  const auto offset = read_uint(extension, "byteOffset", pointer, false, diag);
  const auto length = read_uint(extension, "byteLength", pointer, true, diag);
  const auto stride = read_uint(extension, "byteStride", pointer, true, diag);
  const auto count = read_uint(extension, "count", pointer, true, diag);
  const auto mode = read_enum(extension, "mode", pointer, {"ATTRIBUTES", "TRIANGLES", "INDICES"}, true, diag);
  const auto filter = read_enum(extension, "filter", pointer,
                                {"NONE", "OCTAHEDRAL", "QUATERNION", "EXPONENTIAL"}, false, diag);
  if (!buffer || !offset || !length || !stride || !count || !mode || !filter) return std::nullopt;
  if (*buffer >= buffer_count) {
    diag.error(codes::MESHOPT_INVALID, pointer + "/buffer",
               "buffer " + std::to_string(*buffer) + " does not exist (" + std::to_string(buffer_count) +
                   " buffers)");
    return std::nullopt;
  }
  view = {static_cast<std::size_t>(*buffer), *offset, *length, *stride, *count, *mode, *filter};
  return view;
}

// The layout rules of the extension (and libmeshoptimizer's preconditions, which it asserts).
bool layout_ok(const MeshoptView& view, const std::string& pointer, Diagnostics& diag) {
  std::string why;
  if (view.mode == "ATTRIBUTES") {
    if (view.byte_stride == 0 || view.byte_stride > 256 || view.byte_stride % 4 != 0) {
      why = "ATTRIBUTES need a byteStride that is a multiple of 4 up to 256";
    } else if (view.filter == "OCTAHEDRAL" && view.byte_stride != 4 && view.byte_stride != 8) {
      why = "the OCTAHEDRAL filter needs a byteStride of 4 or 8";
    } else if (view.filter == "QUATERNION" && view.byte_stride != 8) {
      why = "the QUATERNION filter needs a byteStride of 8";
    }
  } else {
    if (view.byte_stride != 2 && view.byte_stride != 4) {
      why = view.mode + " need a byteStride of 2 or 4";
    } else if (view.filter != "NONE") {
      why = "filters apply to ATTRIBUTES only";
    } else if (view.mode == "TRIANGLES" && view.count % 3 != 0) {
      why = "TRIANGLES need a count that is a multiple of 3";
    }
  }
  if (!why.empty()) {
    diag.error(codes::MESHOPT_INVALID, pointer,
               why + " (byteStride " + std::to_string(view.byte_stride) + ", count " +
                   std::to_string(view.count) + ", mode " + view.mode + ", filter " + view.filter + ")");
    return false;
  }
  return true;
}

// The quantization step of each element of a filtered view, read from its encoded elements (the
// filter decoders' own layout, EXT_meshopt_compression "Filters"); nothing for the other filters:
// - QUATERNION: each element stores three components as round(q * sqrt(2) * sf), with sf in its
//   fourth int16 (low two bits the index of the dropped component): a step of 1 / (sqrt(2) sf).
//   The filter has 4 to 16 bits (sf = 2^(K-1) - 1 >= 7): a smaller sf is no encoder's, and widens
//   nothing (an element (0, 0, 0, 3) claimed a step of 0.24, a tolerance of 54 degrees);
// - EXPONENTIAL: each int32 is a mantissa (low 24 bits, signed) times 2^e (the high byte, signed):
//   a step of 2^e, taken at most as 1/64 of the element's largest value (an encoder keeps 7 bits
//   or more of the largest; a zero stored with e = 127 claimed a step of 2^127).
std::vector<double> filter_steps(const std::vector<std::uint8_t>& encoded, std::size_t count, std::size_t stride,
                                 const std::string& filter) {
  std::vector<double> steps;
  if (filter == "QUATERNION") {
    steps.assign(count, 0.0);
    for (std::size_t i = 0; i < count; ++i) {
      std::int16_t fourth = 0;
      std::memcpy(&fourth, encoded.data() + i * stride + 6, sizeof fourth);
      const int sf = fourth | 3;
      if (sf >= 7) steps[i] = 1.0 / (std::sqrt(2.0) * sf);
    }
  } else if (filter == "EXPONENTIAL") {
    steps.assign(count, 0.0);
    for (std::size_t i = 0; i < count; ++i) {
      double step = 0.0, largest = 0.0;
      for (std::size_t c = 0; c < stride / 4; ++c) {
        std::int32_t word = 0;
        std::memcpy(&word, encoded.data() + i * stride + 4 * c, sizeof word);
        const int exponent = word >> 24;
        // The low 24 bits, sign-extended (shifted as unsigned: no signed overflow).
        const std::int32_t mantissa = static_cast<std::int32_t>(static_cast<std::uint32_t>(word) << 8) >> 8;
        step = std::max(step, std::ldexp(1.0, exponent));
        largest = std::max(largest, std::abs(std::ldexp(static_cast<double>(mantissa), exponent)));
      }
      steps[i] = std::min(step, largest / 64);
    }
  }
  return steps;
}

bool decode_view(GltfAsset& asset, std::size_t index, Diagnostics& diag) {
  Json& view_json = asset.document["bufferViews"][index];
  const std::string view_pointer = json_pointer("/bufferViews", index);
  const std::string pointer = view_pointer + "/extensions/" + kMeshoptExtension;
  const auto view = read_extension(view_json["extensions"][kMeshoptExtension], pointer,
                                   asset.buffers.size(), diag);
  if (!view || !layout_ok(*view, pointer, diag)) return false;

  // Where the decoded bytes go: the view's own range, which validate_document checked against
  // its buffer's byteLength (a fallback buffer was sized to it already).
  const std::size_t target = view_json["buffer"].get<std::size_t>();
  const std::uint64_t target_offset = view_json.contains("byteOffset") ? view_json["byteOffset"].get<std::uint64_t>() : 0;
  const std::uint64_t target_length = view_json["byteLength"].get<std::uint64_t>();
  const auto decoded_bytes = checked_mul(view->count, view->byte_stride);
  if (!decoded_bytes || *decoded_bytes > target_length) {
    diag.error(codes::MESHOPT_INVALID, pointer + "/count",
               std::to_string(view->count) + " elements of " + std::to_string(view->byte_stride) +
                   " bytes do not fit the buffer view's byteLength of " + std::to_string(target_length));
    return false;
  }
  if (view->count > asset.limits.max_accessor_count) {
    diag.error(codes::LIMIT_EXCEEDED, pointer + "/count",
               std::to_string(view->count) + " elements, over the limit of " +
                   std::to_string(asset.limits.max_accessor_count) + " (max_accessor_count)");
    return false;
  }
  const auto& source_buffer = asset.buffers[view->buffer];
  const auto source_end = checked_add(view->byte_offset, view->byte_length);
  if (!source_end || *source_end > source_buffer.size()) {
    diag.error(codes::MESHOPT_INVALID, pointer + "/byteLength",
               "the compressed bytes (offset " + std::to_string(view->byte_offset) + ", length " +
                   std::to_string(view->byte_length) + ") lie outside buffer " +
                   std::to_string(view->buffer) + " of " + std::to_string(source_buffer.size()) +
                   " loaded bytes");
    return false;
  }
  // Into a scratch vector first: the source and the target may be the same buffer.
  std::vector<std::uint8_t> decoded(static_cast<std::size_t>(*decoded_bytes));
  const unsigned char* source = source_buffer.data() + view->byte_offset;
  const auto source_size = static_cast<std::size_t>(view->byte_length);
  const auto count = static_cast<std::size_t>(view->count);
  const auto stride = static_cast<std::size_t>(view->byte_stride);
  int status = 0;
  if (view->mode == "ATTRIBUTES") {
    status = meshopt_decodeVertexBuffer(decoded.data(), count, stride, source, source_size);
  } else if (view->mode == "TRIANGLES") {
    status = meshopt_decodeIndexBuffer(decoded.data(), count, stride, source, source_size);
  } else {
    status = meshopt_decodeIndexSequence(decoded.data(), count, stride, source, source_size);
  }
  if (status != 0) {
    diag.error(codes::MESHOPT_INVALID, pointer,
               "libmeshoptimizer could not decode the " + view->mode + " data (" +
                   std::to_string(view->byte_length) + " bytes into " + std::to_string(view->count) +
                   " elements of " + std::to_string(view->byte_stride) + " bytes; status " +
                   std::to_string(status) + ")");
    return false;
  }
  if (count > 0) {
    if (auto steps = filter_steps(decoded, count, stride, view->filter); !steps.empty()) {
      asset.filter_steps[index] = {stride, std::move(steps)};
    }
    if (view->filter == "OCTAHEDRAL") meshopt_decodeFilterOct(decoded.data(), count, stride);
    if (view->filter == "QUATERNION") meshopt_decodeFilterQuat(decoded.data(), count, stride);
    if (view->filter == "EXPONENTIAL") meshopt_decodeFilterExp(decoded.data(), count, stride);
  }
  auto& target_buffer = asset.buffers[target];
  if (target_offset + decoded.size() > target_buffer.size()) {
    diag.error(codes::MESHOPT_INVALID, view_pointer,
               "the buffer view lies outside buffer " + std::to_string(target) + " as loaded (" +
                   std::to_string(target_buffer.size()) + " bytes)");
    return false;
  }
  if (!decoded.empty()) std::memcpy(target_buffer.data() + target_offset, decoded.data(), decoded.size());
  drop_extension(view_json, kMeshoptExtension);
  return true;
}

}  // namespace

bool decode_meshopt(GltfAsset& asset, bool& decoded, Diagnostics& diag) {
  Json& document = asset.document;
  if (!document.contains("bufferViews")) return true;
  // Fallback buffers get their declared size (counted in max_buffer_bytes by validate_document).
  if (document.contains("buffers")) {
    for (std::size_t b = 0; b < document["buffers"].size() && b < asset.buffers.size(); ++b) {
      Json& buffer = document["buffers"][b];
      if (!is_meshopt_fallback(buffer)) continue;
      if (asset.buffers[b].empty()) asset.buffers[b].resize(buffer["byteLength"].get<std::size_t>());
      drop_extension(buffer, kMeshoptExtension);
    }
  }
  bool ok = true;
  std::size_t views = 0;
  for (std::size_t v = 0; v < document["bufferViews"].size(); ++v) {
    const Json& view = document["bufferViews"][v];
    if (!view.contains("extensions") || !view["extensions"].is_object() ||
        !view["extensions"].contains(kMeshoptExtension)) {
      continue;
    }
    if (decode_view(asset, v, diag)) {
      ++views;
    } else {
      ok = false;
    }
  }
  if (ok && views > 0) {
    // Once the name leaves extensionsUsed, no object may keep the extension (UNDECLARED_EXTENSION
    // when the output is checked again): a buffer that is no fallback ({"fallback": false}) keeps
    // its bytes, and the extension says nothing more of them.
    if (document.contains("buffers") && document["buffers"].is_array()) {
      for (Json& buffer : document["buffers"]) {
        if (buffer.is_object()) drop_extension(buffer, kMeshoptExtension);
      }
    }
    drop_extension_name(document, kMeshoptExtension);
    diag.info(codes::COMPRESSION_DECODED, "/bufferViews",
              std::to_string(views) + " buffer view(s) decoded from EXT_meshopt_compression; the "
              "output holds them uncompressed");
    decoded = true;
  }
  return ok;
}

}  // namespace rdtf::internal
