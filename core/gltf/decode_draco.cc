// KHR_draco_mesh_compression: each compressed primitive is decoded with libdraco; its indices and
// the attributes the extension names are written, in the types their accessors declare, into one
// new buffer with a buffer view per accessor; then the extension is removed and the primitive is
// plain. The compressed bytes stay in their (now unused) buffer view.
#include <algorithm>
#include <cstring>
#include <map>
#include <set>
#include <optional>
#include <string>

#include <draco/compression/decode.h>

#include "decode.h"
#include "draco_header.h"
#include "rdtf/diagnostic_codes.h"
#include "validate_util.h"

namespace rdtf::internal {
namespace {

std::uint64_t element_bytes(const Json& accessor) {
  static const std::map<std::string, std::uint64_t> kComponents{
      {"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}};
  const auto found = kComponents.find(accessor["type"].get<std::string>());
  if (found == kComponents.end()) return 0;
  return found->second * component_size(accessor["componentType"].get<std::uint64_t>());
}

std::uint64_t round_up4(std::uint64_t n) { return (n + 3) / 4 * 4; }

// One accessor to fill: where, and from what.
struct Output {
  std::size_t accessor = 0;
  const draco::PointAttribute* attribute = nullptr;  // Null: the indices.
  std::uint64_t offset = 0, stride = 0, length = 0;
  std::string name;  // The primitive's attribute ("POSITION"); empty for the indices.
};

// The attribute's values in the accessor's component type, and their per-component bounds:
// quantization moves values past the min and max the encoder declared for the original data.
template <typename T>
bool write_values(const draco::Mesh& mesh, const draco::PointAttribute& attribute, int components,
                  std::uint64_t stride, std::uint8_t* out, Json& min, Json& max) {
  T value[4];
  std::vector<T> low(static_cast<std::size_t>(components)), high(static_cast<std::size_t>(components));
  for (draco::PointIndex::ValueType p = 0; p < mesh.num_points(); ++p) {
    const draco::AttributeValueIndex index = attribute.mapped_index(draco::PointIndex(p));
    if (index.value() >= attribute.size()) return false;
    if (!attribute.ConvertValue<T>(index, static_cast<int8_t>(components), value)) return false;
    std::memcpy(out + p * stride, value, sizeof(T) * static_cast<std::size_t>(components));
    for (std::size_t k = 0; k < low.size(); ++k) {
      low[k] = p == 0 ? value[k] : std::min(low[k], value[k]);
      high[k] = p == 0 ? value[k] : std::max(high[k], value[k]);
    }
  }
  min = Json::array();
  max = Json::array();
  for (std::size_t k = 0; k < low.size(); ++k) {
    min.push_back(low[k]);
    max.push_back(high[k]);
  }
  return true;
}

bool write_attribute(const draco::Mesh& mesh, const draco::PointAttribute& attribute,
                     Json& accessor, std::uint64_t stride, std::uint8_t* out) {
  const int components = static_cast<int>(element_bytes(accessor) /
                                          component_size(accessor["componentType"].get<std::uint64_t>()));
  Json min, max;
  bool ok = false;
  switch (accessor["componentType"].get<std::uint64_t>()) {
    case kByte: ok = write_values<std::int8_t>(mesh, attribute, components, stride, out, min, max); break;
    case kUnsignedByte: ok = write_values<std::uint8_t>(mesh, attribute, components, stride, out, min, max); break;
    case kShort: ok = write_values<std::int16_t>(mesh, attribute, components, stride, out, min, max); break;
    case kUnsignedShort: ok = write_values<std::uint16_t>(mesh, attribute, components, stride, out, min, max); break;
    case kUnsignedInt: ok = write_values<std::uint32_t>(mesh, attribute, components, stride, out, min, max); break;
    case kFloat: ok = write_values<float>(mesh, attribute, components, stride, out, min, max); break;
    default: return false;
  }
  // Bounds of the decoded values, where the accessor declares any (POSITION must).
  if (ok && mesh.num_points() > 0 && (accessor.contains("min") || accessor.contains("max"))) {
    accessor["min"] = std::move(min);
    accessor["max"] = std::move(max);
  }
  return ok;
}

void write_indices(const draco::Mesh& mesh, std::uint64_t component, std::uint8_t* out) {
  for (draco::FaceIndex::ValueType f = 0; f < mesh.num_faces(); ++f) {
    const auto& face = mesh.face(draco::FaceIndex(f));
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t index = face[k].value();
      const std::size_t at = (static_cast<std::size_t>(f) * 3 + static_cast<std::size_t>(k)) * component;
      if (component == 1) {
        out[at] = static_cast<std::uint8_t>(index);
      } else if (component == 2) {
        const auto value = static_cast<std::uint16_t>(index);
        std::memcpy(out + at, &value, 2);
      } else {
        std::memcpy(out + at, &index, 4);
      }
    }
  }
}

class DracoDecoder {
 public:
  DracoDecoder(GltfAsset& asset, Diagnostics& diag) : asset_(asset), doc_(asset.document), diag_(diag) {}

  bool run(bool& decoded);

 private:
  bool decode_primitive(std::size_t mesh, std::size_t p);
  std::optional<std::span<const std::uint8_t>> compressed_bytes(const Json& extension, const std::string& pointer);
  bool plan(const Json& primitive, const Json& extension, const std::string& pointer,
            std::vector<Output>& outputs, std::uint64_t& total);
  bool check_header(std::span<const std::uint8_t> source, const std::string& pointer,
                    const std::vector<Output>& outputs);
  bool fill(const draco::Mesh& mesh, const Json& extension, const std::string& pointer,
            std::vector<Output>& outputs, std::vector<std::uint8_t>& bytes);

  GltfAsset& asset_;
  Json& doc_;
  Diagnostics& diag_;
  std::map<std::size_t, std::size_t> done_;  // Accessor -> the Draco buffer view that filled it.
  std::uint64_t buffer_total_ = 0;
  // Accessors a primitive without Draco reads: decoding must not replace what they hold.
  std::set<std::size_t> read_plain_;
};

std::optional<std::span<const std::uint8_t>> DracoDecoder::compressed_bytes(const Json& extension,
                                                                            const std::string& pointer) {
  const auto index = extension.contains("bufferView") ? as_uint(extension["bufferView"]) : std::nullopt;
  if (!index || !doc_.contains("bufferViews") || *index >= doc_["bufferViews"].size()) {
    diag_.error(codes::DRACO_INVALID, pointer + "/bufferView",
                "'bufferView' must name one of the document's buffer views, found " +
                    (extension.contains("bufferView") ? describe(extension["bufferView"]) : std::string("nothing")));
    return std::nullopt;
  }
  // validate_document checked the view against its buffer's byteLength; check it against the
  // bytes loaded too.
  const Json& view = doc_["bufferViews"][*index];
  const auto buffer = view["buffer"].get<std::size_t>();
  const std::uint64_t offset = view.contains("byteOffset") ? view["byteOffset"].get<std::uint64_t>() : 0;
  const std::uint64_t length = view["byteLength"].get<std::uint64_t>();
  if (buffer >= asset_.buffers.size() || offset + length > asset_.buffers[buffer].size()) {
    diag_.error(codes::DRACO_INVALID, json_pointer("/bufferViews", *index),
                "the buffer view lies outside its buffer's loaded bytes");
    return std::nullopt;
  }
  return std::span<const std::uint8_t>(asset_.buffers[buffer].data() + offset, length);
}

// Where each accessor's decoded values go in the new buffer, from the counts the document
// declares (validate_document capped them): the total is checked before any decoding.
bool DracoDecoder::plan(const Json& primitive, const Json& extension, const std::string& pointer,
                        std::vector<Output>& outputs, std::uint64_t& total) {
  if (!primitive.contains("indices")) {
    diag_.error(codes::DRACO_INVALID, pointer, "a Draco-compressed primitive needs 'indices' (the extension requires them)");
    return false;
  }
  const std::uint64_t mode = primitive.contains("mode") ? primitive["mode"].get<std::uint64_t>() : 4;
  if (mode != 4) {
    diag_.error(codes::DRACO_INVALID, pointer, "Draco decodes triangles (mode 4); the primitive has mode " + std::to_string(mode));
    return false;
  }
  const Json& attributes = extension.contains("attributes") ? extension["attributes"] : Json();
  if (!attributes.is_object()) {
    diag_.error(codes::DRACO_INVALID, pointer + "/attributes", "'attributes' must be an object of Draco attribute ids");
    return false;
  }
  auto add = [&](std::size_t accessor, bool vertex, const std::string& name = {}) {
    const Json& a = doc_["accessors"][accessor];
    const std::uint64_t element = element_bytes(a);
    const std::uint64_t stride = vertex ? round_up4(element) : element;
    const std::uint64_t count = a["count"].get<std::uint64_t>();
    outputs.push_back({accessor, nullptr, total, stride, stride * count, name});
    total = saturating_add(total, round_up4(stride * count));
    return element != 0;
  };
  if (!add(primitive["indices"].get<std::size_t>(), false)) {
    diag_.error(codes::DRACO_INVALID, pointer + "/indices", "Draco indices must be a SCALAR accessor");
    return false;
  }
  for (const auto& [name, id] : attributes.items()) {
    if (!as_uint(id) || !primitive["attributes"].contains(name)) {
      diag_.error(codes::DRACO_INVALID, pointer + "/attributes/" + name,
                  "'" + quote(name) + "' must be an attribute of the primitive with a Draco id, found " + describe(id));
      return false;
    }
    if (!add(primitive["attributes"][name].get<std::size_t>(), true, name)) {
      diag_.error(codes::DRACO_INVALID, pointer + "/attributes/" + name, "a Draco attribute must be a SCALAR or VEC2-4 accessor");
      return false;
    }
  }
  return true;
}

// The counts the stream declares, before libdraco allocates from them: a decoded mesh must match
// its accessors exactly (fill), so a stream declaring more faces or vertices than they do is
// refused here, and libdraco's corner table and point arrays stay within what the accessors (and
// so the limits validate_document applied to them) allow.
bool DracoDecoder::check_header(std::span<const std::uint8_t> source, const std::string& pointer,
                                const std::vector<Output>& outputs) {
  std::string error;
  const auto header = read_draco_header(source, error);
  if (!header) {
    diag_.error(codes::DRACO_INVALID, pointer, "the buffer view holds no Draco triangle mesh rdtf reads: " + error);
    return false;
  }
  const std::uint64_t indices = doc_["accessors"][outputs[0].accessor]["count"].get<std::uint64_t>();
  // Every attribute accessor must hold one value per decoded point; with none, the accessor limit.
  std::uint64_t points = asset_.limits.max_accessor_count;
  for (std::size_t k = 1; k < outputs.size(); ++k) {
    points = std::min(points, doc_["accessors"][outputs[k].accessor]["count"].get<std::uint64_t>());
  }
  const std::string method = header->edgebreaker ? "edgebreaker" : "sequential";
  const std::string stream = "the Draco stream (version " + std::to_string(header->major) + "." +
                             std::to_string(header->minor) + ", " + method + ") declares ";
  if (header->faces > asset_.limits.max_triangles) {
    diag_.error(codes::LIMIT_EXCEEDED, pointer, stream + std::to_string(header->faces) +
                " faces, over the limit of " + std::to_string(asset_.limits.max_triangles) + " (max_triangles)");
    return false;
  }
  if (header->faces * 3 != indices) {
    diag_.error(codes::DRACO_INVALID, pointer, stream + std::to_string(header->faces) + " faces (" +
                std::to_string(header->faces * 3) + " indices) but the indices accessor declares " +
                std::to_string(indices));
    return false;
  }
  // Sequential streams give the point count; edgebreaker gives the connectivity vertices, each
  // of which is at least one decoded point (attribute seams split a vertex into several). With no
  // attribute accessor, the accessor limit bounds the points.
  const bool exact = !header->edgebreaker && outputs.size() > 1;
  const bool over = exact ? header->vertices != points : header->vertices > points;
  if (over) {
    diag_.error(codes::DRACO_INVALID, pointer, stream + std::to_string(header->vertices) +
                (header->edgebreaker ? " vertices" : " points") + " but the attribute accessors declare " +
                std::to_string(points));
    return false;
  }
  return true;
}

bool DracoDecoder::fill(const draco::Mesh& mesh, const Json& extension, const std::string& pointer,
                        std::vector<Output>& outputs, std::vector<std::uint8_t>& bytes) {
  const Json& attributes = extension["attributes"];
  std::size_t k = 1;
  const auto count_mismatch = [&](const std::string& what, std::uint64_t decoded, std::uint64_t declared) {
    diag_.error(codes::DRACO_INVALID, pointer,
                "the Draco data decodes to " + std::to_string(decoded) + " " + what + " but accessor " +
                    "declares " + std::to_string(declared));
    return false;
  };
  const Json& indices = doc_["accessors"][outputs[0].accessor];
  const std::uint64_t index_count = indices["count"].get<std::uint64_t>();
  if (static_cast<std::uint64_t>(mesh.num_faces()) * 3 != index_count) {
    return count_mismatch("indices (3 per face)", static_cast<std::uint64_t>(mesh.num_faces()) * 3, index_count);
  }
  const std::uint64_t index_size = component_size(indices["componentType"].get<std::uint64_t>());
  if (index_size < 4 && mesh.num_points() > (1ull << (8 * index_size))) {
    diag_.error(codes::DRACO_INVALID, pointer, std::to_string(mesh.num_points()) +
                " decoded vertices cannot be indexed by the indices accessor's component type");
    return false;
  }
  write_indices(mesh, index_size, bytes.data() + outputs[0].offset);
  for (const auto& [name, id] : attributes.items()) {
    Output& output = outputs[k++];
    const draco::PointAttribute* attribute = mesh.GetAttributeByUniqueId(id.get<std::uint32_t>());
    Json& accessor = doc_["accessors"][output.accessor];
    if (attribute == nullptr) {
      diag_.error(codes::DRACO_INVALID, pointer + "/attributes/" + name,
                  "the Draco data has no attribute with id " + id.dump());
      return false;
    }
    if (mesh.num_points() != accessor["count"].get<std::uint64_t>()) {
      return count_mismatch("vertices for " + name, mesh.num_points(), accessor["count"].get<std::uint64_t>());
    }
    if (!write_attribute(mesh, *attribute, accessor, output.stride, bytes.data() + output.offset)) {
      diag_.error(codes::DRACO_INVALID, pointer + "/attributes/" + name,
                  "the Draco attribute " + id.dump() + " cannot be read as the accessor's type");
      return false;
    }
  }
  return true;
}

bool DracoDecoder::decode_primitive(std::size_t m, std::size_t p) {
  Json& primitive = doc_["meshes"][m]["primitives"][p];
  const std::string pointer =
      json_pointer(json_pointer("/meshes", m) + "/primitives", p) + "/extensions/" + kDracoExtension;
  const Json extension = primitive["extensions"][kDracoExtension];
  if (!extension.is_object()) {
    diag_.error(codes::DRACO_INVALID, pointer, "the extension must be an object, found " + describe(extension));
    return false;
  }
  const auto source = compressed_bytes(extension, pointer);
  if (!source) return false;
  const std::size_t draco_view = extension["bufferView"].get<std::size_t>();
  // An accessor another primitive decoded from the same Draco data is filled already.
  if (primitive.contains("indices")) {
    const auto found = done_.find(primitive["indices"].get<std::size_t>());
    if (found != done_.end() && found->second == draco_view) {
      drop_extension(primitive, kDracoExtension);
      return true;
    }
  }
  std::vector<Output> outputs;
  std::uint64_t total = 0;
  if (!plan(primitive, extension, pointer, outputs, total)) return false;
  for (const Output& output : outputs) {
    // An accessor with a bufferView is the uncompressed fallback for readers without Draco
    // (gltf-pipeline --draco.uncompressedFallback): the decoded data replaces it. One that
    // another primitive reads too cannot hold this one's decoded values (Draco orders each mesh's
    // vertices its own way), and such files are wrong already: gltf-pipeline 4.3's fallback
    // writes one mesh's Draco-ordered indices into an index list meshes share, then encodes the
    // next mesh from them (tests/data/encoded/make.sh: 3 kg of an 8 kg base went missing).
    if (done_.count(output.accessor) > 0 || read_plain_.count(output.accessor) > 0) {
      const bool fallback = doc_["accessors"][output.accessor].contains("bufferView");
      diag_.error(codes::DRACO_INVALID, json_pointer("/accessors", output.accessor),
                  "accessor " + std::to_string(output.accessor) + " (the " +
                      (output.name.empty() ? std::string("indices") : output.name) + " of mesh " + std::to_string(m) +
                      " " + describe(doc_["meshes"][m].value("name", Json(""))) +
                      ", Draco-compressed) is read by another primitive too: a Draco primitive's accessors must be "
                      "its own" +
                      (fallback ? std::string(". Its uncompressed fallback data cannot be trusted either: "
                                              "gltf-pipeline's --draco.uncompressedFallback encodes meshes that share "
                                              "an accessor wrongly. Compress without the fallback")
                                : std::string()));
      return false;
    }
  }
  if (saturating_add(buffer_total_, total) > asset_.limits.max_buffer_bytes) {
    diag_.error(codes::LIMIT_EXCEEDED, pointer,
                "decoded, the model's buffers would hold " + std::to_string(saturating_add(buffer_total_, total)) +
                    " bytes, over the limit of " + std::to_string(asset_.limits.max_buffer_bytes) + " (max_buffer_bytes)");
    return false;
  }
  if (!check_header(*source, pointer, outputs)) return false;
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(source->data()), source->size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok() || decoded.value() == nullptr) {
    diag_.error(codes::DRACO_INVALID, pointer,
                "libdraco could not decode the mesh: " + (decoded.ok() ? std::string("no mesh") : decoded.status().error_msg_string()));
    return false;
  }
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(total), 0);
  if (!fill(*decoded.value(), extension, pointer, outputs, bytes)) return false;

  // One new buffer per primitive, one view per accessor.
  const std::size_t buffer_index = asset_.buffers.size();
  doc_["buffers"].push_back({{"byteLength", bytes.size()}});
  asset_.buffers.push_back(std::move(bytes));
  buffer_total_ += total;
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    const Output& output = outputs[k];
    Json view = {{"buffer", buffer_index}, {"byteOffset", output.offset}, {"byteLength", output.length}};
    if (k > 0) view["byteStride"] = output.stride;
    view["target"] = k == 0 ? kElementArrayBuffer : kArrayBuffer;
    Json& accessor = doc_["accessors"][output.accessor];
    accessor["bufferView"] = doc_["bufferViews"].size();
    accessor.erase("byteOffset");
    doc_["bufferViews"].push_back(std::move(view));
    done_[output.accessor] = draco_view;
  }
  drop_extension(primitive, kDracoExtension);
  return true;
}

bool DracoDecoder::run(bool& decoded) {
  if (!doc_.contains("meshes")) return true;
  for (const Json& mesh : doc_["meshes"]) {
    for (const Json& primitive : mesh.value("primitives", Json::array())) {
      if (primitive.contains("extensions") && primitive["extensions"].is_object() &&
          primitive["extensions"].contains(kDracoExtension)) {
        continue;
      }
      if (primitive.contains("indices") && primitive["indices"].is_number_unsigned()) {
        read_plain_.insert(primitive["indices"].get<std::size_t>());
      }
      const Json attributes = primitive.value("attributes", Json::object());
      for (const auto& [name, accessor] : attributes.items()) {
        if (accessor.is_number_unsigned()) read_plain_.insert(accessor.get<std::size_t>());
      }
      for (const Json& target : primitive.value("targets", Json::array())) {
        for (const auto& [name, accessor] : target.items()) {
          if (accessor.is_number_unsigned()) read_plain_.insert(accessor.get<std::size_t>());
        }
      }
    }
  }
  for (const auto& buffer : doc_.value("buffers", Json::array())) {
    buffer_total_ = saturating_add(buffer_total_, buffer["byteLength"].get<std::uint64_t>());
  }
  std::size_t primitives = 0;
  for (std::size_t m = 0; m < doc_["meshes"].size(); ++m) {
    Json& list = doc_["meshes"][m]["primitives"];
    for (std::size_t p = 0; p < list.size(); ++p) {
      const Json& primitive = list[p];
      if (!primitive.contains("extensions") || !primitive["extensions"].is_object() ||
          !primitive["extensions"].contains(kDracoExtension)) {
        continue;
      }
      if (!decode_primitive(m, p)) return false;
      ++primitives;
    }
  }
  if (primitives > 0) {
    if (!doc_.contains("bufferViews")) doc_["bufferViews"] = Json::array();
    drop_extension_name(doc_, kDracoExtension);
    diag_.info(codes::COMPRESSION_DECODED, "/meshes",
               std::to_string(primitives) + " primitive(s) decoded from KHR_draco_mesh_compression; the "
               "output holds them uncompressed");
    decoded = true;
  }
  return true;
}

}  // namespace

bool decode_draco(GltfAsset& asset, bool& decoded, Diagnostics& diag) {
  return DracoDecoder(asset, diag).run(decoded);
}

}  // namespace rdtf::internal
