// The parts of a document rdtf does not read but writes out again: materials, textures, samplers,
// the asset's strings and every object's `extensions`. Each broken value here passed through into
// the output, which the Khronos validator then refused while rdtf said nothing and exited 0
// (s100err D1). Checked as the glTF 2.0 schema says, with the validator's codes.
#include <cmath>
#include <unordered_set>

#include "document_check.h"
#include "rdtf/diagnostic_codes.h"
#include "validate_util.h"

namespace rdtf::internal {

// A number in [low, high], when given.
void DocumentCheck::read_unit_number(const Json& object, const char* key, const std::string& pointer,
                                     double low, double high) {
  const Json* value = read_typed(object, key, pointer, false, &Json::is_number, "a number");
  if (value == nullptr) return;
  const double number = value->get<double>();
  if (!(number >= low && number <= high)) {
    diag_.error(codes::VALUE_NOT_IN_RANGE, json_pointer(pointer, key),
                describe(*value) + " is outside [" + format_number(low) + ", " +
                    (std::isinf(high) ? std::string("infinity") : format_number(high)) + "]");
  }
}

// `length` numbers, each in [0, 1] (a colour factor).
void DocumentCheck::read_factor(const Json& object, const char* key, const std::string& pointer,
                                std::size_t length) {
  const auto numbers = read_numbers(object, key, pointer, length);
  if (!numbers) return;
  for (std::size_t k = 0; k < numbers->size(); ++k) {
    if ((*numbers)[k] < 0 || (*numbers)[k] > 1) {
      diag_.error(codes::VALUE_NOT_IN_RANGE, json_pointer(json_pointer(pointer, key), k),
                  format_number((*numbers)[k]) + " is outside [0, 1]");
    }
  }
}

// A textureInfo: {index, texCoord} and, by kind, scale or strength.
void DocumentCheck::check_texture_info(const Json& object, const char* key, const std::string& pointer) {
  const Json* info = read_object(object, key, pointer);
  if (info == nullptr) return;
  const std::string here = json_pointer(pointer, key);
  read_ref(*info, "index", here, "textures", true);
  read_uint(*info, "texCoord", here);
  if (std::string_view(key) == "normalTexture") {
    read_typed(*info, "scale", here, false, &Json::is_number, "a number");
  }
  if (std::string_view(key) == "occlusionTexture") read_unit_number(*info, "strength", here, 0, 1);
}

void DocumentCheck::check_materials() {
  const auto& materials = entries_["materials"];
  for (std::size_t m = 0; m < materials.size(); ++m) {
    if (materials[m] == nullptr) continue;
    const Json& material = *materials[m];
    const std::string pointer = json_pointer("/materials", m);
    if (const Json* pbr = read_object(material, "pbrMetallicRoughness", pointer)) {
      const std::string here = json_pointer(pointer, "pbrMetallicRoughness");
      read_factor(*pbr, "baseColorFactor", here, 4);
      read_unit_number(*pbr, "metallicFactor", here, 0, 1);
      read_unit_number(*pbr, "roughnessFactor", here, 0, 1);
      check_texture_info(*pbr, "baseColorTexture", here);
      check_texture_info(*pbr, "metallicRoughnessTexture", here);
    }
    for (const char* texture : {"normalTexture", "occlusionTexture", "emissiveTexture"}) {
      check_texture_info(material, texture, pointer);
    }
    read_factor(material, "emissiveFactor", pointer, 3);
    if (const auto mode = read_string(material, "alphaMode", pointer)) {
      if (*mode != "OPAQUE" && *mode != "MASK" && *mode != "BLEND") {
        diag_.error(codes::VALUE_NOT_IN_LIST, json_pointer(pointer, "alphaMode"),
                    "'" + quote(*mode) + "' is not one of OPAQUE, MASK, BLEND");
      }
    }
    read_unit_number(material, "alphaCutoff", pointer, 0, std::numeric_limits<double>::infinity());
    read_bool(material, "doubleSided", pointer);
  }
}

void DocumentCheck::check_textures() {
  const auto& textures = entries_["textures"];
  for (std::size_t t = 0; t < textures.size(); ++t) {
    if (textures[t] == nullptr) continue;
    const std::string pointer = json_pointer("/textures", t);
    read_ref(*textures[t], "sampler", pointer, "samplers");
    read_ref(*textures[t], "source", pointer, "images");
  }
  const auto& samplers = entries_["samplers"];
  for (std::size_t s = 0; s < samplers.size(); ++s) {
    if (samplers[s] == nullptr) continue;
    const std::string pointer = json_pointer("/samplers", s);
    const auto one_of = [&](const char* key, std::initializer_list<std::uint64_t> allowed) {
      const auto value = read_uint(*samplers[s], key, pointer);
      if (!value || std::find(allowed.begin(), allowed.end(), *value) != allowed.end()) return;
      std::string list;
      for (const std::uint64_t a : allowed) list += (list.empty() ? "" : ", ") + std::to_string(a);
      diag_.error(codes::VALUE_NOT_IN_LIST, json_pointer(pointer, key),
                  std::to_string(*value) + " is not one of " + list);
    };
    one_of("magFilter", {9728, 9729});
    one_of("minFilter", {9728, 9729, 9984, 9985, 9986, 9987});
    one_of("wrapS", {33071, 33648, 10497});
    one_of("wrapT", {33071, 33648, 10497});
  }
}

// A primitive's material samples each of its textures with the TEXCOORD_n its texCoord names (0 by
// default), which the primitive must have: a Blender material whose second UV map was deleted
// went through into an output the Khronos validator refused (s100rev R2).
void DocumentCheck::check_material_texcoords() {
  const auto& materials = entries_["materials"];
  const auto& meshes = entries_["meshes"];
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    if (meshes[m] == nullptr || !meshes[m]->contains("primitives") || !(*meshes[m])["primitives"].is_array()) continue;
    const Json& primitives = (*meshes[m])["primitives"];
    for (std::size_t p = 0; p < primitives.size(); ++p) {
      const Json& primitive = primitives[p];
      if (!primitive.is_object() || !primitive.contains("material") || !primitive["material"].is_number_integer()) continue;
      const std::int64_t material_index = primitive["material"].get<std::int64_t>();
      if (material_index < 0 || static_cast<std::uint64_t>(material_index) >= materials.size()) continue;
      const std::size_t index = static_cast<std::size_t>(material_index);
      if (materials[index] == nullptr) continue;
      if (!primitive.contains("attributes") || !primitive["attributes"].is_object()) continue;
      const Json& attributes = primitive["attributes"];
      const Json& material = *materials[index];
      const auto need = [&](const Json& owner, const char* key, const std::string& owner_pointer) {
        if (!owner.contains(key) || !owner[key].is_object()) return;
        const Json& info = owner[key];
        const Json texcoord = info.value("texCoord", Json(0));
        if (!texcoord.is_number_integer() || texcoord.get<std::int64_t>() < 0) return;  // said by check_texture_info
        const std::string attribute = "TEXCOORD_" + std::to_string(texcoord.get<std::int64_t>());
        if (attributes.contains(attribute)) return;
        diag_.error(codes::MESH_PRIMITIVE_TOO_FEW_TEXCOORDS,
                    json_pointer(json_pointer(json_pointer(json_pointer("/meshes", m), "primitives"), p), "material"),
                    "material " + std::to_string(index) + "'s texture " + json_pointer(owner_pointer, key) +
                        " is sampled with " + attribute +
                        ", which this primitive does not have: add that UV map to the mesh, or point texCoord at "
                        "one it has");
      };
      const std::string pointer = json_pointer("/materials", index);
      if (material.contains("pbrMetallicRoughness") && material["pbrMetallicRoughness"].is_object()) {
        const Json& pbr = material["pbrMetallicRoughness"];
        need(pbr, "baseColorTexture", json_pointer(pointer, "pbrMetallicRoughness"));
        need(pbr, "metallicRoughnessTexture", json_pointer(pointer, "pbrMetallicRoughness"));
      }
      for (const char* texture : {"normalTexture", "occlusionTexture", "emissiveTexture"}) need(material, texture, pointer);
    }
  }
}

// Every glTF object's `extensions` is an object. Only the properties glTF defines are glTF
// objects: an exporter's own property (`"myToolData": {"extensions": [...]}`) is not, nor is
// anything under `extras` or inside an extension (s100rev D1: such a file, valid to the Khronos
// validator, was refused).
void DocumentCheck::check_extension_objects(const Json& value, const std::string& pointer, int depth) {
  static const std::unordered_set<std::string> kGltfObjects{
      "asset", "accessors", "animations", "buffers", "bufferViews", "cameras", "images", "materials", "meshes",
      "nodes", "samplers", "scenes", "skins", "textures", "sparse", "indices", "values", "channels", "target",
      "orthographic", "perspective", "pbrMetallicRoughness", "baseColorTexture", "metallicRoughnessTexture",
      "normalTexture", "occlusionTexture", "emissiveTexture", "primitives"};
  if (depth > 8) return;  // glTF objects nest 5 deep (a material's texture info); deeper is data
  if (value.is_array()) {
    for (std::size_t k = 0; k < value.size(); ++k) {
      if (value[k].is_object()) check_extension_objects(value[k], json_pointer(pointer, k), depth + 1);
    }
    return;
  }
  if (!value.is_object()) return;
  for (const auto& [key, child] : value.items()) {
    if (key == "extensions") {
      if (!child.is_object()) {
        diag_.error(codes::TYPE_MISMATCH, json_pointer(pointer, key),
                    "must be an object, found " + std::string(child.type_name()) +
                        (child.is_null() ? std::string() : " " + describe(child)));
        continue;
      }
      // glTF 2.0: every extension used is listed in extensionsUsed. One that is not passed into
      // the output, which the Khronos validator refuses (UNDECLARED_EXTENSION).
      for (const auto& [name, unused] : child.items()) {
        // As the validator: where an undeclared extension is does not matter, only that it is undeclared.
        if (used_extensions_.count(name) != 0) {
          check_extension_place(name, pointer);
          continue;
        }
        diag_.error(codes::UNDECLARED_EXTENSION, json_pointer(json_pointer(pointer, key), name),
                    "uses the extension '" + quote(name) +
                        "', which extensionsUsed does not list (glTF 2.0 requires every extension used to be "
                        "listed there): list it in extensionsUsed, or remove it");
      }
      continue;
    }
    if (kGltfObjects.count(key) != 0 && (child.is_object() || child.is_array())) {
      check_extension_objects(child, json_pointer(pointer, key), depth + 1);
    }
  }
}

}  // namespace rdtf::internal
