// Compressed geometry decoded into plain glTF: KHR_draco_mesh_compression (libdraco) and
// EXT_meshopt_compression (libmeshoptimizer). Runs after the buffers are loaded and before the
// data checks; afterwards the document is plain glTF 2.0 whose accessors hold the decoded data,
// so validation, geometry and mass properties read decoded and plain models the same way, and
// the written output needs no decoder (docs/format.md, "Extensions").
//
// The compressed bytes are untrusted: every size a decoder will write is computed from the
// document (accessor counts, buffer view lengths: already capped by validate_document) and
// checked against the limits before anything is allocated, and every decoded count is compared
// with the document's before a byte of it is used.
#pragma once

#include <cstdint>
#include <vector>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"

namespace rdtf::internal {

inline constexpr const char* kDracoExtension = "KHR_draco_mesh_compression";
inline constexpr const char* kMeshoptExtension = "EXT_meshopt_compression";

// A buffer that EXT_meshopt_compression fills by decoding (`"fallback": true`): it has no bytes
// of its own to load.
bool is_meshopt_fallback(const Json& buffer);

// Decodes every compressed buffer view and primitive of `asset` in place (fallback buffers come
// in empty and are sized here). False, with errors, when a compressed part cannot be decoded.
// `decoded` says whether the document changed (and must be validated again).
bool decode_compressed(GltfAsset& asset, bool& decoded, Diagnostics& diag);

// The parts, each on its own.
bool decode_meshopt(GltfAsset& asset, bool& decoded, Diagnostics& diag);
bool decode_draco(GltfAsset& asset, bool& decoded, Diagnostics& diag);

// Removes `name` from extensionsUsed and extensionsRequired (an emptied list goes too).
void drop_extension_name(Json& document, const char* name);

// Removes `name` from `object`'s "extensions" (and an emptied "extensions").
void drop_extension(Json& object, const char* name);

}  // namespace rdtf::internal
