// Node completion: the RDTF paper's Algorithm 4, with the amendments docs/format.md lists.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/typing.h"

namespace rdtf {

// Inserts visual, joint and inertial nodes under every link, appending them to document["nodes"]
// in link order (so the paper's List 1 becomes List 5 exactly) and extending `types` to match.
// A link that carries its own mesh (Blender) gets a new mesh node for it, first under its visual
// node. Links that already have their visual, joint and inertial nodes are left as they are, so
// completing twice changes nothing. `carried_by`, when given, gets for each node the input node
// whose mesh it took (a link that carried its own mesh), else -1: what diagnostics about that
// mesh name, since the input has no node of the output's index.
void complete_nodes(Json& document, std::vector<NodeType>& types, Diagnostics& diag,
                    std::vector<int>* carried_by = nullptr);

// The name a node goes by in generated names and the robot: its name, else "node<index>".
std::string node_name(const Json& document, std::size_t node);

// How a diagnostic names a node: "node 7 'elbow'" (the glTF name, which is the Blender object's
// name), or "node 7" when it has none.
std::string node_label(const Json& document, std::size_t node);

// An offending value as a diagnostic shows it: compact JSON, ASCII only, at most 80 characters.
std::string value_text(const Json& value);

// For a number or an axis typed as text in a Blender custom property ("2700", "[0, 0, 1]"), the
// advice to change the property's type; "" for any other value or key (an extras.RDTF entry's).
std::string text_value_advice(const Json& value, std::string_view key);

}  // namespace rdtf
