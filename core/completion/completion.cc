#include "rdtf/completion.h"

#include <cstdint>
#include <cstdio>
#include <optional>
#include <string_view>
#include <unordered_map>

#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

std::size_t append_node(Json& document, std::vector<NodeType>& types, Json node, NodeType type) {
  document["nodes"].push_back(std::move(node));
  types.push_back(type);
  return document["nodes"].size() - 1;
}

// Blender's mesh-on-the-parent: move the link's mesh (with its skin and morph weights, which
// belong to it) onto a new child with an identity transform, so the scene renders the same. Its
// weight animations follow it afterwards (retarget_weight_animations).
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
  return append_node(document, types, std::move(mesh_node), NodeType::kMesh);
}

// Morph-weight animations follow each mesh split_off_mesh moved to its new node: channels of the
// link's "weights", and KHR_animation_pointer's at "/nodes/<link>/weights" (a weights animation of
// a node without a mesh is invalid glTF). One walk over the channels for all the moved meshes:
// a walk per link cost links x channels (4.9 MB of them took 76 s).
void retarget_weight_animations(Json& document, const std::unordered_map<std::size_t, std::size_t>& mesh_node_of) {
  if (mesh_node_of.empty() || !document.contains("animations")) return;
  const auto moved = [&](std::size_t link) {
    const auto it = mesh_node_of.find(link);
    return it == mesh_node_of.end() ? std::optional<std::size_t>() : it->second;
  };
  for (Json& animation : document["animations"]) {
    if (!animation.contains("channels")) continue;
    for (Json& channel : animation["channels"]) {
      Json& target = channel["target"];
      if (target.value("path", "") == "weights" && target.contains("node")) {
        if (const auto index = moved(target["node"].get<std::size_t>())) target["node"] = *index;
      }
      const auto extensions = target.find("extensions");
      if (target.value("path", "") != "pointer" || extensions == target.end() || !extensions->is_object()) continue;
      const auto extension = extensions->find("KHR_animation_pointer");
      if (extension == extensions->end() || !extension->is_object()) continue;
      const auto pointer = extension->find("pointer");
      if (pointer == extension->end() || !pointer->is_string()) continue;
      // "/nodes/<digits>/weights" or below it.
      const std::string before = pointer->get<std::string>();
      constexpr std::string_view kNodes = "/nodes/";
      if (before.rfind(kNodes, 0) != 0) continue;
      const std::size_t digits_end = before.find_first_not_of("0123456789", kNodes.size());
      if (digits_end == kNodes.size() || digits_end == std::string::npos || digits_end - kNodes.size() > 19) continue;
      const std::string rest = before.substr(digits_end);
      if (rest != "/weights" && rest.rfind("/weights/", 0) != 0) continue;
      const std::string digits = before.substr(kNodes.size(), digits_end - kNodes.size());
      if (digits.size() > 1 && digits[0] == '0') continue;  // Not a JSON pointer's array index.
      if (const auto index = moved(std::stoull(digits))) {
        *pointer = std::string(kNodes) + std::to_string(*index) + rest;
      }
    }
  }
}

// A name as a part of a generated name: a long one (a hostile file's megabyte of name) is cut to
// its first 48 bytes, at a UTF-8 character boundary, and told apart by a digest of the whole.
// Each child link's joint is named after its parent: without the cut, one long name times many
// children made the output quadratic (a 2.6 MB glTF took 9-11 GB).
std::string name_part(const std::string& name) {
  constexpr std::size_t kMaxBytes = 64, kKeptBytes = 48;
  if (name.size() <= kMaxBytes) return name;
  std::size_t cut = kKeptBytes;
  while (cut > 0 && (static_cast<unsigned char>(name[cut]) & 0xC0) == 0x80) --cut;  // A continuation byte.
  std::uint64_t digest = 14695981039346656037ull;  // 64-bit FNV-1a.
  for (const char c : name) digest = (digest ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(digest));
  return name.substr(0, cut) + "~" + std::string(hex, 8);
}

// A part of a group with joint empties or frames parented to it (typing.cc, part_of_group) stays
// a mesh of the group's link, under its visual node; what was parented to it hangs from the link
// instead, each through a new joint node that places it as the part did (the part's transform,
// copied), so every node keeps its place in the scene. Returns the new joint nodes.
std::vector<std::size_t> hang_from_link(Json& document, std::vector<NodeType>& types, std::size_t link,
                                        std::size_t mesh, Diagnostics& diag) {
  std::vector<std::size_t> moved, kept;
  for (const Json& child : document["nodes"][mesh].value("children", Json::array())) {
    const auto c = child.get<std::size_t>();
    (types[c] == NodeType::kJoint || types[c] == NodeType::kLink ? moved : kept).push_back(c);
  }
  std::vector<std::size_t> placers;
  if (moved.empty()) return placers;
  if (kept.empty()) {
    document["nodes"][mesh].erase("children");
  } else {
    document["nodes"][mesh]["children"] = kept;
  }
  std::string names;
  for (std::size_t child : moved) names += std::string(names.empty() ? "" : ", ") + "'" + node_name(document, child) + "'";
  diag.info(codes::MESH_HOLDS_FRAMES, json_pointer("/nodes", mesh),
            "mesh node '" + node_name(document, mesh) + "' is a part of group '" + node_name(document, link) +
                "' (its rdtf_density or rdtf_mass covers it), so it stays in link '" + node_name(document, link) +
                "'; what is parented to it (" + names + ") hangs from that link where it was (give the part "
                "rdtf_joint to make it a link of its own)");
  for (std::size_t child : moved) {
    const std::string child_name = name_part(node_name(document, child));
    // Named as completion names a joint node it adds above a link; above a joint node, after the
    // part that placed it.
    Json placer = {{"name", types[child] == NodeType::kLink
                                ? name_part(node_name(document, link)) + "_" + child_name + "_joint"
                                : name_part(node_name(document, mesh)) + "_" + child_name + "_frame"},
                   {"children", Json::array({child})}};
    for (const char* key : {"matrix", "translation", "rotation", "scale"}) {
      if (document["nodes"][mesh].contains(key)) placer[key] = document["nodes"][mesh][key];
    }
    placers.push_back(append_node(document, types, std::move(placer), NodeType::kJoint));
  }
  return placers;
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

std::string text_value_advice(const Json& value, std::string_view key) {
  if (!value.is_string() || !key.starts_with("rdtf_")) return {};
  const std::string text = value.get<std::string>();
  const bool numeric = !text.empty() && text.find_first_not_of("0123456789+-.eE[], ") == std::string::npos &&
                       text.find_first_of("0123456789") != std::string::npos;
  if (!numeric) return {};
  return "; it is text: in Blender, make the custom property a number (Edit Property > Type: Float, or Float "
         "Array for an axis), not a String";
}

void complete_nodes(Json& document, std::vector<NodeType>& types, Diagnostics& diag, std::vector<int>* carried_by) {
  if (!document.contains("nodes")) return;
  const std::size_t original_count = document["nodes"].size();
  std::unordered_map<std::size_t, std::size_t> mesh_node_of;  // Link -> the node its mesh moved to.
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
      mesh_node_of.emplace(link, mesh_node);
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
        case NodeType::kMesh: {
          mesh_children.push_back(child);
          const auto placers = hang_from_link(document, types, link, child, diag);
          other_children.insert(other_children.end(), placers.begin(), placers.end());
          break;
        }
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
      Json joint = {{"name", name_part(name) + "_" + name_part(node_name(document, child)) + "_joint"},
                    {"children", Json::array({child})}};
      other_children.push_back(append_node(document, types, std::move(joint), NodeType::kJoint));
    }
    if (!has_inertial) {
      other_children.push_back(
          append_node(document, types, Json{{"name", name + "_inertial"}}, NodeType::kInertial));
    }
    document["nodes"][link]["children"] = other_children;
  }
  retarget_weight_animations(document, mesh_node_of);
}

}  // namespace rdtf
