// Checks of accessor values by their use (skins, animations), run by validate_data once every
// accessor was located. `readable[i]`: accessor i lies within its buffer and its sparse indices
// are sound, so read_accessor may read it.
#pragma once

#include <cstdint>
#include <vector>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"

namespace rdtf::internal {

// A primitive a node draws with a skin (the node has both), where the checks of its JOINTS_n and
// WEIGHTS_n find it. Primitives of malformed meshes or skins are left out (validate_document's).
struct SkinnedPrimitive {
  std::size_t node = 0;
  std::uint64_t joint_count = 0;  // Of the node's skin.
  std::uint64_t mesh = 0;
  std::size_t primitive = 0;
  const Json* attributes = nullptr;  // An object.
};
std::vector<SkinnedPrimitive> skinned_primitives(const Json& document);

// JOINTS_n / WEIGHTS_n of every skinned primitive: ACCESSOR_JOINTS_INDEX_DUPLICATE,
// ACCESSOR_WEIGHTS_NEGATIVE, ACCESSOR_WEIGHTS_NON_NORMALIZED.
void check_skin_influences(const GltfAsset& asset, const std::vector<char>& readable, Diagnostics& diag);

// Every skin's inverse bind matrices are affine: ACCESSOR_INVALID_IBM.
void check_inverse_bind_matrices(const GltfAsset& asset, const std::vector<char>& readable, Diagnostics& diag);

// Every animation sampler's key times: declared bounds, >= 0, strictly rising.
void check_animation_inputs(const GltfAsset& asset, const std::vector<char>& readable, Diagnostics& diag);

}  // namespace rdtf::internal
