// Mass, centre of mass and inertia of every link, from the meshes it owns (section 4.3 of the
// paper, extended: full tensor, every glTF transform, skinned meshes split among their bones).
#pragma once

#include <memory>
#include <vector>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/robot.h"
#include "rdtf/typing.h"

namespace rdtf {

// Fills Link::inertial, meshes, inertial_node and inertial_source for every link. Density:
// `rdtf_density` in the extras of the mesh node or an ancestor up to its link, else
// `default_density` (kg/m^3). `rdtf_mass` on a mesh node sets that mesh's mass, on a link node
// the link's (rescaling its densities). An inertial already authored in extras.RDTF is kept.
// `carried_by` (complete_nodes): a mesh node split off its link is reported as that link's node,
// the one the input file has.
//
// `solids` (optional) keeps what was integrated for report_part_overlaps, which runs once the
// joints are final (KHR_physics_rigid_bodies may still replace them). It borrows the asset's
// buffers: the asset must outlive it.
class LinkSolids;
void compute_link_inertia(const GltfAsset& asset, const std::vector<NodeType>& types,
                          double default_density, Robot& robot, Diagnostics& diag,
                          const std::vector<int>& carried_by = {}, LinkSolids* solids = nullptr);

// Warns where a rigid body's solids count a region twice (LINK_PARTS_OVERLAP) or subtract it
// (MESH_SHELL_INSIDE_OUT), by sampling their winding number (docs/format.md, "Overlapping
// parts"). A body is a link with the links fixed joints join to it: a part parented to a part in
// Blender is a link of its own on a fixed joint, and overlaps its parent all the same. Links whose
// inertial is authored take no part: their mass does not come from their meshes.
void report_part_overlaps(const Json& document, const Robot& robot, const LinkSolids& solids, Diagnostics& diag);

class LinkSolids {
 public:
  LinkSolids();
  ~LinkSolids();
  LinkSolids(LinkSolids&&) noexcept;
  LinkSolids& operator=(LinkSolids&&) noexcept;
  struct State;  // Defined where it is filled and read (core/inertia/link_inertia.cc).
  State& state() const { return *state_; }

 private:
  std::unique_ptr<State> state_;
};

}  // namespace rdtf
