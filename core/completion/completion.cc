#include "rdtf/completion.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

std::size_t append_node(Json& document, std::vector<NodeType>& types, Json node, NodeType type) {
  document["nodes"].push_back(std::move(node));
  types.push_back(type);
  return document["nodes"].size() - 1;
}

// Blender's mesh-on-the-parent: move the link's mesh (with its skin and morph weights, which
// belong to it) onto a new child with an identity transform, so the scene renders the same.
std::size_t split_off_mesh(Json& document, std::vector<NodeType>& types, std::size_t link) {
  Json mesh_node = {{"name", node_name(document, link) + "_mesh"}};
  Json& link_node = document["nodes"][link];
  for (const char* key : {"mesh", "skin", "weights"}) {
    if (link_node.contains(key)) {
      mesh_node[key] = link_node[key];
      link_node.erase(key);
    }
  }
  // GPU instances are copies of the mesh: they go with it.
  constexpr const char* kInstancing = "EXT_mesh_gpu_instancing";
  if (link_node.contains("extensions") && link_node["extensions"].is_object() &&
      link_node["extensions"].contains(kInstancing)) {
    mesh_node["extensions"] = {{kInstancing, link_node["extensions"][kInstancing]}};
    link_node["extensions"].erase(kInstancing);
    if (link_node["extensions"].empty()) link_node.erase("extensions");
  }
  const std::size_t index = append_node(document, types, std::move(mesh_node), NodeType::kMesh);
  // Morph-weight animations follow the mesh to its new node: channels of the node's "weights", and
  // KHR_animation_pointer's at "/nodes/<link>/weights" (a weights animation of a node without a
  // mesh is invalid glTF).
  const std::string pointer_before = "/nodes/" + std::to_string(link) + "/weights";
  if (document.contains("animations")) {
    for (Json& animation : document["animations"]) {
      if (!animation.contains("channels")) continue;
      for (Json& channel : animation["channels"]) {
        Json& target = channel["target"];
        if (target.value("path", "") == "weights" && target.contains("node") &&
            target["node"].get<std::size_t>() == link) {
          target["node"] = index;
        }
        const auto extensions = target.find("extensions");
        if (target.value("path", "") != "pointer" || extensions == target.end() || !extensions->is_object()) continue;
        const auto extension = extensions->find("KHR_animation_pointer");
        if (extension == extensions->end() || !extension->is_object()) continue;
        const auto pointer = extension->find("pointer");
        if (pointer == extension->end() || !pointer->is_string()) continue;
        const std::string before = pointer->get<std::string>();
        if (before == pointer_before || before.rfind(pointer_before + "/", 0) == 0) {
          *pointer = "/nodes/" + std::to_string(index) + "/weights" + before.substr(pointer_before.size());
        }
      }
    }
  }
  return index;
}

}  // namespace

std::string node_name(const Json& document, std::size_t node) {
  const Json& n = document["nodes"][node];
  if (n.contains("name") && n["name"].is_string() && !n["name"].get<std::string>().empty()) {
    return n["name"].get<std::string>();
  }
  return "node" + std::to_string(node);
}

std::string node_label(const Json& document, std::size_t node) {
  const Json& n = document["nodes"][node];
  std::string label = "node " + std::to_string(node);
  if (n.contains("name") && n["name"].is_string() && !n["name"].get<std::string>().empty()) {
    label += " " + value_text(n["name"]);
  }
  return label;
}

std::string value_text(const Json& value) {
  constexpr std::size_t kMax = 80;
  std::string text = value.dump(-1, ' ', true, Json::error_handler_t::replace);
  if (value.is_string() && text.size() >= 2) text = "'" + text.substr(1, text.size() - 2) + "'";
  if (text.size() > kMax) text = text.substr(0, kMax - 3) + "...";
  return text;
}

void complete_nodes(Json& document, std::vector<NodeType>& types, Diagnostics& diag, std::vector<int>* carried_by) {
  if (!document.contains("nodes")) return;
  const std::size_t original_count = document["nodes"].size();
  for (std::size_t link = 0; link < original_count; ++link) {
    if (types[link] != NodeType::kLink) continue;
    const std::string name = node_name(document, link);
    std::vector<std::size_t> mesh_children;
    std::vector<std::size_t> link_children;
    std::vector<std::size_t> other_children;
    if (document["nodes"][link].contains("mesh")) {
      const bool has_children = document["nodes"][link].contains("children") && !document["nodes"][link]["children"].empty();
      const std::size_t mesh_node = split_off_mesh(document, types, link);
      mesh_children.push_back(mesh_node);
      if (carried_by != nullptr) {
        carried_by->resize(document["nodes"].size(), -1);
        (*carried_by)[mesh_node] = static_cast<int>(link);
      }
      diag.info(codes::LINK_MESH_SPLIT, json_pointer("/nodes", link),
                "link '" + name + "' carries its own mesh" + (has_children ? " and children (Blender's layout)" : "") +
                    ": its mesh moved to the new node '" + name + "_mesh' (node " + std::to_string(mesh_node) +
                    " of the output)");
    }
    bool has_inertial = false;
    const Json children = document["nodes"][link].value("children", Json::array());
    for (const Json& child_json : children) {
      const auto child = child_json.get<std::size_t>();
      switch (types[child]) {
        case NodeType::kMesh:
          mesh_children.push_back(child);
          break;
        case NodeType::kLink:
          link_children.push_back(child);
          break;
        default:
          has_inertial |= types[child] == NodeType::kInertial;
          other_children.push_back(child);
      }
    }
    if (!mesh_children.empty()) {
      Json visual = {{"name", name + "_visual"}, {"children", mesh_children}};
      other_children.push_back(append_node(document, types, std::move(visual), NodeType::kVisual));
    }
    // One joint node per child link (the paper groups them in one; URDF needs one each).
    for (std::size_t child : link_children) {
      Json joint = {{"name", name + "_" + node_name(document, child) + "_joint"},
                    {"children", Json::array({child})}};
      other_children.push_back(append_node(document, types, std::move(joint), NodeType::kJoint));
    }
    if (!has_inertial) {
      other_children.push_back(
          append_node(document, types, Json{{"name", name + "_inertial"}}, NodeType::kInertial));
    }
    document["nodes"][link]["children"] = other_children;
  }
}

}  // namespace rdtf
