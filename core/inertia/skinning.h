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
  std::vector<TriangleMesh> pieces;      // The mesh's triangles bound to this bone.
};

// Splits a skinned mesh node's triangles among its skin's bones. Each connected part of the
// surface (vertices welded by position) goes whole to the bone that carries most of its vertex
// weight, so closed parts stay closed and their volumes exact.
std::vector<BoneGeometry> split_by_bone(const GltfAsset& asset, std::size_t mesh_node,
                                        const std::vector<TriangleMesh>& pieces,
                                        const std::vector<std::size_t>& primitive_index,
                                        Diagnostics& diag);

}  // namespace rdtf
