// extras.RDTF (the paper's section 3, Tables 1 and 2): one entry per typed node, with joint and
// inertial properties. docs/format.md documents every key.
#pragma once

#include <vector>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/robot.h"
#include "rdtf/typing.h"

namespace rdtf {

// Writes document["extras"]["RDTF"] from the types and the robot. Entries already there are kept
// with everything in them (an authored joint or inertial is never overwritten); computed
// inertials ("source": "computed") are refreshed. False (and an error) when the document's extras
// is not an object, so RDTF cannot be added without destroying it.
bool write_rdtf_extras(Json& document, const std::vector<NodeType>& types, const Robot& robot,
                       Diagnostics& diag);

// The same description in node extras, for tools that keep only those (Blender's importer drops
// the document's extras): rdtf_type on every typed node; the joint keys on each joint's frame node
// when its properties came from extras.RDTF (or a default); rdtf_inertial on inertial nodes;
// rdtf_density on each mesh node whose density was not its own. Keys already there are kept.
// Called by write_rdtf_extras.
void write_node_extras(Json& document, const std::vector<NodeType>& types, const Robot& robot);

// [ixx, ixy, ixz, iyy, iyz, izz], URDF's order.
Json inertia_to_json(const Eigen::Matrix3d& inertia);
Json vector_to_json(const Eigen::Vector3d& v);

}  // namespace rdtf
