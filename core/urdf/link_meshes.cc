// The surface of each link in its own frame, for the URDF's visual and collision STL files: the
// same meshes, transforms and skin split the mass properties use (core/inertia/link_inertia.cc).
#include <algorithm>
#include <map>

#include "../inertia/skinning.h"
#include "rdtf/geometry.h"
#include "rdtf/instancing.h"
#include "rdtf/mass_properties.h"
#include "rdtf/mesh_checks.h"
#include "urdf_internal.h"

namespace rdtf::urdf_internal {
namespace {

struct MeshPieces {
  std::vector<TriangleMesh> pieces;
  std::vector<std::size_t> primitive_index;
  bool closed = false;
};

// A mesh as drawn with morph weights (morph_weights; none: as stored), as the mass is computed.
using PiecesKey = std::pair<std::size_t, std::vector<double>>;

const MeshPieces& pieces_of(const GltfAsset& asset, PiecesKey key, std::map<PiecesKey, MeshPieces>& cache) {
  if (const auto found = cache.find(key); found != cache.end()) return found->second;
  MeshPieces result;
  Diagnostics ignored;  // The conversion reported these already.
  const std::size_t mesh = key.first;
  const Json& primitives = asset.document["meshes"][mesh]["primitives"];
  for (std::size_t p = 0; p < primitives.size(); ++p) {
    if (auto triangles = read_primitive_triangles(asset, mesh, p, ignored, key.second)) {
      result.pieces.push_back(std::move(*triangles));
      result.primitive_index.push_back(p);
    }
  }
  result.closed = analyze_surface(result.pieces).closed();
  return cache.emplace(std::move(key), std::move(result)).first->second;
}

// Appends one solid, mapped by X and wound outward. Returns false when it has no volume.
bool append_solid(const std::vector<TriangleMesh>& pieces, const Eigen::Affine3d& X,
                  TriangleMesh& out) {
  const VolumeIntegrals integrals = integrate_solid(pieces, X);
  // A mirroring X flips the winding; so does an inside-out surface. Either way the signed
  // volume, which integrate_solid corrects for the mirror, says which way is out.
  const bool flip = (integrals.volume < 0) != (X.linear().determinant() < 0);
  Eigen::AlignedBox3d box;
  for (const TriangleMesh& piece : pieces) {
    const auto base = static_cast<std::uint32_t>(out.positions.size());
    for (const Eigen::Vector3d& p : piece.positions) {
      out.positions.push_back(X * p);
      box.extend(out.positions.back());
    }
    for (const auto& t : piece.triangles) {
      out.triangles.push_back(flip ? std::array<std::uint32_t, 3>{base + t[0], base + t[2], base + t[1]}
                                   : std::array<std::uint32_t, 3>{base + t[0], base + t[1], base + t[2]});
    }
  }
  if (box.isEmpty()) return false;
  // "No volume": below rounding noise for its size, or below what MuJoCo accepts (mjMINVAL).
  const double extent = box.diagonal().norm();
  const double volume = std::abs(integrals.volume);
  return volume > 1e-12 * extent * extent * extent && volume > 1e-15;
}

}  // namespace

std::vector<LinkSurface> link_surfaces(const GltfAsset& asset, const Robot& robot) {
  std::vector<LinkSurface> surfaces(robot.links.size());
  const Json& document = asset.document;
  if (!document.contains("nodes")) return surfaces;
  const auto world = node_world_transforms(document);
  std::map<PiecesKey, MeshPieces> cache;
  std::map<int, std::vector<BoneGeometry>> bones_of_node;

  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    LinkSurface& surface = surfaces[l];
    std::vector<int> done;
    for (const LinkMesh& link_mesh : link.meshes) {
      const int node = link_mesh.node;
      if (std::find(done.begin(), done.end(), node) != done.end()) continue;
      done.push_back(node);
      const Json& n = document["nodes"][node];
      const MeshPieces& mesh =
          pieces_of(asset, {n["mesh"].get<std::size_t>(), morph_weights(document, static_cast<std::size_t>(node))}, cache);
      if (mesh.pieces.empty()) continue;
      if (!n.contains("skin")) {
        const Eigen::Affine3d X_LN = link.X_SL.inverse() * world[node];
        // Every instance of EXT_mesh_gpu_instancing is a solid of the link, as its inertial counts
        // them (core/inertia/link_inertia.cc); the conversion checked them, so a failure here
        // leaves the mesh out as one the conversion refused.
        std::uint64_t triangles = 0;
        for (const TriangleMesh& piece : mesh.pieces) triangles += piece.triangles.size();
        Diagnostics ignored;
        const auto instances = instance_transforms(
            asset, static_cast<std::size_t>(node), asset.limits.max_triangles / std::max<std::uint64_t>(triangles, 1),
            ignored, static_cast<std::size_t>(node));
        if (!instances) continue;
        for (const Eigen::Affine3d& X_NI : *instances) {
          const bool solid = append_solid(mesh.pieces, X_LN * X_NI, surface.mesh);
          surface.closed = surface.closed && mesh.closed && solid;
          ++surface.solids;
        }
        continue;
      }
      auto bones = bones_of_node.find(node);
      if (bones == bones_of_node.end()) {
        Diagnostics ignored;
        bones = bones_of_node
                    .emplace(node, split_by_bone(asset, static_cast<std::size_t>(node), mesh.pieces,
                                                 mesh.primitive_index, world, ignored))
                    .first;
      }
      for (const BoneGeometry& bone : bones->second) {
        if (bone.joint_node != link.node) continue;
        const Eigen::Affine3d X_LV = link.X_SL.inverse() * world[bone.joint_node] * bone.inverse_bind;
        const bool solid = append_solid(bone.pieces, X_LV, surface.mesh);
        surface.closed = surface.closed && analyze_surface(bone.pieces).closed() && solid;
        ++surface.solids;
      }
    }
  }
  return surfaces;
}

}  // namespace rdtf::urdf_internal
