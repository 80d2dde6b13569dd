// Mass, centre of mass and inertia of every link, from the meshes it owns (section 4.3 of the
// paper, extended: full tensor, every glTF transform, skinned meshes split among their bones).
#pragma once

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
void compute_link_inertia(const GltfAsset& asset, const std::vector<NodeType>& types,
                          double default_density, Robot& robot, Diagnostics& diag,
                          const std::vector<int>& carried_by = {});

}  // namespace rdtf
