#include "decode.h"

#include <string>

#include "rdtf/diagnostic_codes.h"

namespace rdtf::internal {

bool is_meshopt_fallback(const Json& buffer) {
  if (!buffer.is_object() || !buffer.contains("extensions")) return false;
  const Json& extensions = buffer["extensions"];
  if (!extensions.is_object() || !extensions.contains(kMeshoptExtension)) return false;
  const Json& extension = extensions[kMeshoptExtension];
  return extension.is_object() && extension.contains("fallback") &&
         extension["fallback"].is_boolean() && extension["fallback"].get<bool>();
}

void drop_extension(Json& object, const char* name) {
  if (!object.is_object() || !object.contains("extensions") || !object["extensions"].is_object()) return;
  object["extensions"].erase(name);
  if (object["extensions"].empty()) object.erase("extensions");
}

void drop_extension_name(Json& document, const char* name) {
  for (const char* key : {"extensionsUsed", "extensionsRequired"}) {
    if (!document.contains(key) || !document[key].is_array()) continue;
    Json kept = Json::array();
    for (const Json& item : document[key]) {
      if (item != name) kept.push_back(item);
    }
    if (kept.empty()) {
      document.erase(key);
    } else {
      document[key] = std::move(kept);
    }
  }
}

namespace {

bool declared(const Json& document, const char* name) {
  if (!document.contains("extensionsUsed") || !document["extensionsUsed"].is_array()) return false;
  for (const Json& used : document["extensionsUsed"]) {
    if (used == name) return true;
  }
  return false;
}

bool uses(const Json& object, const char* name) {
  return object.is_object() && object.contains("extensions") && object["extensions"].is_object() &&
         object["extensions"].contains(name);
}

// The extensions rdtf decodes, used where extensionsUsed does not list them: glTF 2.0 requires
// the list (the Khronos validator: UNDECLARED_EXTENSION), and rdtf refuses them as it refuses
// quantized data without KHR_mesh_quantization, rather than read an invalid file silently.
bool check_declared(const Json& document, Diagnostics& diag) {
  bool ok = true;
  const auto refuse = [&](const std::string& pointer, const char* name) {
    diag.error(codes::UNDECLARED_EXTENSION, pointer + "/extensions/" + name,
               std::string("uses ") + name + ", which extensionsUsed does not list (glTF 2.0 requires it, and " +
                   "extensionsRequired too where the data is only there compressed): list it, or compress the " +
                   "model again with a tool that does");
    ok = false;
  };
  if (!declared(document, kDracoExtension) && document.contains("meshes") && document["meshes"].is_array()) {
    const Json& meshes = document["meshes"];
    for (std::size_t m = 0; m < meshes.size() && ok; ++m) {
      const Json primitives = meshes[m].is_object() ? meshes[m].value("primitives", Json::array()) : Json::array();
      for (std::size_t p = 0; p < primitives.size() && ok; ++p) {
        if (uses(primitives[p], kDracoExtension)) {
          refuse("/meshes/" + std::to_string(m) + "/primitives/" + std::to_string(p), kDracoExtension);
        }
      }
    }
  }
  for (const char* key : {"bufferViews", "buffers"}) {
    if (declared(document, kMeshoptExtension) || !document.contains(key) || !document[key].is_array()) continue;
    for (std::size_t i = 0; i < document[key].size() && ok; ++i) {
      if (uses(document[key][i], kMeshoptExtension)) refuse("/" + std::string(key) + "/" + std::to_string(i), kMeshoptExtension);
    }
  }
  return ok;
}

}  // namespace

bool decode_compressed(GltfAsset& asset, bool& decoded, Diagnostics& diag) {
  decoded = false;
  if (!check_declared(asset.document, diag)) return false;
  // Meshopt first: a Draco primitive's bytes could sit in a meshopt-decoded view.
  if (!decode_meshopt(asset, decoded, diag)) return false;
  return decode_draco(asset, decoded, diag);
}

}  // namespace rdtf::internal
