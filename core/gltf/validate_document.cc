// validate_document (rdtf/validate.h): the order of the checks, the type-checked reading of
// properties they all use, and the checks of the document as a whole. See document_check.h.
#include <algorithm>
#include <cctype>
#include <map>
#include <cmath>
#include <unordered_set>

#include "document_check.h"
#include "rdtf/validate.h"
#include "validate_util.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace internal {
namespace {

constexpr double kFloatMax = 3.4028234663852886e38;  // glTF numbers are single precision.

// Extensions a model may require: those that change nothing the converter reads (geometry, node
// tree), and those it decodes (Draco, meshopt: decode.h) or reads (instancing). Any other required
// extension may store geometry where plain accessors do not: such a model is refused rather than
// misread.
bool extension_is_harmless(const std::string& name) {
  for (const char* prefix : {"KHR_materials_", "KHR_texture_", "EXT_texture_", "KHR_lights_"}) {
    if (name.rfind(prefix, 0) == 0) return true;
  }
  return name == "KHR_mesh_quantization" || name == "KHR_draco_mesh_compression" ||
         name == "EXT_meshopt_compression" || name == "EXT_mesh_gpu_instancing" ||
         name == "KHR_animation_pointer" ||
         name == "KHR_node_visibility" || name == "KHR_xmp_json_ld";
}

}  // namespace

void DocumentCheck::run() {
  if (!doc_.is_object()) {
    diag_.error(codes::TYPE_MISMATCH, "",
                "the glTF JSON must be an object, found " + std::string(doc_.type_name()));
    return;
  }
  check_asset();
  check_extensions();
  for (const char* key : {"buffers", "bufferViews", "accessors", "meshes", "nodes", "scenes", "skins",
                          "cameras", "materials", "images", "animations", "textures", "samplers"}) {
    entries_[key] = top_level(key);
  }
  check_extension_objects(doc_, "", 0);
  // Each step uses the facts of those before it.
  check_buffers();
  check_buffer_views();
  check_accessors();
  check_meshes();
  check_nodes();
  check_node_graph();
  check_skins();
  check_scenes();
  check_images_and_animations();
  check_usages();
  check_lights();
  check_variants();
  check_materials();
  check_textures();
  check_material_texcoords();
  check_triangle_limit();
}

// ---- Reading properties ------------------------------------------------------------------------

// The elements of a top-level array, null for those that are not objects.
std::vector<const Json*> DocumentCheck::top_level(const char* key) {
  std::vector<const Json*> elements;
  const Json* array = read_array(doc_, key, "");
  if (array == nullptr) return elements;
  for (std::size_t i = 0; i < array->size(); ++i) {
    elements.push_back(object_at(*array, i, json_pointer("", key)));
    // Every glTF object's name is a string: a number there passed through into our output, which
    // the Khronos validator then refused.
    if (elements.back() != nullptr) read_string(*elements.back(), "name", json_pointer(json_pointer("", key), i));
  }
  return elements;
}

const Json* DocumentCheck::object_at(const Json& array, std::size_t i, const std::string& pointer) {
  if (array[i].is_object()) return &array[i];
  diag_.error(
      codes::TYPE_MISMATCH, json_pointer(pointer, i),
      "must be an object, found " + std::string(array[i].type_name()) +
          (array[i].is_null() ? std::string() : " " + describe(array[i])));
  return nullptr;
}

const Json* DocumentCheck::find(const Json& object, const char* key, const std::string& pointer,
                                bool required) {
  const auto it = object.find(key);
  if (it != object.end()) return &*it;
  if (required) {
    diag_.error(codes::UNDEFINED_PROPERTY, pointer,
                std::string("property '") + key + "' must be defined");
  }
  return nullptr;
}

const Json* DocumentCheck::read_typed(const Json& object, const char* key,
                                      const std::string& pointer, bool required,
                                      bool (Json::*is_type)() const noexcept, const char* type) {
  const Json* value = find(object, key, pointer, required);
  if (value == nullptr || ((*value).*is_type)()) return value;
  diag_.error(
      codes::TYPE_MISMATCH, json_pointer(pointer, key),
      std::string("must be ") + type + ", found " + value->type_name() +
          (value->is_null() ? std::string() : " " + describe(*value)));
  return nullptr;
}

// An array property; an empty one is reported (glTF arrays have at least one element).
const Json* DocumentCheck::read_array(const Json& object, const char* key,
                                      const std::string& pointer, bool required) {
  const Json* array = read_typed(object, key, pointer, required, &Json::is_array, "an array");
  if (array == nullptr || !array->empty()) return array;
  // Named by the object that holds it (a node's name) and, for children, by the likely cause.
  const bool named = object.contains("name") && object["name"].is_string();
  const bool children = std::string_view(key) == "children";
  diag_.error(codes::EMPTY_ENTITY, json_pointer(pointer, key),
              (named ? "'" + quote(object["name"].get<std::string>()) + "': '" : std::string("'")) + key +
                  "' is an empty array, which glTF does not allow (an array holds at least one element); leave it out" +
                  (children ? std::string(". A tool that removed this node's children leaves it so: gltf-pipeline "
                                          "removes nodes nothing refers to (KHR_physics_rigid_bodies frames among "
                                          "them) unless given --keepUnusedElements")
                            : std::string()));
  return nullptr;
}

const Json* DocumentCheck::read_object(const Json& object, const char* key,
                                       const std::string& pointer, bool required) {
  return read_typed(object, key, pointer, required, &Json::is_object, "an object");
}

std::optional<std::string> DocumentCheck::read_string(const Json& object, const char* key,
                                                      const std::string& pointer, bool required) {
  const Json* value = read_typed(object, key, pointer, required, &Json::is_string, "a string");
  return value == nullptr ? std::nullopt : std::optional(value->get<std::string>());
}

std::optional<bool> DocumentCheck::read_bool(const Json& object, const char* key,
                                             const std::string& pointer) {
  const Json* value = read_typed(object, key, pointer, false, &Json::is_boolean, "true or false");
  return value == nullptr ? std::nullopt : std::optional(value->get<bool>());
}

std::optional<std::uint64_t> DocumentCheck::uint_value(const Json& value,
                                                       const std::string& pointer) {
  if (auto number = as_uint(value)) return number;
  if (value.is_number_integer()) {  // Negative.
    diag_.error(codes::VALUE_NOT_IN_RANGE, pointer,
                "must be a non-negative integer, found " + describe(value));
  } else if (value.is_number_float() && std::isfinite(value.get<double>()) && value.get<double>() >= 0 &&
             std::floor(value.get<double>()) == value.get<double>()) {  // 2^64 and beyond: whole, too large
    diag_.error(codes::VALUE_NOT_IN_RANGE, pointer, describe(value) + " is too large for an index or a count");
  } else {
    diag_.error(
        codes::TYPE_MISMATCH, pointer,
        "must be an integer, found " + std::string(value.type_name()) + " " + describe(value));
  }
  return std::nullopt;
}

std::optional<std::uint64_t> DocumentCheck::read_uint(const Json& object, const char* key,
                                                      const std::string& pointer, bool required,
                                                      std::uint64_t minimum) {
  const Json* value = find(object, key, pointer, required);
  if (value == nullptr) return std::nullopt;
  const auto number = uint_value(*value, json_pointer(pointer, key));
  if (!number || *number >= minimum) return number;
  diag_.error(codes::VALUE_NOT_IN_RANGE, json_pointer(pointer, key),
              "is " + std::to_string(*number) + "; it must be at least " + std::to_string(minimum));
  return std::nullopt;
}

// An index into the top-level array `array`; kNone when it is wrong (reported).
std::size_t DocumentCheck::reference(const Json& value, const std::string& pointer,
                                     const char* array) {
  const auto index = uint_value(value, pointer);
  if (!index) return kNone;
  const std::size_t count = entries_[array].size();
  if (*index < count) return static_cast<std::size_t>(*index);
  diag_.error(codes::UNRESOLVED_REFERENCE, pointer,
              "there is no " + std::string(array) + "[" + std::to_string(*index) +
                  "]: the file has " +
                  (count == 0 ? std::string("none")
                              : std::to_string(count) + " (0.." + std::to_string(count - 1) + ")"));
  return kNone;
}

std::size_t DocumentCheck::read_ref(const Json& object, const char* key, const std::string& pointer,
                                    const char* array, bool required) {
  const Json* value = find(object, key, pointer, required);
  return value == nullptr ? kNone : reference(*value, json_pointer(pointer, key), array);
}

// An array of distinct indices into a top-level array: the resolved ones, in order.
std::vector<std::size_t> DocumentCheck::read_refs(const Json& object, const char* key,
                                                  const std::string& pointer, const char* array,
                                                  bool required) {
  std::vector<std::size_t> result;
  const Json* values = read_array(object, key, pointer, required);
  if (values == nullptr) return result;
  const std::string here = json_pointer(pointer, key);
  std::unordered_set<std::size_t> seen;
  for (std::size_t k = 0; k < values->size(); ++k) {
    const std::size_t index = reference((*values)[k], json_pointer(here, k), array);
    if (index == kNone) continue;
    if (!seen.insert(index).second) {
      diag_.error(codes::DUPLICATE_ELEMENTS, json_pointer(here, k),
                  std::to_string(index) + " is listed twice");
      continue;
    }
    result.push_back(index);
  }
  return result;
}

// Finite single-precision numbers, as many as `length` says (0: any number of them).
std::optional<std::vector<double>> DocumentCheck::read_numbers(const Json& object, const char* key,
                                                               const std::string& pointer,
                                                               std::size_t length) {
  const Json* array = read_typed(object, key, pointer, false, &Json::is_array, "an array");
  if (array == nullptr) return std::nullopt;
  const std::string here = json_pointer(pointer, key);
  if (length != 0 && array->size() != length) {
    diag_.error(codes::ARRAY_LENGTH_NOT_IN_LIST, here,
                "has " + std::to_string(array->size()) + " elements; it must have " +
                    std::to_string(length));
    return std::nullopt;
  }
  std::vector<double> numbers;
  for (std::size_t k = 0; k < array->size(); ++k) {
    const Json& value = (*array)[k];
    if (!value.is_number()) {
      diag_.error(codes::ARRAY_TYPE_MISMATCH, here,
                  "element " + std::to_string(k) + " is " + describe(value) + ", not a number");
      return std::nullopt;
    }
    const double number = value.get<double>();
    if (!std::isfinite(number) || std::abs(number) > kFloatMax) {
      diag_.error(codes::VALUE_NOT_IN_RANGE, json_pointer(here, k),
                  describe(value) + " is beyond the range of a single-precision float");
      return std::nullopt;
    }
    numbers.push_back(number);
  }
  return numbers;
}

// ---- The document as a whole -------------------------------------------------------------------

// "2.0" -> {2, 0}; PATTERN_MISMATCH when it is not MAJOR.MINOR.
std::optional<std::pair<int, int>> DocumentCheck::read_version(const Json& asset, const char* key,
                                                               bool required) {
  const auto text = read_string(asset, key, "/asset", required);
  if (!text) return std::nullopt;
  const auto dot = text->find('.');
  const auto digits = [](const std::string& s) {
    return !s.empty() && s.size() <= 6 && s.find_first_not_of("0123456789") == std::string::npos;
  };
  if (dot == std::string::npos || !digits(text->substr(0, dot)) || !digits(text->substr(dot + 1))) {
    diag_.error(codes::PATTERN_MISMATCH, std::string("/asset/") + key,
                "'" + quote(*text) + "' is not a version of the form MAJOR.MINOR, such as \"2.0\"");
    return std::nullopt;
  }
  return std::pair{std::stoi(text->substr(0, dot)), std::stoi(text->substr(dot + 1))};
}

void DocumentCheck::check_asset() {
  const Json* asset = read_object(doc_, "asset", "", true);
  if (asset == nullptr) return;
  for (const char* key : {"generator", "copyright"}) read_string(*asset, key, "/asset");
  const auto version = read_version(*asset, "version", true);
  if (version && version->first != 2) {
    diag_.error(
        codes::UNKNOWN_ASSET_MAJOR_VERSION, "/asset/version",
        "glTF " + std::to_string(version->first) + " is not supported; the model must be glTF 2.x");
  } else if (version && version->second != 0) {
    diag_.warning(codes::UNKNOWN_ASSET_MINOR_VERSION, "/asset/version",
                  "glTF 2." + std::to_string(version->second) + " is newer than 2.0; read as 2.0");
  }
  const auto minimum = read_version(*asset, "minVersion", false);
  if (version && minimum && *minimum > *version) {
    diag_.error(codes::ASSET_MIN_VERSION_GREATER_THAN_VERSION, "/asset/minVersion",
                "minVersion is greater than version " + std::to_string(version->first) + "." +
                    std::to_string(version->second));
  }
}

void DocumentCheck::check_extensions() {
  for (const std::string key : {"extensionsUsed", "extensionsRequired"}) {
    const Json* names = read_array(doc_, key.c_str(), "");
    std::unordered_set<std::string> seen;
    for (std::size_t k = 0; names != nullptr && k < names->size(); ++k) {
      const std::string pointer = json_pointer(json_pointer("", key), k);
      const Json& name = (*names)[k];
      if (key == "extensionsUsed" && name.is_string()) used_extensions_.insert(name.get<std::string>());
      if (!name.is_string()) {
        diag_.error(codes::TYPE_MISMATCH, pointer,
                    "an extension name must be a string, found " + describe(name));
      } else if (!seen.insert(name.get<std::string>()).second) {
        diag_.error(codes::DUPLICATE_ELEMENTS, pointer,
                    "'" + quote(name.get<std::string>()) + "' is listed twice; list each extension once");
      } else if (key == "extensionsUsed" && name == "KHR_mesh_quantization") {
        quantization_ = true;
      } else if (key == "extensionsRequired" && !extension_is_harmless(name)) {
        diag_.error(codes::UNSUPPORTED_EXTENSION, pointer,
                    "the model requires " + quote(name.get<std::string>()) +
                        ", which rdtf cannot read; export the model without it");
      }
    }
  }
  // KHR_mesh_quantization cannot be optional (the Khronos validator's NON_REQUIRED_EXTENSION): a
  // reader without it would take the integer positions for floats. rdtf keeps it in its output.
  // Read again without a word: the loop above reported an empty or mistyped list (s80valid D9: an
  // empty extensionsUsed was an EMPTY_ENTITY three times).
  const auto list = [&](const char* key) -> const Json* {
    const auto it = doc_.find(key);
    return it != doc_.end() && it->is_array() ? &*it : nullptr;
  };
  const Json* used_names = list("extensionsUsed");
  const Json* required_names = list("extensionsRequired");
  for (std::size_t k = 0; used_names != nullptr && k < used_names->size(); ++k) {
    if ((*used_names)[k] != "KHR_mesh_quantization") continue;
    const bool required = required_names != nullptr &&
                          std::find(required_names->begin(), required_names->end(), (*used_names)[k]) != required_names->end();
    if (!required) {
      diag_.error(codes::NON_REQUIRED_EXTENSION, json_pointer("/extensionsUsed", k),
                  "'KHR_mesh_quantization' is used but not required; it cannot be optional (a reader without it "
                  "would misread the quantized attributes): list it in extensionsRequired too");
    }
  }
  // glTF 2.0: every required extension is also used. One that is not would be kept required by
  // an output that no longer uses it, which the Khronos validator refuses.
  const Json* used = used_names;
  const Json* required = required_names;
  for (std::size_t k = 0; required != nullptr && k < required->size(); ++k) {
    const Json& name = (*required)[k];
    if (!name.is_string()) continue;
    const bool listed = used != nullptr && std::find(used->begin(), used->end(), name) != used->end();
    if (!listed) {
      diag_.error(codes::UNUSED_EXTENSION_REQUIRED, json_pointer("/extensionsRequired", k),
                  quote(name.get<std::string>()) +
                      " is required but not in extensionsUsed (glTF 2.0: every required extension is also "
                      "used): list it in extensionsUsed too, or remove it from extensionsRequired");
    }
  }
}

// Not geometry, but the converter walks images (to copy them) and animation channels (to
// retarget them): their shape must be sound.
void DocumentCheck::check_images_and_animations() {
  const auto& images = entries_["images"];
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (images[i] == nullptr) continue;
    const Json& image = *images[i];
    const std::string pointer = json_pointer("/images", i);
    read_string(image, "uri", pointer);
    read_string(image, "mimeType", pointer);
    read_ref(image, "bufferView", pointer, "bufferViews");
    // The image's bytes are a file or a buffer view, never both or neither (the validator's
    // ONE_OF_MISMATCH); bytes in a buffer carry no file name, so their mimeType says the format.
    // As the validator counts them: a uri that is a string, a bufferView that is an index (one
    // past the end is still given, and refused as unresolved).
    const bool file = image.contains("uri") && image["uri"].is_string();
    const bool view = image.contains("bufferView") && as_uint(image["bufferView"]).has_value();
    if (file == view) {
      diag_.error(codes::ONE_OF_MISMATCH, pointer,
                  file ? "the image has both a uri and a bufferView; give it exactly one (its file, or its bytes in "
                         "a buffer)"
                       : "the image has neither a uri nor a bufferView; give it exactly one (its file, or its "
                         "bytes in a buffer)");
    }
    if (view && !(image.contains("mimeType") && image["mimeType"].is_string())) {
      diag_.error(codes::UNSATISFIED_DEPENDENCY, pointer + "/bufferView",
                  "an image in a buffer view must give its mimeType ('image/png' or 'image/jpeg')");
    }
  }
  const auto& animations = entries_["animations"];
  for (std::size_t a = 0; a < animations.size(); ++a) {
    if (animations[a] != nullptr) check_animation(*animations[a], json_pointer("/animations", a));
  }
}

// An animation's samplers and channels, as the Khronos validator checks them: rdtf reads the
// channels that move the robot (NODE_ANIMATED) and writes every animation into its output, which
// would otherwise carry a dangling or misshapen sampler on into a file the validator refuses.
void DocumentCheck::check_animation(const Json& animation, const std::string& pointer) {
  struct Sampler {
    std::size_t input = kNone, output = kNone;
    std::uint64_t values_per_key = 1;  // 3 for CUBICSPLINE
  };
  std::vector<Sampler> samplers;
  const Json* sampler_array = read_array(animation, "samplers", pointer, true);
  for (std::size_t k = 0; sampler_array != nullptr && k < sampler_array->size(); ++k) {
    Sampler& sampler = samplers.emplace_back();
    const Json* object = object_at(*sampler_array, k, pointer + "/samplers");
    if (object == nullptr) continue;
    const std::string here = json_pointer(pointer + "/samplers", k);
    sampler.input = read_ref(*object, "input", here, "accessors", true);
    sampler.output = read_ref(*object, "output", here, "accessors", true);
    const auto interpolation = read_string(*object, "interpolation", here);
    if (interpolation == "CUBICSPLINE") sampler.values_per_key = 3;
    if (interpolation && *interpolation != "LINEAR" && *interpolation != "STEP" && *interpolation != "CUBICSPLINE") {
      diag_.error(codes::VALUE_NOT_IN_LIST, here + "/interpolation",
                  "is '" + quote(*interpolation) + "'; it must be LINEAR, STEP or CUBICSPLINE");
    }
    for (const auto& [accessor, key] : {std::pair{sampler.input, "input"}, std::pair{sampler.output, "output"}}) {
      if (accessor == kNone || !accessors_[accessor].valid) continue;
      const std::size_t view = accessors_[accessor].view;
      if (view != kNone && views_[view].byte_stride != 0) {
        diag_.error(codes::ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE, here + "/" + key,
                    "accessor " + std::to_string(accessor) + "'s buffer view " + std::to_string(view) +
                        " has a byteStride, which glTF forbids for animation data");
      }
    }
    if (sampler.input != kNone && accessors_[sampler.input].valid) {
      const AccessorFacts& input = accessors_[sampler.input];
      if (input.type != "SCALAR" || input.component_type != kFloat) {
        diag_.error(codes::ANIMATION_SAMPLER_INPUT_ACCESSOR_INVALID_FORMAT, here + "/input",
                    "accessor " + std::to_string(sampler.input) + " holds key times, so it must be SCALAR of FLOAT "
                        "(5126), not " + input.type + " of component type " + std::to_string(input.component_type));
      } else if (sampler.values_per_key == 3 && input.count < 2) {
        diag_.error(codes::ANIMATION_SAMPLER_INPUT_ACCESSOR_TOO_FEW_ELEMENTS, here + "/input",
                    "a CUBICSPLINE sampler needs at least 2 key times; accessor " + std::to_string(sampler.input) +
                        " has " + std::to_string(input.count));
      }
    }
  }
  const Json* channels = read_array(animation, "channels", pointer, true);
  std::map<std::pair<std::size_t, std::string>, std::size_t> targets;  // (node, path) -> first channel
  std::map<std::string, std::size_t> pointers;                          // KHR_animation_pointer's
  for (std::size_t c = 0; channels != nullptr && c < channels->size(); ++c) {
    const Json* channel = object_at(*channels, c, pointer + "/channels");
    const std::string here = json_pointer(pointer + "/channels", c);
    if (channel == nullptr) continue;
    const auto index = read_uint(*channel, "sampler", here, true);
    if (index && *index >= samplers.size()) {
      diag_.error(codes::UNRESOLVED_REFERENCE, here + "/sampler",
                  "there is no samplers[" + std::to_string(*index) + "] in this animation: it has " +
                      (samplers.empty() ? std::string("none") : std::to_string(samplers.size())));
    }
    const Json* target = read_object(*channel, "target", here, true);
    if (target == nullptr) continue;
    const std::size_t node = read_ref(*target, "node", here + "/target", "nodes");
    const auto path = read_string(*target, "path", here + "/target", true);
    if (!path) continue;
    const bool trs = *path == "translation" || *path == "rotation" || *path == "scale";
    if (!trs && *path != "weights" && *path != "pointer") {
      diag_.error(codes::VALUE_NOT_IN_LIST, here + "/target/path",
                  "is '" + quote(*path) + "'; it must be translation, rotation, scale, weights, or pointer "
                  "(KHR_animation_pointer)");
      continue;
    }
    // Two channels of one animation that move one property say two things of it at once.
    std::optional<std::size_t> earlier;
    if (*path == "pointer") {
      const Json* extensions = read_object(*target, "extensions", here + "/target");
      const Json* extension = extensions ? read_object(*extensions, "KHR_animation_pointer", here + "/target/extensions") : nullptr;
      const auto animated = extension ? read_string(*extension, "pointer", here + "/target/extensions/KHR_animation_pointer") : std::nullopt;
      if (animated) {
        const auto [at, added] = pointers.emplace(*animated, c);
        if (!added) earlier = at->second;
      }
    } else if (node != kNone) {
      const auto [at, added] = targets.emplace(std::pair{node, *path}, c);
      if (!added) earlier = at->second;
    }
    if (earlier) {
      diag_.error(codes::ANIMATION_DUPLICATE_TARGETS, json_pointer(pointer + "/channels", *earlier) + "/target",
                  "channels " + std::to_string(*earlier) + " and " + std::to_string(c) + " both animate the " + *path +
                      (node != kNone ? " of node " + std::to_string(node) : std::string()) +
                      ": an animation has one channel per property");
    }
    if (trs && node != kNone && doc_["nodes"][node].contains("matrix")) {
      diag_.error(codes::ANIMATION_CHANNEL_TARGET_NODE_MATRIX, here + "/target",
                  "node " + std::to_string(node) + " has a matrix, which glTF forbids an animation of its " +
                      *path + " to move: give the node translation, rotation and scale instead");
    }
    if (*path == "weights" && node != kNone) {
      // Morph weights move morph targets: a node whose mesh has none has nothing to animate.
      const Json& target_node = doc_["nodes"][node];
      const Json* mesh = nullptr;
      if (target_node.is_object() && target_node.contains("mesh") && target_node["mesh"].is_number_unsigned() &&
          doc_.contains("meshes") && doc_["meshes"].is_array() && target_node["mesh"].get<std::size_t>() < doc_["meshes"].size()) {
        mesh = &doc_["meshes"][target_node["mesh"].get<std::size_t>()];
      }
      bool morphs = false;
      if (mesh != nullptr && mesh->is_object() && mesh->contains("primitives") && (*mesh)["primitives"].is_array()) {
        for (const Json& primitive : (*mesh)["primitives"]) morphs |= primitive.is_object() && primitive.contains("targets");
      }
      if (!morphs) {
        diag_.error(codes::ANIMATION_CHANNEL_TARGET_NODE_WEIGHTS_NO_MORPHS, here + "/target",
                    "channel " + std::to_string(c) + " animates the morph weights of " + node_named(doc_, node) + ", whose " +
                        (mesh == nullptr ? std::string("node has no mesh") : std::string("mesh has no morph targets")) +
                        ": there is nothing for them to move");
      }
    }
    if (!index || *index >= samplers.size() || *path == "pointer") continue;
    const Sampler& sampler = samplers[*index];
    if (sampler.output == kNone || !accessors_[sampler.output].valid) continue;
    const AccessorFacts& output = accessors_[sampler.output];
    const std::uint64_t type = output.component_type;
    const bool normalized_int = output.normalized && (type == 5120 || type == 5121 || type == 5122 || type == 5123);
    const bool format_ok = *path == "rotation" ? output.type == "VEC4" && (type == kFloat || normalized_int)
                           : *path == "weights" ? output.type == "SCALAR" && (type == kFloat || normalized_int)
                                                : output.type == "VEC3" && type == kFloat;
    // Where the validator puts them: at the channel whose path the sampler does not suit.
    const std::string sampler_pointer = here + "/sampler";
    if (!format_ok) {
      diag_.error(codes::ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_FORMAT, sampler_pointer,
                  "accessor " + std::to_string(sampler.output) + " animates the " + *path + " of channel " +
                      std::to_string(c) + ", so it must be " +
                      (*path == "rotation"  ? "VEC4 of FLOAT or of normalized BYTE, UNSIGNED_BYTE, SHORT or UNSIGNED_SHORT"
                       : *path == "weights" ? "SCALAR of FLOAT or of a normalized integer"
                                            : "VEC3 of FLOAT") +
                      ", not " + output.type + (output.normalized ? " of normalized component type " : " of component type ") +
                      std::to_string(type));
      continue;
    }
    if (sampler.input == kNone || !accessors_[sampler.input].valid) continue;
    const std::uint64_t keys = accessors_[sampler.input].count;
    const std::uint64_t per_key = sampler.values_per_key;
    // Weights hold one value per morph target per key: a multiple.
    const bool count_ok = *path == "weights" ? keys > 0 && output.count % (keys * per_key) == 0
                                             : output.count == keys * per_key;
    if (!count_ok) {
      diag_.error(codes::ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_COUNT, sampler_pointer,
                  "accessor " + std::to_string(sampler.output) + " holds " + std::to_string(output.count) +
                      " values for " + std::to_string(keys) + " key times (accessor " + std::to_string(sampler.input) +
                      "): it must hold " + (*path == "weights" ? "a multiple of " : "") +
                      std::to_string(keys * per_key) + (per_key == 3 ? " (CUBICSPLINE: in-tangent, value, out-tangent)" : ""));
    }
  }
}

// Every node that uses a mesh makes the converter read and integrate its triangles once more, and
// displace its vertices by each morph target the node weighs (a node's own weights, else the
// mesh's): one morphed vertex counts as one triangle. Without the second term, a mesh of many
// targets sharing one accessor, all weighed, made the work targets x vertices from a file of
// targets + vertices (5.4 MB took 14.5 s).
void DocumentCheck::check_triangle_limit() {
  const Json* nodes = doc_.contains("nodes") ? &doc_["nodes"] : nullptr;
  const Json* meshes = doc_.contains("meshes") ? &doc_["meshes"] : nullptr;
  const auto weights_of = [](const Json& object) -> const Json* {
    const auto weights = object.find("weights");
    return weights != object.end() && weights->is_array() ? &*weights : nullptr;
  };
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    if (nodes_[i].mesh == kNone) continue;
    const MeshFacts& mesh = meshes_[nodes_[i].mesh];
    total = saturating_add(total, mesh.triangles);
    const Json* weights = nullptr;
    if (!mesh.target_vertices.empty() && nodes != nullptr && meshes != nullptr) {
      weights = weights_of((*nodes)[i]);
      if (weights == nullptr) weights = weights_of((*meshes)[nodes_[i].mesh]);
    }
    std::uint64_t morphed = 0;
    for (std::size_t t = 0; weights != nullptr && t < weights->size() && t < mesh.target_vertices.size(); ++t) {
      const Json& w = (*weights)[t];
      if (w.is_number() && w.get<double>() != 0.0) morphed = saturating_add(morphed, mesh.target_vertices[t]);
    }
    total = saturating_add(total, morphed);
    if (total <= limits_.max_triangles) continue;
    diag_.error(codes::LIMIT_EXCEEDED, json_pointer("/nodes", i) + "/mesh",
                "with this node the model's meshes reach " + std::to_string(total) +
                    " triangles (a mesh counts once per node using it" +
                    (morphed > 0 ? ", and each vertex a weighed morph target moves as one more; this node's " +
                                       std::to_string(morphed)
                                 : std::string()) +
                    "), over the limit of " + std::to_string(limits_.max_triangles) + " (max_triangles)");
    return;
  }
}

}  // namespace internal

namespace {

// A problem under /nodes/N (or a mesh's, a material's, ...) names the object by its name too,
// unless the message does already: a Blender user knows objects by name, not by export index
// (s100err D4: TYPE_MISMATCH, UNRESOLVED_REFERENCE, ARRAY_LENGTH_NOT_IN_LIST on nodes gave the
// index only).
std::string named(const Json& document, const Diagnostic& d) {
  static constexpr std::pair<const char*, const char*> kKinds[] = {
      {"nodes", "node"}, {"meshes", "mesh"}, {"materials", "material"}, {"skins", "skin"},
      {"animations", "animation"}, {"cameras", "camera"}, {"scenes", "scene"}, {"accessors", "accessor"}};
  if (!document.is_object()) return d.message;
  for (const auto& [array, kind] : kKinds) {
    const std::string prefix = std::string("/") + array + "/";
    if (d.pointer.rfind(prefix, 0) != 0) continue;
    const std::size_t end = d.pointer.find('/', prefix.size());
    const std::string digits = d.pointer.substr(prefix.size(), end == std::string::npos ? std::string::npos : end - prefix.size());
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) return d.message;
    const std::size_t index = std::stoul(digits);
    const auto it = document.find(array);
    if (it == document.end() || !it->is_array() || index >= it->size()) return d.message;
    const Json& object = (*it)[index];
    if (!object.is_object() || !object.contains("name") || !object["name"].is_string()) return d.message;
    const std::string name = internal::quote(object["name"].get<std::string>());
    if (name.empty() || d.message.find("'" + name + "'") != std::string::npos) return d.message;
    // A message that names its nodes itself ("node 2 'hand' is already a child of ...").
    for (std::size_t at = d.message.find(std::string(kind) + " "); at != std::string::npos;
         at = d.message.find(std::string(kind) + " ", at + 1)) {
      const std::size_t next = at + std::string_view(kind).size() + 1;
      if (next < d.message.size() && std::isdigit(static_cast<unsigned char>(d.message[next]))) return d.message;
    }
    return std::string(kind) + " " + digits + " '" + name + "': " + d.message;
  }
  return d.message;
}

}  // namespace

void validate_document(const Json& document, const LoadLimits& limits, Diagnostics& diagnostics) {
  Diagnostics found(diagnostics.file());
  internal::DocumentCheck(document, limits, found).run();
  for (const Diagnostic& d : found.all()) diagnostics.add(d.severity, d.code, d.pointer, named(document, d));
}

}  // namespace rdtf
