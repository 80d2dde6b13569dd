// Nodes that an encoder inserted only to carry a mesh (gltfpack moves each mesh into a new child
// node that holds the dequantization transform). The robot must not change when a scene is
// re-encoded, so such a node counts as its parent's mesh: the parent is typed as if the mesh were
// its own, and the carrier is a mesh node of the parent's link. docs/format.md, "Mesh carriers".
#pragma once

#include <vector>

#include "rdtf/gltf.h"

namespace rdtf {

// Per node: 1 for a mesh carrier. A carrier has a mesh and nothing that an author gives a node:
// no name, no children, no extras, no skin, camera or morph weights, no extension but
// EXT_mesh_gpu_instancing; its parent has no mesh and no other such child. Assumes a validated
// document (a forest).
std::vector<char> mesh_carrier_nodes(const Json& document);

}  // namespace rdtf
