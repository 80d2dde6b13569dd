// Bounds of each link's geometry in its link frame, for the centre-of-mass check.
#include <algorithm>

#include "rdtf/dynamics.h"
#include "rdtf/geometry.h"
#include "rdtf/instancing.h"

namespace rdtf {
namespace {

bool is_triangle_mode(const Json& primitive) {
  const int mode = primitive.value("mode", 4);
  return mode == 4 || mode == 5 || mode == 6;  // TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN
}

// Grows `box` by the triangle primitives' positions of `mesh`, morphed by `weights` (morph_weights
// of the node drawing it) and mapped by each of `placements` (one per instance of the node).
void add_mesh(const GltfAsset& asset, std::size_t mesh, std::span<const double> weights,
              std::span<const Eigen::Affine3d> placements, Eigen::AlignedBox3d& box) {
  const Json& meshes = asset.document["meshes"];
  if (mesh >= meshes.size()) return;
  for (const Json& primitive : meshes[mesh].value("primitives", Json::array())) {
    if (!is_triangle_mode(primitive) || !primitive.contains("attributes") ||
        !primitive["attributes"].contains("POSITION")) {
      continue;
    }
    const auto accessor = primitive["attributes"]["POSITION"].get<std::size_t>();
    const std::vector<double> values = read_accessor(asset, accessor);
    std::vector<Eigen::Vector3d> positions(values.size() / 3);
    for (std::size_t i = 0; i < positions.size(); ++i) {
      positions[i] = Eigen::Vector3d(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
    }
    add_morph_displacements(asset, primitive, weights, positions);
    for (const Eigen::Affine3d& X : placements) {
      for (const Eigen::Vector3d& p : positions) box.extend(X * p);
    }
  }
}

// The inverse bind matrix of `joint_node` in the skin of `mesh_node` (identity when none).
std::optional<Eigen::Affine3d> inverse_bind(const GltfAsset& asset, const Json& mesh_node,
                                            int joint_node) {
  const Json& document = asset.document;
  const auto skin_index = mesh_node["skin"].get<std::size_t>();
  if (!document.contains("skins") || skin_index >= document["skins"].size()) return std::nullopt;
  const Json& skin = document["skins"][skin_index];
  const Json& joints = skin.value("joints", Json::array());
  for (std::size_t j = 0; j < joints.size(); ++j) {
    if (joints[j].get<int>() != joint_node) continue;
    Eigen::Affine3d X = Eigen::Affine3d::Identity();
    if (skin.contains("inverseBindMatrices")) {
      const std::vector<double> m = read_accessor(asset, skin["inverseBindMatrices"].get<std::size_t>());
      if (m.size() < 16 * (j + 1)) return std::nullopt;
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) X.matrix()(r, c) = m[16 * j + 4 * c + r];  // column-major
    }
    return X;
  }
  return std::nullopt;
}

}  // namespace

LinkBounds link_geometry_bounds(const GltfAsset& asset, const Robot& robot) {
  LinkBounds bounds(robot.links.size());
  const Json& document = asset.document;
  if (!document.contains("nodes")) return bounds;
  const std::vector<Eigen::Affine3d> world = node_world_transforms(document);
  const int node_count = static_cast<int>(document["nodes"].size());
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    const Eigen::Affine3d X_LS(link.X_SL.inverse().matrix());
    Eigen::AlignedBox3d box;  // empty
    std::vector<int> done;  // A node with N instances is N of the link's meshes: bound it once.
    for (const LinkMesh& mesh : link.meshes) {
      if (mesh.node < 0 || mesh.node >= node_count) continue;
      if (std::find(done.begin(), done.end(), mesh.node) != done.end()) continue;
      done.push_back(mesh.node);
      const Json& node = document["nodes"][mesh.node];
      if (!node.contains("mesh")) continue;
      const auto mesh_index = node["mesh"].get<std::size_t>();
      const std::vector<double> weights = morph_weights(document, static_cast<std::size_t>(mesh.node));
      if (node.contains("skin")) {
        // The whole skinned mesh placed as this bone places its part (superset of the part).
        if (link.node < 0 || link.node >= node_count) continue;
        const auto ibm = inverse_bind(asset, node, link.node);
        if (!ibm) continue;
        const Eigen::Affine3d X = X_LS * world[link.node] * *ibm;
        add_mesh(asset, mesh_index, weights, std::span(&X, 1), box);
      } else {
        // Every instance of EXT_mesh_gpu_instancing is a solid of the link (its mass counts them
        // all), so the bounds hold each where it is drawn. The conversion checked the instances:
        // a failure here leaves the mesh out, as one the conversion refused.
        Diagnostics scratch;
        const auto instances =
            instance_transforms(asset, static_cast<std::size_t>(mesh.node), asset.limits.max_triangles, scratch,
                                static_cast<std::size_t>(mesh.node));
        if (!instances) continue;
        std::vector<Eigen::Affine3d> placements;
        placements.reserve(instances->size());
        for (const Eigen::Affine3d& X_NI : *instances) placements.push_back(X_LS * world[mesh.node] * X_NI);
        add_mesh(asset, mesh_index, weights, placements, box);
      }
    }
    if (!box.isEmpty()) bounds[l] = box;
  }
  return bounds;
}

}  // namespace rdtf
