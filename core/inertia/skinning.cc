#include "skinning.h"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <unordered_map>

#include "rdtf/geometry.h"
#include "rdtf/completion.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) { parent[find(a)] = find(b); }
};

// A vertex is welded to another at the same position weighted most to the same joint: the
// copies a seam (UV, sharp edge) splits. Position alone welded rigid parts that only touch (CAD
// parts of an arm sharing a face's corners, each wholly on its own bone) into one part, which
// then went whole to one bone and left the other massless (s100xform D2).
struct PositionKey {
  double x, y, z;
  std::int64_t joint;  // the joint with the most weight on the vertex (-1: none)
  bool operator==(const PositionKey& o) const { return x == o.x && y == o.y && z == o.z && joint == o.joint; }
};
struct PositionKeyHash {
  std::size_t operator()(const PositionKey& p) const {
    const std::hash<double> h;
    return h(p.x) ^ (h(p.y) * 31) ^ (h(p.z) * 1000003) ^ (std::hash<std::int64_t>()(p.joint) * 7919);
  }
};

std::vector<Eigen::Affine3d> inverse_bind_matrices(const GltfAsset& asset, const Json& skin,
                                                   std::size_t joints) {
  std::vector<Eigen::Affine3d> result(joints, Eigen::Affine3d::Identity());
  if (!skin.contains("inverseBindMatrices")) return result;
  const auto values = read_accessor(asset, skin["inverseBindMatrices"].get<std::size_t>());
  for (std::size_t j = 0; j < joints && (j + 1) * 16 <= values.size(); ++j) {
    Eigen::Matrix4d m;
    for (int column = 0; column < 4; ++column)
      for (int row = 0; row < 4; ++row) m(row, column) = values[j * 16 + column * 4 + row];
    result[j].matrix() = m;
  }
  return result;
}

}  // namespace

std::vector<BoneGeometry> split_by_bone(const GltfAsset& asset, std::size_t mesh_node,
                                        const std::vector<TriangleMesh>& pieces,
                                        const std::vector<std::size_t>& primitive_index,
                                        const std::vector<Eigen::Affine3d>& world, Diagnostics& diag) {
  const Json& document = asset.document;
  const Json& node = document["nodes"][mesh_node];
  const Json& skin = document["skins"][node["skin"].get<std::size_t>()];
  const std::size_t joint_count = skin["joints"].size();
  const Json& primitives = document["meshes"][node["mesh"].get<std::size_t>()]["primitives"];
  const std::string pointer = json_pointer("/nodes", mesh_node);

  // Weld vertices of all pieces, and give each its weight per joint. Weights are kept sparse (a
  // vertex names at most 4 joints a set): dense, per vertex per joint, a skin of 10,000 joints on
  // boxes took 13 GB and 72 s. Each sum is taken in the order the dense one was, so the bone each
  // part goes to is the same to the bit.
  std::unordered_map<PositionKey, std::uint32_t, PositionKeyHash> ids;
  std::vector<std::vector<std::uint32_t>> welded(pieces.size());
  std::unordered_map<std::uint64_t, double> vertex_weight;  // (welded vertex << 32 | joint) -> weight
  std::vector<std::vector<std::uint32_t>> vertex_joints;    // Per welded vertex, its joints as first met.
  const auto add_weight = [&](std::uint32_t vertex, std::size_t joint, double weight) {
    const auto [it, added] = vertex_weight.try_emplace(std::uint64_t{vertex} << 32 | joint, 0.0);
    if (added) vertex_joints[vertex].push_back(static_cast<std::uint32_t>(joint));
    it->second += weight;
  };
  // Per piece, per vertex: 4 x sets joints and their weights, as read.
  std::vector<std::vector<double>> joints_by_piece(pieces.size()), weights_by_piece(pieces.size());
  std::vector<std::pair<std::size_t, double>> own;  // One vertex's weight per joint.
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    const Json& attributes = primitives[primitive_index[p]]["attributes"];
    const std::size_t n = pieces[p].positions.size();
    std::vector<double> joints_of(n * 4, 0.0), weights_of(n * 4, 0.0);
    bool bound = false;
    for (int set = 0; attributes.contains("JOINTS_" + std::to_string(set)); ++set) {
      const std::string suffix = std::to_string(set);
      if (!attributes.contains("WEIGHTS_" + suffix)) break;
      const auto joints = read_accessor(asset, attributes["JOINTS_" + suffix].get<std::size_t>());
      const auto weights = read_accessor(asset, attributes["WEIGHTS_" + suffix].get<std::size_t>());
      if (set > 0) {
        joints_of.resize(n * 4 * (set + 1));
        weights_of.resize(n * 4 * (set + 1));
      }
      for (std::size_t v = 0; v < n && v * 4 + 3 < joints.size(); ++v) {
        for (int k = 0; k < 4; ++k) {
          joints_of[(set * n + v) * 4 + k] = joints[v * 4 + k];
          weights_of[(set * n + v) * 4 + k] = weights[v * 4 + k];
        }
      }
      bound = true;
    }
    if (!bound) {
      diag.warning(codes::SKIN_NO_WEIGHTS, pointer,
                   "a primitive of the skinned mesh has no JOINTS_0/WEIGHTS_0; its triangles "
                   "are left out of the mass");
    }
    welded[p].resize(n);
    const std::size_t sets = n == 0 ? 0 : joints_of.size() / (n * 4);
    for (std::size_t v = 0; v < n; ++v) {
      const Eigen::Vector3d& q = pieces[p].positions[v];
      std::int64_t heaviest = -1;
      if (bound) {
        own.clear();
        for (std::size_t s = 0; s < sets; ++s) {
          for (int k = 0; k < 4; ++k) {
            const auto joint = static_cast<std::size_t>(joints_of[(s * n + v) * 4 + k]);
            if (joint >= joint_count) continue;
            auto at = std::find_if(own.begin(), own.end(), [&](const auto& e) { return e.first == joint; });
            if (at == own.end()) at = own.insert(own.end(), {joint, 0.0});
            at->second += weights_of[(s * n + v) * 4 + k];
          }
        }
        // The joint of the most weight, the lowest of equals (as max_element over all joints).
        double best = 0;
        for (const auto& [joint, weight] : own) {
          if (weight > best || (weight == best && best > 0 && static_cast<std::int64_t>(joint) < heaviest)) {
            best = weight;
            heaviest = static_cast<std::int64_t>(joint);
          }
        }
      }
      const auto [it, inserted] =
          ids.try_emplace(PositionKey{q.x(), q.y(), q.z(), heaviest}, static_cast<std::uint32_t>(ids.size()));
      if (inserted) vertex_joints.emplace_back();
      welded[p][v] = it->second;
      if (!bound) continue;
      for (std::size_t s = 0; s < sets; ++s) {
        for (int k = 0; k < 4; ++k) {
          const auto joint = static_cast<std::size_t>(joints_of[(s * n + v) * 4 + k]);
          if (joint < joint_count) add_weight(it->second, joint, weights_of[(s * n + v) * 4 + k]);
        }
      }
    }
    if (bound) {
      joints_by_piece[p] = std::move(joints_of);
      weights_by_piece[p] = std::move(weights_of);
    }
  }

  UnionFind parts(ids.size());
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    for (const auto& t : pieces[p].triangles) {
      parts.unite(welded[p][t[0]], welded[p][t[1]]);
      parts.unite(welded[p][t[1]], welded[p][t[2]]);
    }
  }
  // Each part's weight per joint, summed over its vertices in their order.
  std::unordered_map<std::uint32_t, std::unordered_map<std::uint32_t, double>> part_weights;
  for (std::uint32_t v = 0; v < vertex_joints.size(); ++v) {
    auto& sum = part_weights[parts.find(v)];
    for (const std::uint32_t joint : vertex_joints[v]) sum[joint] += vertex_weight.at(std::uint64_t{v} << 32 | joint);
  }
  std::unordered_map<std::uint32_t, int> bone_of_part;
  for (const auto& [part, sum] : part_weights) {
    std::vector<std::pair<std::uint32_t, double>> by_joint(sum.begin(), sum.end());
    std::sort(by_joint.begin(), by_joint.end());
    double total = 0, best = 0;
    std::int64_t best_joint = -1;
    for (const auto& [joint, weight] : by_joint) {
      total += weight;  // In joint order, as over the dense vector.
      if (best_joint < 0 || weight > best) {
        best = weight;
        best_joint = joint;
      }
    }
    if (total <= 0 || best_joint < 0) {
      bone_of_part[part] = -1;
      continue;
    }
    bone_of_part[part] = static_cast<int>(best_joint);
    if (best < 0.999 * total) {
      const auto joint_node = skin["joints"][static_cast<std::size_t>(best_joint)].get<std::size_t>();
      diag.info(codes::SKIN_PART_SHARED, pointer,
                "a connected part of the skinned mesh is weighted to several bones: it weighs as drawn (each "
                "vertex where its weights blend it to), all of it on " + node_label(document, joint_node) +
                    ", which carries " + format_number(100.0 * best / total, 3) + "% of its weight");
    }
  }

  const auto inverse_binds = inverse_bind_matrices(asset, skin, joint_count);
  std::vector<BoneGeometry> bones(joint_count);
  for (std::size_t j = 0; j < joint_count; ++j) {
    bones[j].joint_node = skin["joints"][j].get<int>();
    bones[j].inverse_bind = inverse_binds[j];
  }
  // Each bone gets, of each piece with triangles bound to it, those triangles and the vertices
  // they use, in their order (a vertex is in one part, so on one bone). A copy of every piece's
  // vertices for every bone was bones x vertices of memory.
  constexpr std::uint32_t kNone = ~std::uint32_t{0};
  std::vector<std::vector<std::uint32_t>> local(pieces.size());  // Per piece, per vertex: index on its bone.
  std::vector<std::unordered_map<int, std::size_t>> piece_on(pieces.size());  // Per piece: bone -> its piece there.
  const auto bone_of_vertex = [&](std::size_t p, std::uint32_t v) { return bone_of_part[parts.find(welded[p][v])]; };
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    local[p].assign(pieces[p].positions.size(), kNone);
    for (const auto& t : pieces[p].triangles) {
      if (bone_of_vertex(p, t[0]) < 0) continue;
      for (const std::uint32_t v : t) local[p][v] = 0;  // Used; numbered below.
    }
    for (std::uint32_t v = 0; v < local[p].size(); ++v) {
      if (local[p][v] == kNone) continue;
      const int bone = bone_of_vertex(p, v);
      auto& bone_pieces = bones[static_cast<std::size_t>(bone)].pieces;
      const auto [at, added] = piece_on[p].try_emplace(bone, bone_pieces.size());
      if (added) bone_pieces.emplace_back();
      TriangleMesh& mesh = bone_pieces[at->second];
      local[p][v] = static_cast<std::uint32_t>(mesh.positions.size());
      mesh.positions.push_back(pieces[p].positions[v]);
    }
    for (const auto& t : pieces[p].triangles) {
      const int bone = bone_of_vertex(p, t[0]);
      if (bone < 0) continue;
      bones[static_cast<std::size_t>(bone)].pieces[piece_on[p].at(bone)].triangles.push_back(
          {local[p][t[0]], local[p][t[1]], local[p][t[2]]});
    }
  }
  // A vertex weighted to other bones too is drawn where its weights blend it to (glTF 2.0 3.7.3.3:
  // sum of w_j S_j v, S_j = the joint's world transform times its inverse bind matrix), which no
  // one bone's S_b puts it: its place is kept in the bone's space, S_b^-1 sum(w_j S_j) v, so that
  // the part weighs as drawn. (Rigid under S_b alone it was 53% heavier than drawn, with the
  // skeleton posed away from its bind pose; s100xform D1.) In the bind pose every S_j is the
  // identity, and a vertex wholly on its part's bone keeps its coordinates to the bit.
  std::vector<Eigen::Affine3d> S(joint_count);
  for (std::size_t j = 0; j < joint_count; ++j) {
    const auto joint_node = skin["joints"][j].get<std::size_t>();
    S[j] = (joint_node < world.size() ? world[joint_node] : Eigen::Affine3d::Identity()) * inverse_binds[j];
  }
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    const std::vector<double>& joints_of = joints_by_piece[p];
    const std::vector<double>& weights_of = weights_by_piece[p];
    const std::size_t n = pieces[p].positions.size();
    if (joints_of.empty() || n == 0) continue;
    const std::size_t slots = joints_of.size() / n;  // 4 per JOINTS_n set
    for (std::size_t v = 0; v < n; ++v) {
      const int bone = bone_of_part[parts.find(welded[p][v])];
      if (bone < 0 || local[p][v] == kNone) continue;  // No triangle of the bone uses it.
      Eigen::Matrix4d blend = Eigen::Matrix4d::Zero();
      double total = 0, others = 0;
      for (std::size_t k = 0; k < slots; ++k) {
        const std::size_t set = k / 4, slot = k % 4;
        const auto joint = static_cast<std::size_t>(joints_of[(set * n + v) * 4 + slot]);
        const double weight = weights_of[(set * n + v) * 4 + slot];
        if (joint >= joint_count || weight == 0) continue;
        blend += weight * S[joint].matrix();
        total += weight;
        if (joint != static_cast<std::size_t>(bone)) others += weight;
      }
      if (others == 0 || !(total > 0)) continue;
      const Eigen::Matrix3d L = S[static_cast<std::size_t>(bone)].linear();
      if (!(std::abs(L.determinant()) > 0)) continue;
      const Eigen::Vector4d drawn = (blend / total) * pieces[p].positions[v].homogeneous();
      bones[static_cast<std::size_t>(bone)].pieces[piece_on[p].at(bone)].positions[local[p][v]] =
          S[static_cast<std::size_t>(bone)].inverse() * drawn.head<3>();
    }
  }
  std::erase_if(bones, [](const BoneGeometry& bone) { return bone.pieces.empty(); });
  return bones;
}

}  // namespace rdtf
