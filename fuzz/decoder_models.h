// The inputs of the `draco` and `meshopt` fuzz targets: a few header bytes (counts and formats)
// and the compressed bytes, made into a GLB whose one mesh the decoder must read. The rest of the
// model is fixed and valid, so every input reaches the decoder, and what it decodes goes on
// through validation, typing and mass properties. Seeds: the encoders' outputs in
// tests/data/encoded/ (fuzz/corpus/<target>/, made by fuzz/make_decoder_seeds.py).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "rdtf/glb.h"
#include "rdtf/gltf.h"

namespace rdtf::fuzz {

inline std::uint32_t little_endian(const std::vector<std::uint8_t>& bytes, std::size_t at, int size) {
  std::uint32_t value = 0;
  for (int k = size - 1; k >= 0; --k) value = value << 8 | bytes[at + static_cast<std::size_t>(k)];
  return value;
}

inline Json one_mesh_document(Json primitive) {
  return {{"asset", {{"version", "2.0"}}},
          {"scene", 0},
          {"scenes", {{{"nodes", {0}}}}},
          {"nodes", {{{"name", "part"}, {"mesh", 0}}}},
          {"meshes", {{{"primitives", {std::move(primitive)}}}}}};
}

inline std::vector<std::uint8_t> glb_of(const Json& document, std::vector<std::uint8_t> bin) {
  while (bin.size() % 4 != 0) bin.push_back(0);
  return make_glb(document.dump(), bin);
}

// [u16 vertices][u16 indices][u8 Draco id of POSITION][u8 flags: bit 0 = 32-bit indices][Draco bytes]
inline std::optional<std::vector<std::uint8_t>> draco_model(const std::vector<std::uint8_t>& bytes) {
  if (bytes.size() < 7) return std::nullopt;
  const std::uint32_t vertices = little_endian(bytes, 0, 2), indices = little_endian(bytes, 2, 2);
  if (vertices == 0 || indices == 0) return std::nullopt;
  const bool wide = (bytes[5] & 1) != 0;
  std::vector<std::uint8_t> payload(bytes.begin() + 6, bytes.end());
  Json document = one_mesh_document(
      {{"attributes", {{"POSITION", 0}}},
       {"indices", 1},
       {"extensions", {{"KHR_draco_mesh_compression", {{"bufferView", 0}, {"attributes", {{"POSITION", bytes[4]}}}}}}}});
  document["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  document["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  document["accessors"] = {
      {{"componentType", 5126}, {"count", vertices}, {"type", "VEC3"}, {"min", {-1, -1, -1}}, {"max", {1, 1, 1}}},
      {{"componentType", wide ? 5125 : 5123}, {"count", indices}, {"type", "SCALAR"}}};
  document["bufferViews"] = {{{"buffer", 0}, {"byteLength", payload.size()}}};
  document["buffers"] = {{{"byteLength", payload.size()}}};
  return glb_of(document, std::move(payload));
}

// [u16 vertices][u16 indices][u8 flags][u16 bytes of the vertex stream][vertex stream][index stream]
// flags: bit 0 positions as VEC3 of UNSIGNED_SHORT, stride 8 (KHR_mesh_quantization), else FLOAT,
// stride 12; bit 1 the EXPONENTIAL filter on FLOAT positions; bit 2 32-bit indices; bit 3 mode
// INDICES, else TRIANGLES.
inline std::optional<std::vector<std::uint8_t>> meshopt_model(const std::vector<std::uint8_t>& bytes) {
  if (bytes.size() < 7) return std::nullopt;
  const std::uint32_t vertices = little_endian(bytes, 0, 2), indices = little_endian(bytes, 2, 2);
  const std::uint8_t flags = bytes[4];
  const std::uint32_t vertex_bytes = little_endian(bytes, 5, 2);
  if (vertices == 0 || indices == 0 || 7 + vertex_bytes > bytes.size()) return std::nullopt;
  const bool quantized = (flags & 1) != 0, wide = (flags & 4) != 0;
  const std::uint32_t vertex_stride = quantized ? 8 : 12, index_stride = wide ? 4 : 2;
  const std::uint32_t index_bytes = static_cast<std::uint32_t>(bytes.size() - 7 - vertex_bytes);
  std::vector<std::uint8_t> compressed(bytes.begin() + 7, bytes.end());
  while (compressed.size() % 4 != 0) compressed.push_back(0);
  const std::uint32_t index_offset = (vertex_bytes + 3) / 4 * 4;
  compressed.insert(compressed.begin() + vertex_bytes, index_offset - vertex_bytes, 0);
  const std::uint64_t decoded_vertices = std::uint64_t{vertices} * vertex_stride;
  const std::uint64_t decoded_indices = std::uint64_t{indices} * index_stride;
  Json vertex_extension = {{"buffer", 0}, {"byteOffset", 0}, {"byteLength", vertex_bytes},
                           {"byteStride", vertex_stride}, {"count", vertices}, {"mode", "ATTRIBUTES"}};
  if (!quantized && (flags & 2) != 0) vertex_extension["filter"] = "EXPONENTIAL";
  Json document = one_mesh_document({{"attributes", {{"POSITION", 0}}}, {"indices", 1}});
  document["extensionsUsed"] = {"EXT_meshopt_compression", "KHR_mesh_quantization"};
  document["extensionsRequired"] = {"EXT_meshopt_compression", "KHR_mesh_quantization"};
  const double limit = quantized ? 65535.0 : 1e6;
  document["accessors"] = {
      {{"bufferView", 0}, {"componentType", quantized ? 5123 : 5126}, {"count", vertices}, {"type", "VEC3"},
       {"min", {quantized ? 0.0 : -limit, quantized ? 0.0 : -limit, quantized ? 0.0 : -limit}},
       {"max", {limit, limit, limit}}},
      {{"bufferView", 1}, {"componentType", wide ? 5125 : 5123}, {"count", indices}, {"type", "SCALAR"}}};
  document["bufferViews"] = {
      {{"buffer", 1}, {"byteLength", decoded_vertices}, {"byteStride", vertex_stride}, {"target", 34962},
       {"extensions", {{"EXT_meshopt_compression", vertex_extension}}}},
      {{"buffer", 1}, {"byteOffset", decoded_vertices}, {"byteLength", decoded_indices}, {"target", 34963},
       {"extensions", {{"EXT_meshopt_compression",
                        {{"buffer", 0}, {"byteOffset", index_offset}, {"byteLength", index_bytes},
                         {"byteStride", index_stride}, {"count", indices},
                         {"mode", (flags & 8) != 0 ? "INDICES" : "TRIANGLES"}}}}}}};
  document["buffers"] = {{{"byteLength", compressed.size()}},
                         {{"byteLength", decoded_vertices + decoded_indices},
                          {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}}};
  return glb_of(document, std::move(compressed));
}

// The converted model as one GLB, every buffer merged into the binary chunk (as `rdtf convert
// --glb` writes it): decoding leaves the decoded data in buffers of their own.
inline std::vector<std::uint8_t> merged_glb(const std::string& output_json, const GltfAsset& asset) {
  Json document = Json::parse(output_json);
  std::vector<std::uint8_t> bin;
  std::vector<std::uint64_t> offsets;
  for (const auto& buffer : asset.buffers) {
    while (bin.size() % 4 != 0) bin.push_back(0);
    offsets.push_back(bin.size());
    bin.insert(bin.end(), buffer.begin(), buffer.end());
  }
  if (document.contains("bufferViews")) {
    for (Json& view : document["bufferViews"]) {
      const auto buffer = view["buffer"].get<std::size_t>();
      view["byteOffset"] = view.value("byteOffset", std::uint64_t{0}) + offsets[buffer];
      view["buffer"] = 0;
    }
  }
  while (bin.size() % 4 != 0) bin.push_back(0);
  document["buffers"] = {{{"byteLength", bin.size()}}};
  return make_glb(document.dump(), bin);
}

}  // namespace rdtf::fuzz
