// KHR_physics_rigid_bodies (Khronos draft): the robot's mass properties and joints as glTF physics
// tools (Blender's physics add-on, Babylon.js, fastgltf) read them, written beside extras.RDTF,
// and read from inputs those tools made. docs/format.md, "KHR_physics_rigid_bodies", has the
// frames, the precedence against extras.RDTF and node extras, and what is not carried.
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/robot.h"
#include "rdtf/typing.h"

namespace rdtf {

inline constexpr const char* kKhrPhysics = "KHR_physics_rigid_bodies";

// A symmetric tensor as I = R diag(moments) R^T with R a proper rotation (det +1): the draft's
// inertiaDiagonal and inertiaOrientation. Moments ascending; repeated moments (a cylinder, a
// sphere) get a deterministic basis (eigenvectors signed so that their largest component is
// positive, the third the cross product of the first two).
struct PrincipalInertia {
  Eigen::Vector3d moments = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // w >= 0
};
PrincipalInertia principal_inertia(const Eigen::Matrix3d& inertia);
Eigen::Matrix3d inertia_from_principal(const Eigen::Vector3d& moments, const Eigen::Quaterniond& rotation);

// The attachment frames of a KHR joint: `node` carries the joint, `connected` is its connectedNode.
struct KhrJointRef {
  int node = -1;
  int connected = -1;
  int definition = -1;  // Index into physicsJoints.
};

// For each robot joint, the KHR joint of the document that joins its two links (its attachment
// nodes lie one in each link's body: the link node or a node under it that is under no other
// link), if any. Index errors are not reported here (read_khr_physics does).
std::vector<std::optional<KhrJointRef>> khr_joints_of_robot(const Json& document,
                                                            const std::vector<NodeType>& types,
                                                            const Robot& robot);

// Reads authored KHR motion and joints into the robot (after its mass properties are computed):
// motion for links with no RDTF mass description, joints for joints with no RDTF properties. KHR
// data that RDTF overrides and that disagrees with it is a warning; invalid KHR data an error.
void read_khr_physics(const Json& document, const std::vector<NodeType>& types, Robot& robot,
                      Diagnostics& diag);

// Writes motion on every link node and a KHR joint for every robot joint that has none, with two
// attachment nodes (appended, typed visual: `types` grows to match), and lists the extension in
// extensionsUsed (never extensionsRequired). A joint whose attachment frames no node of translation
// and rotation can give (a link under a mirror) gets none, with the warning KHR_JOINT_NOT_WRITTEN.
void write_khr_physics(Json& document, std::vector<NodeType>& types, const Robot& robot, Diagnostics& diag);

}  // namespace rdtf
