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

// [ixx, ixy, ixz, iyy, iyz, izz], URDF's order.
Json inertia_to_json(const Eigen::Matrix3d& inertia);
Json vector_to_json(const Eigen::Vector3d& v);

}  // namespace rdtf
