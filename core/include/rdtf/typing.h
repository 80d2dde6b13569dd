// Node typing: the RDTF paper's Algorithms 1-3, with the amendments docs/format.md lists.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"

namespace rdtf {

// Table 2 of the paper; kNone for nodes outside the scene.
enum class NodeType { kNone, kLink, kJoint, kMesh, kVisual, kInertial };

const char* to_string(NodeType type);
std::optional<NodeType> node_type_from_string(const std::string& text);

// The scene the converter works on: `scene`, else the first one. Nothing (and an error) if the
// document has no scene.
std::optional<std::size_t> default_scene(const Json& document, Diagnostics& diag);

// A type for every node of the default scene (kNone elsewhere). Types already in extras.RDTF (a
// previous conversion, or the author's) and `rdtf_type` in node extras are kept as given.
std::vector<NodeType> type_nodes(const Json& document, std::size_t scene, Diagnostics& diag);

}  // namespace rdtf
