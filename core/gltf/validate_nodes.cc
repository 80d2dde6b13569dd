// Nodes and what they form: transforms, the node graph (a forest), skins and scenes. See
// document_check.h.
#include <algorithm>
#include <cmath>

#include "document_check.h"
#include "validate_util.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::internal {
namespace {

// Why a column-major 4x4 matrix is no translation, rotation and scale, or "" when it is one: the
// last row must be (0, 0, 0, 1) and the first three columns orthogonal and non-zero. The
// validator's tolerance: it accepts 1e-5 of shear and refuses 1e-4.
std::string not_decomposable(const std::vector<double>& m) {
  if (m[3] != 0 || m[7] != 0 || m[11] != 0 || m[15] != 1) {
    return "its last row is (" + number_text(m[3]) + ", " + number_text(m[7]) + ", " + number_text(m[11]) + ", " +
           number_text(m[15]) + "), not (0, 0, 0, 1): it projects";
  }
  const auto dot = [&](int a, int b) {
    return m[4 * a] * m[4 * b] + m[4 * a + 1] * m[4 * b + 1] + m[4 * a + 2] * m[4 * b + 2];
  };
  static const char* const kAxes[] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (!(dot(a, a) > 0) || !std::isfinite(dot(a, a))) {
      return std::string("its ") + kAxes[a] + " column has length " + number_text(std::sqrt(dot(a, a))) +
             ": it collapses space (a scale of 0)";
    }
  }
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      const double cosine = dot(a, b) / std::sqrt(dot(a, a) * dot(b, b));
      if (std::abs(cosine) > 5e-5) {
        return std::string("its ") + kAxes[a] + " and " + kAxes[b] + " columns are not orthogonal (cosine " +
               number_text(cosine) + "): it shears";
      }
    }
  }
  return "";
}

std::string numbers_text(const std::vector<double>& values) {
  std::string text = "[";
  for (std::size_t i = 0; i < values.size(); ++i) text += (i ? ", " : "") + number_text(values[i]);
  return text + "]";
}

}  // namespace

void DocumentCheck::check_nodes() {
  const auto& nodes = entries_["nodes"];
  nodes_.resize(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i] != nullptr) check_node(*nodes[i], i, json_pointer("/nodes", i), nodes_[i]);
  }
}

void DocumentCheck::check_node(const Json& node, std::size_t index, const std::string& pointer, NodeFacts& facts) {
  facts.children = read_refs(node, "children", pointer, "nodes");
  facts.mesh = read_ref(node, "mesh", pointer, "meshes");
  facts.skin = read_ref(node, "skin", pointer, "skins");
  read_ref(node, "camera", pointer, "cameras");
  if (node.contains("skin") && !node.contains("mesh")) {
    diag_.error(codes::UNSATISFIED_DEPENDENCY, pointer + "/skin", "a node with a skin must have a mesh");
  }
  const MeshFacts* mesh =
      facts.mesh != kNone && meshes_[facts.mesh].valid ? &meshes_[facts.mesh] : nullptr;
  const auto weights = read_numbers(node, "weights", pointer, 0);
  if (weights && mesh != nullptr && weights->size() != mesh->targets) {
    diag_.error(codes::NODE_WEIGHTS_INVALID, pointer + "/weights",
                "the node has " + std::to_string(weights->size()) + " weights for the " +
                    std::to_string(mesh->targets) + " morph targets of mesh " +
                    std::to_string(facts.mesh));
  }
  if (facts.skin != kNone && mesh != nullptr && !mesh->skinned) {
    diag_.error(codes::NODE_SKIN_WITH_NON_SKINNED_MESH, pointer,
                "the node has a skin but mesh " + std::to_string(facts.mesh) +
                    " has no JOINTS_0 attribute");
  }
  check_transform(node, index, pointer);
}

void DocumentCheck::check_transform(const Json& node, std::size_t index, const std::string& pointer) {
  const auto matrix = read_numbers(node, "matrix", pointer, 16);
  read_numbers(node, "translation", pointer, 3);
  read_numbers(node, "scale", pointer, 3);
  const auto rotation = read_numbers(node, "rotation", pointer, 4);
  if (node.contains("matrix") &&
      (node.contains("translation") || node.contains("rotation") || node.contains("scale"))) {
    diag_.error(codes::NODE_MATRIX_TRS, pointer + "/matrix",
                node_named(doc_, index) + " has a matrix and translation/rotation/scale too; a node has "
                "either, not both");
  }
  if (matrix) {
    if (const std::string why = not_decomposable(*matrix); !why.empty()) {
      diag_.error(codes::NODE_MATRIX_NON_TRS, pointer + "/matrix",
                  node_named(doc_, index) + ": the matrix " + numbers_text(*matrix) +
                      " (column-major) is not a translation, rotation and scale: " + why +
                      "; apply the transform in the modeller before export");
    }
  }
  if (!rotation) return;
  double norm2 = 0;
  for (std::size_t k = 0; k < 4; ++k) {
    if (std::abs((*rotation)[k]) > 1) {
      diag_.error(codes::VALUE_NOT_IN_RANGE, json_pointer(pointer + "/rotation", k),
                  "a unit quaternion's components lie in [-1, 1]; this one is " +
                      number_text((*rotation)[k]));
    }
    norm2 += (*rotation)[k] * (*rotation)[k];
  }
  // The validator's tolerance for a unit quaternion stored as floats.
  if (std::abs(std::sqrt(norm2) - 1) > 0.00769) {
    diag_.error(
        codes::ROTATION_NON_UNIT, pointer + "/rotation",
        node_named(doc_, index) + ": the rotation quaternion " + numbers_text(*rotation) + " has length " +
            number_text(std::sqrt(norm2)) + "; it must be 1 (x, y, z, w of a unit quaternion)");
  }
}

// At most one parent per node and no loops: the node graph is a forest.
void DocumentCheck::check_node_graph() {
  parents_.assign(nodes_.size(), kNone);
  const std::size_t errors = diag_.error_count();
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    for (std::size_t k = 0; k < nodes_[i].children.size(); ++k) {
      const std::size_t child = nodes_[i].children[k];
      if (parents_[child] == kNone) {
        parents_[child] = i;
        continue;
      }
      diag_.error(codes::NODE_PARENT_OVERRIDE, json_pointer(json_pointer("/nodes", i) + "/children", k),
                  node_named(doc_, child) + " is already a child of " + node_named(doc_, parents_[child]) +
                      "; a node can have only one parent");
    }
  }
  report_loops();
  forest_ = diag_.error_count() == errors;
  if (forest_) order_trees();
}

// Depth-first along children: meeting a node that is still on the path closes a loop, made of
// the nodes on the path from it.
void DocumentCheck::report_loops() {
  std::vector<char> state(nodes_.size(), 0);  // 0 unseen, 1 on the path, 2 done
  std::vector<char> reported(nodes_.size(), 0);
  for (std::size_t start = 0; start < nodes_.size(); ++start) {
    if (state[start] != 0) continue;
    std::vector<std::pair<std::size_t, std::size_t>> path = {{start, 0}};  // (node, next child)
    state[start] = 1;
    while (!path.empty()) {
      const std::size_t node = path.back().first;
      if (path.back().second == nodes_[node].children.size()) {
        state[node] = 2;
        path.pop_back();
        continue;
      }
      const std::size_t child = nodes_[node].children[path.back().second++];
      if (state[child] == 0) {
        state[child] = 1;
        path.emplace_back(child, 0);
        continue;
      }
      for (auto it = path.rbegin(); state[child] == 1 && it != path.rend(); ++it) {
        if (!reported[it->first]) {
          reported[it->first] = 1;
          diag_.error(codes::NODE_LOOP, json_pointer("/nodes", it->first),
                      node_named(doc_, it->first) + " is its own descendant: the children lists form a loop");
        }
        if (it->first == child) break;
      }
    }
  }
}

// Each node's tree root and depth-first entry and exit times: ancestry then costs O(1), so
// skins of many joints in deep trees stay cheap to check.
void DocumentCheck::order_trees() {
  root_.assign(nodes_.size(), kNone);
  enter_.assign(nodes_.size(), 0);
  leave_.assign(nodes_.size(), 0);
  std::size_t clock = 0;
  for (std::size_t start = 0; start < nodes_.size(); ++start) {
    if (parents_[start] != kNone) continue;
    std::vector<std::pair<std::size_t, std::size_t>> path = {{start, 0}};  // (node, next child)
    root_[start] = start;
    enter_[start] = clock++;
    while (!path.empty()) {
      const std::size_t node = path.back().first;
      if (path.back().second == nodes_[node].children.size()) {
        leave_[node] = clock++;
        path.pop_back();
        continue;
      }
      const std::size_t child = nodes_[node].children[path.back().second++];
      root_[child] = start;
      enter_[child] = clock++;
      path.emplace_back(child, 0);
    }
  }
}

bool DocumentCheck::is_ancestor_or_self(std::size_t ancestor, std::size_t node) const {
  return enter_[ancestor] <= enter_[node] && leave_[node] <= leave_[ancestor];
}

void DocumentCheck::check_skins() {
  const auto& skins = entries_["skins"];
  skin_tree_.assign(skins.size(), kNone);
  for (std::size_t s = 0; s < skins.size(); ++s) {
    if (skins[s] == nullptr) continue;
    const std::string pointer = json_pointer("/skins", s);
    const std::size_t errors = diag_.error_count();
    const auto joints = read_refs(*skins[s], "joints", pointer, "nodes", true);
    const std::size_t skeleton = read_ref(*skins[s], "skeleton", pointer, "nodes");
    const std::size_t matrices = read_ref(*skins[s], "inverseBindMatrices", pointer, "accessors");
    if (matrices != kNone) {
      check_inverse_bind_matrices(matrices, joints.size(), pointer + "/inverseBindMatrices");
    }
    if (!forest_ || diag_.error_count() != errors) continue;
    const std::size_t root = root_[joints.front()];
    if (std::any_of(joints.begin(), joints.end(),
                    [&](std::size_t j) { return root_[j] != root; })) {
      diag_.error(codes::SKIN_NO_COMMON_ROOT, pointer + "/joints",
                  "the joints are not all in one node tree");
      continue;
    }
    skin_tree_[s] = root;
    if (skeleton != kNone && !std::all_of(joints.begin(), joints.end(), [&](std::size_t j) {
          return is_ancestor_or_self(skeleton, j);
        })) {
      diag_.error(
          codes::SKIN_SKELETON_INVALID, pointer + "/skeleton",
          "skeleton node " + std::to_string(skeleton) + " is not an ancestor of every joint");
    }
  }
}

void DocumentCheck::check_inverse_bind_matrices(std::size_t accessor, std::size_t joints,
                                                const std::string& pointer) {
  const AccessorFacts& facts = accessors_[accessor];
  if (!facts.valid) return;
  if (facts.type != "MAT4" || facts.component_type != kFloat || facts.normalized) {
    diag_.error(codes::SKIN_IBM_INVALID_FORMAT, pointer,
                "inverse bind matrices must be MAT4 of FLOAT, not " + facts.type +
                    " of component type " + std::to_string(facts.component_type));
  } else if (facts.count < joints) {
    diag_.error(codes::INVALID_IBM_ACCESSOR_COUNT, pointer,
                "the accessor has " + std::to_string(facts.count) + " matrices for " +
                    std::to_string(joints) + " joints");
  }
  if (facts.view != kNone && views_[facts.view].byte_stride != 0) {
    diag_.error(codes::SKIN_IBM_ACCESSOR_WITH_BYTESTRIDE, pointer,
                "buffer view " + std::to_string(facts.view) +
                    " holds inverse bind matrices, so it must not have a byteStride");
  }
}

void DocumentCheck::check_scenes() {
  read_ref(doc_, "scene", "", "scenes");
  const auto& scenes = entries_["scenes"];
  std::vector<std::vector<std::size_t>> scene_roots(scenes.size());
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    if (scenes[s] == nullptr) continue;
    const std::string pointer = json_pointer("/scenes", s) + "/nodes";
    scene_roots[s] = read_refs(*scenes[s], "nodes", json_pointer("/scenes", s), "nodes");
    // Report each listed node that has a parent, at its place in the list.
    const Json* listed = scenes[s]->contains("nodes") ? &(*scenes[s])["nodes"] : nullptr;
    for (std::size_t k = 0; listed != nullptr && listed->is_array() && k < listed->size(); ++k) {
      const auto node = as_uint((*listed)[k]);
      if (!node || *node >= parents_.size() || parents_[*node] == kNone) continue;
      diag_.error(codes::SCENE_NON_ROOT_NODE, json_pointer(pointer, k),
                  node_named(doc_, *node) + " is a child of " + node_named(doc_, parents_[*node]) +
                      ", so it cannot be a root of the scene");
    }
  }
  if (forest_) check_skins_in_scenes(scene_roots);
}

// A skinned mesh in a scene is posed by its skin's joints, which must be in that scene too. In
// a forest whose scenes list roots, a node is in a scene when the root of its tree is listed.
void DocumentCheck::check_skins_in_scenes(
    const std::vector<std::vector<std::size_t>>& scene_roots) {
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::size_t>> by_trees;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const std::size_t skin = nodes_[i].skin;
    if (skin == kNone || nodes_[i].mesh == kNone || skin_tree_[skin] == kNone) continue;
    if (root_[i] != skin_tree_[skin]) by_trees[{root_[i], skin_tree_[skin]}].push_back(i);
  }
  if (by_trees.empty()) return;
  std::map<std::size_t, std::vector<std::size_t>> scenes_of_root;
  std::vector<std::vector<std::size_t>> sorted_roots = scene_roots;
  for (std::size_t s = 0; s < sorted_roots.size(); ++s) {
    std::sort(sorted_roots[s].begin(), sorted_roots[s].end());
    for (std::size_t root : sorted_roots[s]) scenes_of_root[root].push_back(s);
  }
  for (const auto& [trees, skinned] : by_trees) {
    const auto [mesh_root, joint_root] = trees;
    for (std::size_t s : scenes_of_root[mesh_root]) {
      if (std::binary_search(sorted_roots[s].begin(), sorted_roots[s].end(), joint_root)) continue;
      for (std::size_t node : skinned) {
        diag_.error(codes::NODE_SKIN_NO_SCENE, json_pointer("/nodes", node),
                    "scene " + std::to_string(s) +
                        " shows this skinned mesh but not the joints of skin " +
                        std::to_string(nodes_[node].skin) + " (the tree of node " +
                        std::to_string(joint_root) + ")");
      }
      break;
    }
  }
}

}  // namespace rdtf::internal
