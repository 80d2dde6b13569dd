// Structural checks of a glTF document, in the order the loader runs them.
//
// These cover what the converter reads (asset, buffers, bufferViews, accessors including sparse,
// meshes, nodes, scenes, skins) and report each problem with the JSON pointer the Khronos
// validator would use and, where the validator has one, its issue code. The loader refuses the
// model when any error is reported, so later stages may index without re-checking.
#pragma once

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"

namespace rdtf {

// Before any buffer is loaded: types, required properties, index references, enum values,
// ranges and overflow-safe offset arithmetic between accessors and buffer views, counts against
// `limits`, and the node graph (no cycles, at most one parent, scene roots are roots).
void validate_document(const Json& document, const LoadLimits& limits, Diagnostics& diagnostics);

// After buffers are loaded: each buffer holds its byteLength, and the data of the accessors the
// converter reads is sound (indices within the vertex count, no NaN or infinite positions,
// positions within the accessor's declared min/max).
void validate_data(const GltfAsset& asset, Diagnostics& diagnostics);

}  // namespace rdtf
