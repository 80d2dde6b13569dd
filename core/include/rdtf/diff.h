// What changed between two revisions of a robot: links and joints added, removed and changed, and
// for each changed one which aspects changed. Pure: the facts of two robots in, a delta out.
//
// Comparison is exact, on the converted values (the same content gives the same doubles, so no
// tolerance is needed and none hides a real edit). What counts as a change of each aspect:
//   joint origin   any of the 12 numbers of X_PJ (rotation and translation in the parent link frame)
//   joint axis     any component of the unit axis (joint frame)
//   joint type     the joint kind (fixed, revolute, ...)
//   joint limits   whether there are limits, lower, upper, effort or velocity
//   joint dynamics damping, friction or spring stiffness
//   joint parent / child   the glTF name of the parent / child link
//   link inertial  mass, volume, centre of mass, any of the 6 inertia entries, or authored/computed
//   link geometry  the digest of the link's solids (link_geometry_digests): their triangles,
//                  vertex positions and placement in the link frame
//   link parent    the glTF name of the link's parent joint ("" for a root)
// Elements are matched by glTF name (the n-th element of a name with the n-th of the same name,
// for names that repeat): a renamed element is one removed and one added.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "rdtf/atomic_file.h"
#include "rdtf/gltf.h"
#include "rdtf/robot.h"

namespace rdtf {

// Everything a delta compares of one link or joint, with both of its names.
struct LinkFacts {
  std::string name;         // glTF name (Robot::links)
  std::string urdf_name;    // Its name in the URDF
  std::string parent_joint; // glTF name of its parent joint; "" for a root
  double mass = 0;          // kg
  double volume = 0;        // m^3
  double center_of_mass[3] = {0, 0, 0};        // m, link frame
  double inertia[6] = {0, 0, 0, 0, 0, 0};      // ixx ixy ixz iyy iyz izz, kg m^2
  bool authored = false;
  std::string geometry;     // link_geometry_digests
};

struct JointFacts {
  std::string name;       // glTF name (Robot::joints)
  std::string urdf_name;  // Its name in the URDF
  std::string type;       // to_string(JointKind)
  std::string parent;     // glTF name of the parent link
  std::string child;      // glTF name of the child link
  double origin[12] = {};  // X_PJ: rotation row by row, then translation
  double axis[3] = {0, 0, 0};
  bool has_limits = false;
  bool has_range = false;             // lower and upper given (JointLimits::position)
  double limits[4] = {0, 0, 0, 0};    // lower, upper, effort, velocity
  double dynamics[3] = {0, 0, 0};     // damping, friction, spring stiffness
};

struct RobotFacts {
  std::vector<LinkFacts> links;    // Robot::links order
  std::vector<JointFacts> joints;  // Robot::joints order
};

// The facts of a robot. `urdf_link_names` / `urdf_joint_names`: the URDF name of each link /
// joint in Robot order, `link_geometry` the digest of each link's geometry (either may be empty:
// the names are then the glTF names, the digests "").
RobotFacts robot_facts(const Robot& robot, const std::vector<std::string>& urdf_link_names,
                       const std::vector<std::string>& urdf_joint_names,
                       const std::vector<std::string>& link_geometry);

// A digest of each link's geometry (Robot::links order): for each solid of the link (its mesh
// nodes, Link::meshes) the node's placement (for a node at or below the link node the local
// transforms below the link node, which an edit upstream leaves alone; else its pose in the link
// frame), the positions and indices of every primitive of its mesh as the mass computation reads
// them (in place as stored; strips, fans and sparse accessors as copied) and, for a skinned mesh, the
// skin's inverse bind matrices. A skinned mesh split among several links counts whole for each of
// them. A scale on the link node or above it is not in the digest; it shows in the inertial.
// `digest` as in atomic_file.h.
std::vector<std::string> link_geometry_digests(const GltfAsset& asset, const Robot& robot,
                                               const ContentDigest& digest);

// Aspects of a change, as bits.
enum DeltaAspect : std::uint32_t {
  kAspectOrigin = 1u << 0,
  kAspectAxis = 1u << 1,
  kAspectType = 1u << 2,
  kAspectLimits = 1u << 3,
  kAspectDynamics = 1u << 4,
  kAspectInertial = 1u << 5,
  kAspectGeometry = 1u << 6,
  kAspectParent = 1u << 7,
  kAspectChild = 1u << 8,
};

// The names of the aspects set in `aspects`, in the order of DeltaAspect ("origin", "axis",
// "type", "limits", "dynamics", "inertial", "geometry", "parent", "child").
std::vector<std::string> aspect_names(std::uint32_t aspects);

struct ElementChange {
  enum class Element { kLink, kJoint };
  enum class Kind { kAdded, kRemoved, kChanged };
  Element element = Element::kLink;
  Kind kind = Kind::kChanged;
  std::string name;       // glTF name
  std::string urdf_name;  // URDF name (of the new revision; of the old one when removed)
  std::uint32_t aspects = 0;  // For kChanged: the DeltaAspect bits, never 0
};

const char* to_string(ElementChange::Element element);
const char* to_string(ElementChange::Kind kind);

// Links first, then joints; within each, removed (old order), changed and added (new order).
// Empty when nothing compared differs.
std::vector<ElementChange> diff_robots(const RobotFacts& before, const RobotFacts& after);

}  // namespace rdtf
