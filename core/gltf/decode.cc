#include "decode.h"

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

bool decode_compressed(GltfAsset& asset, bool& decoded, Diagnostics& diag) {
  decoded = false;
  // Extensions missing from extensionsUsed were refused before (validate_document:
  // UNDECLARED_EXTENSION, for these as for any other).
  // Meshopt first: a Draco primitive's bytes could sit in a meshopt-decoded view.
  if (!decode_meshopt(asset, decoded, diag)) return false;
  return decode_draco(asset, decoded, diag);
}

}  // namespace rdtf::internal
