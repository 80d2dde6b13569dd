// Skinned meshes (the paper's future work): an armature is a kinematic tree already, so every
// bone is a link, and a rigidly skinned mesh's mass belongs to the bones it is bound to.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/triangle_mesh.h"

namespace rdtf {

struct BoneGeometry {
  int joint_node = -1;                   // The bone's node.
  Eigen::Affine3d inverse_bind = Eigen::Affine3d::Identity();  // Mesh space -> bone space.
  // The mesh's triangles bound to this bone: of each piece that has some, those triangles and
  // the vertices they use (in the piece's order).
  std::vector<TriangleMesh> pieces;
};

// Splits a skinned mesh node's triangles among its skin's bones. Each connected part of the
// surface (vertices welded by position and heaviest joint) goes whole to the bone that carries most
// of its vertex weight, so closed parts stay closed and their volumes exact. A part weighted to
// several bones keeps the shape it is drawn in: its vertices are blended by their weights and put
// in the bone's space, so that bone.inverse_bind then world[bone] places them as drawn.
// `world`: every node's transform in the scene (node_world_transforms).
std::vector<BoneGeometry> split_by_bone(const GltfAsset& asset, std::size_t mesh_node,
                                        const std::vector<TriangleMesh>& pieces,
                                        const std::vector<std::size_t>& primitive_index,
                                        const std::vector<Eigen::Affine3d>& world, Diagnostics& diag);

}  // namespace rdtf
