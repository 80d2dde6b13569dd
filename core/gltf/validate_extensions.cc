// Extensions rdtf does not read but writes out again: KHR_lights_punctual (lights on nodes; Blender
// exports them, "Punctual Lights") and KHR_materials_variants (a primitive's material per variant;
// Blender exports them too), and where each extension the Khronos validator knows may be. A broken
// light, a node naming a light that is not there, a mapping naming a missing variant or an
// extension in the wrong place passed into the output, which the validator then refused. Checked
// as the validator does (2.0.0-dev.3.10: the extensions' schemas, the spot's cone angles in order,
// each variant once per primitive), with its codes and pointers; what it only warns of (an unknown
// light type, a range on a directional light) is left to it.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <set>
#include <string_view>
#include <vector>

#include "document_check.h"
#include "rdtf/diagnostic_codes.h"
#include "validate_util.h"

namespace rdtf::internal {
namespace {

constexpr const char* kLights = "KHR_lights_punctual";
constexpr const char* kVariants = "KHR_materials_variants";

const Json* extension_of(const Json& object, const char* name) {
  const auto extensions = object.find("extensions");
  if (extensions == object.end() || !extensions->is_object()) return nullptr;
  const auto extension = extensions->find(name);
  return extension == extensions->end() ? nullptr : &*extension;
}

// The kind of glTF object at `pointer`, as far as where an extension may be goes.
enum class Place { kRoot, kNode, kMesh, kPrimitive, kMaterial, kTextureInfo, kTexture, kChannelTarget, kOther };

Place place_of(std::string_view pointer) {
  std::vector<std::string_view> parts;
  while (!pointer.empty()) {
    pointer.remove_prefix(1);  // '/'
    const std::size_t end = pointer.find('/');
    parts.push_back(pointer.substr(0, end));
    pointer = end == std::string_view::npos ? std::string_view() : pointer.substr(end);
  }
  const auto is = [&](std::size_t k, std::string_view text) { return k < parts.size() && parts[k] == text; };
  const auto texture_info = [](std::string_view key) {
    return key == "baseColorTexture" || key == "metallicRoughnessTexture" || key == "normalTexture" ||
           key == "occlusionTexture" || key == "emissiveTexture";
  };
  switch (parts.size()) {
    case 0:
      return Place::kRoot;
    case 2:
      if (is(0, "nodes")) return Place::kNode;
      if (is(0, "meshes")) return Place::kMesh;
      if (is(0, "materials")) return Place::kMaterial;
      if (is(0, "textures")) return Place::kTexture;
      return Place::kOther;
    case 3:
      return is(0, "materials") && texture_info(parts[2]) ? Place::kTextureInfo : Place::kOther;
    case 4:
      if (is(0, "meshes") && is(2, "primitives")) return Place::kPrimitive;
      if (is(0, "materials") && is(2, "pbrMetallicRoughness") && texture_info(parts[3])) return Place::kTextureInfo;
      return Place::kOther;
    case 5:
      return is(0, "animations") && is(2, "channels") && is(4, "target") ? Place::kChannelTarget : Place::kOther;
    default:
      return Place::kOther;
  }
}

// The places the validator allows an extension it knows; nullopt for one it does not know.
std::optional<std::vector<Place>> places_of(std::string_view name) {
  if (name == kLights) return std::vector{Place::kRoot, Place::kNode};
  if (name == kVariants) return std::vector{Place::kRoot, Place::kPrimitive};
  if (name == "EXT_texture_webp") return std::vector{Place::kTexture};
  if (name == "KHR_texture_transform") return std::vector{Place::kTextureInfo};
  if (name == "KHR_animation_pointer") return std::vector{Place::kChannelTarget};
  if (name == "KHR_mesh_quantization") return std::vector<Place>{};  // Declared, never an object.
  for (const char* material :
       {"KHR_materials_anisotropy", "KHR_materials_clearcoat", "KHR_materials_dispersion",
        "KHR_materials_emissive_strength", "KHR_materials_ior", "KHR_materials_iridescence",
        "KHR_materials_pbrSpecularGlossiness", "KHR_materials_sheen", "KHR_materials_specular",
        "KHR_materials_transmission", "KHR_materials_unlit", "KHR_materials_volume"}) {
    if (name == material) return std::vector{Place::kMaterial};
  }
  return std::nullopt;
}

// "none", or "3 (0..2)": what a reference may name.
std::string count_and_range(std::size_t count) {
  return count == 0 ? std::string("none") : std::to_string(count) + " (0.." + std::to_string(count - 1) + ")";
}

}  // namespace

// An extension's object (the document's, a node's, a primitive's), which must be one and holds
// `required`: as the validator, a value of another type is said twice, as a mismatch and as the
// property it lacks.
bool DocumentCheck::extension_is_object(const Json& extension, const std::string& pointer, const char* required) {
  if (extension.is_object()) return true;
  diag_.error(codes::TYPE_MISMATCH, pointer, "must be an object, found " + describe(extension));
  diag_.error(codes::UNDEFINED_PROPERTY, pointer, std::string("property '") + required + "' must be defined");
  return false;
}

// A required, non-empty array of objects (lights, variants, mappings): null when it is not one. As
// the validator reads it, an array with an element of another type is no array of those objects.
const Json* DocumentCheck::read_objects(const Json& object, const char* key, const std::string& pointer) {
  const Json* array = read_array(object, key, pointer, true);
  if (array == nullptr) return nullptr;
  const auto other = std::find_if(array->begin(), array->end(), [](const Json& j) { return !j.is_object(); });
  if (other == array->end()) return array;
  diag_.error(codes::ARRAY_TYPE_MISMATCH, json_pointer(pointer, key),
              "element " + std::to_string(other - array->begin()) + " is " + describe(*other) + ", not an object");
  return nullptr;
}

// A number within bounds, each inclusive or not; returns it (or `fallback` when absent), or
// nothing when it is not a number or out of range.
std::optional<double> DocumentCheck::read_bounded(const Json& object, const char* key, const std::string& pointer,
                                                  double fallback, Bound low, Bound high) {
  const Json* value = read_typed(object, key, pointer, false, &Json::is_number, "a number");
  if (value == nullptr) return object.contains(key) ? std::nullopt : std::optional<double>(fallback);
  const double number = value->get<double>();
  const bool above = low.inclusive ? number >= low.value : number > low.value;
  const bool below = high.inclusive ? number <= high.value : number < high.value;
  if (above && below) return number;
  diag_.error(codes::VALUE_NOT_IN_RANGE, json_pointer(pointer, key),
              describe(*value) + " is outside " + (low.inclusive ? "[" : "(") + format_number(low.value) + ", " +
                  (std::isinf(high.value) ? std::string("infinity") : format_number(high.value)) +
                  (high.inclusive ? "]" : ")"));
  return std::nullopt;
}

void DocumentCheck::check_lights() {
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  constexpr double kRightAngle = std::numbers::pi / 2;
  // The document's lights: how many a node may name, or none when the root extension is missing.
  std::optional<std::size_t> light_count;
  const std::string root = json_pointer("/extensions", kLights);
  if (const Json* extension = extension_of(doc_, kLights)) {
    light_count = 0;
    const Json* lights =
        extension_is_object(*extension, root, "lights") ? read_objects(*extension, "lights", root) : nullptr;
    if (lights != nullptr) {
      light_count = lights->size();
      const std::string here = json_pointer(root, "lights");
      for (std::size_t k = 0; k < lights->size(); ++k) {
        const Json& light = (*lights)[k];
        const std::string at = json_pointer(here, k);
        read_factor(light, "color", at, 3);
        read_bounded(light, "intensity", at, 1.0, {0.0, true}, {kInfinity, true});
        read_bounded(light, "range", at, kInfinity, {0.0, false}, {kInfinity, true});
        read_string(light, "name", at);
        const auto type = read_string(light, "type", at, true);
        if (type != "spot") continue;
        const Json* spot = read_object(light, "spot", at, true);
        if (spot == nullptr) continue;
        const std::string spot_at = json_pointer(at, "spot");
        const auto inner = read_bounded(*spot, "innerConeAngle", spot_at, 0.0, {0.0, true}, {kRightAngle, false});
        const auto outer =
            read_bounded(*spot, "outerConeAngle", spot_at, std::numbers::pi / 4, {0.0, false}, {kRightAngle, true});
        if (inner && outer && *outer <= *inner) {
          diag_.error(codes::KHR_LIGHTS_PUNCTUAL_LIGHT_SPOT_ANGLES, json_pointer(spot_at, "outerConeAngle"),
                      "outerConeAngle (" + format_number(*outer) + ") is less than or equal to innerConeAngle (" +
                          format_number(*inner) + "): the cone's edge must lie outside its core");
        }
      }
    }
  }
  const auto& nodes = entries_["nodes"];
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Json* extension = nodes[i] == nullptr ? nullptr : extension_of(*nodes[i], kLights);
    if (extension == nullptr) continue;
    const std::string at = json_pointer(json_pointer("/nodes", i) + "/extensions", kLights);
    if (!extension_is_object(*extension, at, "light")) continue;
    const Json* light = find(*extension, "light", at, true);
    if (light == nullptr) continue;
    const auto index = uint_value(*light, json_pointer(at, "light"));
    if (!index) continue;
    if (!light_count) {
      diag_.error(codes::UNSATISFIED_DEPENDENCY, at,
                  "names light " + std::to_string(*index) +
                      ", but the document has no lights (extensions.KHR_lights_punctual.lights): add the light, "
                      "or remove the node's light");
    } else if (*index >= *light_count) {
      diag_.error(codes::UNRESOLVED_REFERENCE, json_pointer(at, "light"),
                  "there is no light " + std::to_string(*index) + ": the document has " +
                      count_and_range(*light_count));
    }
  }
}

// An extension the validator knows, on an object where it may not be (KHR_lights_punctual on a
// mesh): UNEXPECTED_EXTENSION_OBJECT. Called for each extension of each glTF object.
void DocumentCheck::check_extension_place(const std::string& name, const std::string& object_pointer) {
  const auto places = places_of(name);
  if (!places) return;
  const Place place = place_of(object_pointer);
  if (std::find(places->begin(), places->end(), place) != places->end()) return;
  diag_.error(codes::UNEXPECTED_EXTENSION_OBJECT, json_pointer(object_pointer + "/extensions", name),
              "'" + quote(name) + "' may not be on " +
                  (object_pointer.empty() ? std::string("the document") : "'" + object_pointer + "'") +
                  " (glTF objects it extends: " +
                  (name == kLights                          ? "the document and nodes"
                   : name == kVariants                      ? "the document and mesh primitives"
                   : name == "EXT_texture_webp"             ? "textures"
                   : name == "KHR_texture_transform"        ? "texture infos"
                   : name == "KHR_animation_pointer"        ? "animation channel targets"
                   : name == "KHR_mesh_quantization"        ? "none: it is only declared"
                                                            : "materials") +
                  "): move it there, or remove it");
}

void DocumentCheck::check_variants() {
  // The document's variants: how many a mapping may name, or none when the root extension is
  // missing.
  std::optional<std::size_t> variant_count;
  const std::string root = json_pointer("/extensions", kVariants);
  if (const Json* extension = extension_of(doc_, kVariants)) {
    variant_count = 0;
    const Json* variants =
        extension_is_object(*extension, root, "variants") ? read_objects(*extension, "variants", root) : nullptr;
    if (variants != nullptr) {
      variant_count = variants->size();
      const std::string here = json_pointer(root, "variants");
      for (std::size_t k = 0; k < variants->size(); ++k) {
        read_string((*variants)[k], "name", json_pointer(here, k), true);
      }
    }
  }
  const auto& meshes = entries_["meshes"];
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    if (meshes[m] == nullptr) continue;
    const auto primitives = meshes[m]->find("primitives");
    if (primitives == meshes[m]->end() || !primitives->is_array()) continue;
    for (std::size_t p = 0; p < primitives->size(); ++p) {
      const Json& primitive = (*primitives)[p];
      const Json* extension = primitive.is_object() ? extension_of(primitive, kVariants) : nullptr;
      if (extension == nullptr) continue;
      const std::string at =
          json_pointer(json_pointer(json_pointer("/meshes", m) + "/primitives", p) + "/extensions", kVariants);
      const Json* mappings =
          extension_is_object(*extension, at, "mappings") ? read_objects(*extension, "mappings", at) : nullptr;
      if (mappings == nullptr) continue;
      const std::string here = json_pointer(at, "mappings");
      std::set<std::uint64_t> used;  // Each variant names one material of the primitive.
      for (std::size_t k = 0; k < mappings->size(); ++k) {
        const Json& mapping = (*mappings)[k];
        const std::string mapping_at = json_pointer(here, k);
        const Json* variants = read_array(mapping, "variants", mapping_at, true);
        read_ref(mapping, "material", mapping_at, "materials", true);
        read_string(mapping, "name", mapping_at);
        if (!variant_count) {
          diag_.error(codes::UNSATISFIED_DEPENDENCY, mapping_at,
                      "names variants, but the document has none (extensions.KHR_materials_variants.variants): "
                      "add them, or remove the primitive's mappings");
          continue;
        }
        std::set<std::uint64_t> in_mapping;
        for (std::size_t j = 0; variants != nullptr && j < variants->size(); ++j) {
          const std::string variant_at = json_pointer(json_pointer(mapping_at, "variants"), j);
          const auto index = uint_value((*variants)[j], variant_at);
          if (!index) continue;
          if (!in_mapping.insert(*index).second) {
            diag_.error(codes::DUPLICATE_ELEMENTS, variant_at, std::to_string(*index) + " is listed twice");
          }
          if (!used.insert(*index).second) {
            diag_.error(codes::KHR_MATERIALS_VARIANTS_NON_UNIQUE_VARIANT, variant_at,
                        "variant " + std::to_string(*index) +
                            " is mapped more than once for this primitive: each variant gives it one material");
          }
          if (*index >= *variant_count) {
            diag_.error(codes::UNRESOLVED_REFERENCE, variant_at,
                        "there is no variant " + std::to_string(*index) + ": the document has " +
                            count_and_range(*variant_count));
          }
        }
      }
    }
  }
}

}  // namespace rdtf::internal
