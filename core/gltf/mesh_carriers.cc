#include "rdtf/mesh_carriers.h"

#include "rdtf/geometry.h"

namespace rdtf {
namespace {

// Nothing an author or a modelling tool gives a node: what gltfpack writes for the node it
// inserts (mesh, translation/rotation/scale, and the skin of a skinned mesh it moved) and, at
// most, instancing.
bool bare_mesh_node(const Json& node) {
  if (!node.contains("mesh")) return false;
  for (const char* key : {"name", "children", "extras", "camera", "weights", "matrix"}) {
    if (node.contains(key)) return false;
  }
  if (node.contains("extensions")) {
    const Json& extensions = node["extensions"];
    if (!extensions.is_object()) return false;
    for (const auto& [name, value] : extensions.items()) {
      if (name != "EXT_mesh_gpu_instancing") return false;
    }
  }
  return true;
}

}  // namespace

std::vector<char> mesh_carrier_nodes(const Json& document) {
  const std::size_t count = document.contains("nodes") ? document["nodes"].size() : 0;
  std::vector<char> carrier(count, 0);
  if (count == 0) return carrier;
  const Json& nodes = document["nodes"];
  for (std::size_t parent = 0; parent < count; ++parent) {
    const Json& node = nodes[parent];
    if (node.contains("mesh") || !node.contains("children")) continue;
    std::size_t found = count;
    std::size_t bare = 0;
    for (const Json& child : node["children"]) {
      const auto c = child.get<std::size_t>();
      if (bare_mesh_node(nodes[c])) {
        found = c;
        ++bare;
      }
    }
    // Two bare mesh children are no encoder's doing (it gives a node one mesh): plain meshes.
    if (bare == 1) carrier[found] = 1;
  }
  return carrier;
}

}  // namespace rdtf
