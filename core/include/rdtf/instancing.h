// EXT_mesh_gpu_instancing: a node drawn many times, each instance placed by its own
// translation, rotation and scale relative to the node. Every instance is a solid of the node's
// link (docs/format.md, "Extensions").
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"

namespace rdtf {

// X_NI for each instance I of node N: translation * rotation * scale of its attributes (a missing
// attribute is the identity); one identity for a node without the extension. Nothing, and an
// INSTANCING_INVALID error at the attribute's pointer, when an attribute is unusable. More than
// `max_instances` instances is a LIMIT_EXCEEDED error. Errors point at `input_node`, the node
// the input file had the extension on (a link's mesh, and its instances, move to a node of their
// own in completion: that node is not in the user's file).
std::optional<std::vector<Eigen::Affine3d>> instance_transforms(const GltfAsset& asset, std::size_t node,
                                                                std::uint64_t max_instances,
                                                                Diagnostics& diag, std::size_t input_node);

}  // namespace rdtf
