// Geometry from glTF accessors: positions and triangles of mesh primitives, node transforms.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/triangle_mesh.h"

namespace rdtf {

// Every element of an accessor as doubles, `components` per element, row after row: honours
// byteStride, sparse substitution and normalized integers (glTF 2.0 section 3.11). Assumes the
// accessor passed validate_document and validate_data.
std::vector<double> read_accessor(const GltfAsset& asset, std::size_t accessor);

// Number of components of an accessor's element type ("VEC3" -> 3, "MAT4" -> 16).
int component_count(const std::string& type);

// The morph target weights a node draws its mesh with (glTF 2.0 section 3.7.2.2): the node's
// `weights`, else its mesh's; empty when there are none or all are 0 (the mesh as stored). A
// Blender shape key's value is exported as such a weight.
std::vector<double> morph_weights(const Json& document, std::size_t node);

// Adds each morph target's POSITION displacements, times its weight, to the primitive's
// positions: what a viewer draws. Nothing when no weighted target moves POSITION.
void add_morph_displacements(const GltfAsset& asset, const Json& primitive, std::span<const double> weights,
                             std::vector<Eigen::Vector3d>& positions);

// The triangles of one primitive (modes TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN, indexed or not),
// morphed by `weights` (morph_weights of the node that draws it). Points and lines give nothing
// and an info diagnostic.
std::optional<TriangleMesh> read_primitive_triangles(const GltfAsset& asset, std::size_t mesh,
                                                     std::size_t primitive, Diagnostics& diag,
                                                     std::span<const double> weights = {});

// A primitive's triangles for the mass and surface computations: read in place from the asset's
// buffers when they allow it (mode TRIANGLES, POSITION as dense floats, indices dense unsigned
// integers or none: what exporters write), else copied out by read_primitive_triangles. The same
// triangles, positions and diagnostics either way; in place spares copying (and faulting in) a
// large model's geometry (issue 6).
struct PrimitiveTriangles {
  TriangleMeshView in_place;        // Borrows the asset's buffers; used when `copy` is empty.
  std::optional<TriangleMesh> copy;

  TriangleMeshView view() const { return copy ? TriangleMeshView::of(*copy) : in_place; }
  TriangleMesh mesh() const;  // As read_primitive_triangles gives it.
};

// Nothing (and the diagnostics of read_primitive_triangles) for a primitive without triangles.
// A primitive that `weights` morph is always a copy.
std::optional<PrimitiveTriangles> read_primitive_in_place(const GltfAsset& asset, std::size_t mesh,
                                                          std::size_t primitive, Diagnostics& diag,
                                                          std::span<const double> weights = {});

// A node's local transform (matrix, or translation * rotation * scale).
Eigen::Affine3d node_local_transform(const Json& node);

// Parent of every node (-1 for none); assumes a validated document (a forest).
std::vector<int> node_parents(const Json& document);

// Transform from the scene frame to each node's frame, X_SN: every root of the node forest (in a
// scene or not) is placed in the scene frame.
std::vector<Eigen::Affine3d> node_world_transforms(const Json& document);

// The orthogonal factor Q of the polar decomposition A = Q P (P symmetric positive definite): the
// frame's axes with the scale removed, a mirror kept (det Q = -1 then). Unique for an invertible A;
// an orthonormal A comes back exactly.
Eigen::Matrix3d orthogonal_part(const Eigen::Matrix3d& A);

// The rigid part of an affine transform: its translation and the rotation of orthogonal_part,
// under a mirror with the frame's own Z axis reversed (docs/format.md, "The link frame"), so a
// mirrored frame has one rotation whatever its scale.
Eigen::Isometry3d rigid_part(const Eigen::Affine3d& X);

}  // namespace rdtf
