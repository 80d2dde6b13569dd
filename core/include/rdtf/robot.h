// The robot that an RDTF document describes: links and joints with frames, limits, dynamics and
// mass properties. One owner (a value), cross references by index. Every element remembers the
// glTF node it came from so that a late error (URDF, ODE) can still name it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rdtf/mass_properties.h"

namespace rdtf {

enum class JointKind { kFixed, kRevolute, kContinuous, kPrismatic, kFloating, kPlanar, kBall };

const char* to_string(JointKind kind);
std::optional<JointKind> joint_kind_from_string(const std::string& text);

enum class InertialSource { kComputed, kAuthored };

// One solid a link's mass comes from: a mesh node (or, for a skinned mesh, its part on a bone).
struct LinkMesh {
  int node = -1;
  double volume = 0;   // m^3, in the link frame (transform applied, inside-out turned right)
  double density = 0;  // kg/m^3
};

struct Link {
  std::string name;
  int node = -1;          // glTF node index of the link node.
  int parent_joint = -1;  // Index into Robot::joints; -1 for a root link.
  std::vector<int> child_joints;
  // Pose of the link frame in the scene frame (the link node's world transform with any scale
  // removed; exactly the node's frame when the node and its ancestors carry no scale).
  Eigen::Isometry3d X_SL = Eigen::Isometry3d::Identity();
  std::vector<LinkMesh> meshes;     // The solids this link's mass comes from.
  MassProperties inertial;          // Centre of mass and inertia in the link frame.
  InertialSource inertial_source = InertialSource::kComputed;
  int inertial_node = -1;           // The inserted (or authored) inertial node.
  // Its rdtf_inertial node extra says otherwise than the extras.RDTF entry that took precedence
  // (warned: RDTF_NODE_EXTRAS_IGNORED); the writer rewrites it.
  bool ignored_inertial_extras = false;
};

struct JointLimits {
  double lower = 0;     // rad or m; meaningful only when `position`
  double upper = 0;     // rad or m; meaningful only when `position`
  double effort = 0;    // N m or N; 0: not given
  double velocity = 0;  // rad/s or m/s; 0: not given
  // Whether lower and upper were given. Effort and speed limits come without a range of motion
  // as often as with one: a wheel's URDF <limit effort velocity/> on a continuous joint, or an
  // rdtf_effort hint alone. Such a joint is not locked at [0, 0]; it turns freely.
  bool position = true;
};

struct Joint {
  std::string name;
  int node = -1;  // glTF node index of the joint node (the one nearest the child link).
  // The node whose frame is the joint frame (the pivot): the joint node nearest the child with a
  // transform of its own or joint properties in its extras, else the child link node.
  int frame_node = -1;
  // Where the properties came from: the node whose extras.RDTF entry (source_is_entry) or node
  // extras held them; -1 when none did (a fixed joint, List 4's default).
  int source_node = -1;
  bool source_is_entry = false;
  // A node whose node-extras joint keys say otherwise than the extras.RDTF entry that took
  // precedence (warned: RDTF_NODE_EXTRAS_IGNORED); -1 when none. The writer rewrites its keys, so
  // that a tool that keeps node extras only (Blender's importer) reads the same joint.
  int ignored_extras_node = -1;
  int parent_link = -1;
  int child_link = -1;
  JointKind kind = JointKind::kFixed;
  // The joint frame is the child link's frame (as in URDF): X_PJ is its pose in the parent link
  // frame at zero joint position. The axis is a unit vector in that frame.
  Eigen::Isometry3d X_PJ = Eigen::Isometry3d::Identity();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
  std::optional<JointLimits> limits;
  double damping = 0;           // N m s/rad or N s/m
  double friction = 0;          // N m or N
  double spring_stiffness = 0;  // N m/rad or N/m
};

// Whether the joint's position is bounded: lower and upper given on a revolute or prismatic
// joint. (A continuous joint is unbounded whatever it carries, as in URDF.)
inline bool position_limited(const Joint& joint) {
  return joint.limits && joint.limits->position &&
         (joint.kind == JointKind::kRevolute || joint.kind == JointKind::kPrismatic);
}

struct Robot {
  std::string name;
  std::vector<Link> links;
  std::vector<Joint> joints;
  std::vector<int> root_links;  // Links with no parent joint, in scene order.
};

}  // namespace rdtf

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/typing.h"

namespace rdtf {

// The node-extras keys (Blender custom properties) that describe a joint.
inline constexpr const char* kJointExtrasKeys[] = {
    "rdtf_joint",   "rdtf_axis",     "rdtf_lower",    "rdtf_upper",           "rdtf_damping",
    "rdtf_friction", "rdtf_effort", "rdtf_velocity", "rdtf_spring_stiffness"};

// True when Blender's glTF exporter wrote the document (asset.generator "Khronos glTF Blender I/O
// ..."): its custom-property vectors were typed in Blender's axes.
bool written_by_blender(const Json& document);

// The asset.generator of a packer that replaces the generator of the file it packs (gltfpack,
// glTF-Transform, draco_transcoder), cut to 80 bytes; nothing for any other tool. Behind it, the
// tool that wrote the model (Blender's axes, its export options) cannot be told.
std::optional<std::string> repacked_by(const Json& document);

// Whether the node's extras vectors (rdtf_axis) are read in Blender's axes: as its rdtf_axes says,
// else when Blender's exporter wrote the document; never for a bone (a skin joint), whose node
// Blender writes in the bone's own axes. An invalid rdtf_axes counts as absent here (build_robot
// reports it).
bool node_extras_in_blender_axes(const Json& document, std::size_t node);

// The extras.RDTF entry of each node (nullptr for none) and its JSON pointer, in one pass over the
// entries. A node listed twice keeps its first entry (typing reports the second as an error).
std::vector<const Json*> rdtf_entries(const Json& document, std::vector<std::string>& pointers);

// Blender's axes (Z up) to glTF's (Y up), as Blender's exporter turns every frame:
// glTF (x, y, z) = Blender (x, z, -y).
Eigen::Matrix3d blender_to_gltf_axes();

// The links and joints of a completed document (mass properties not yet filled in). Joint kinds,
// axes, limits and dynamics come from extras.RDTF, then node extras (docs/format.md lists the
// keys), else a fixed joint as in the paper's List 4.
Robot build_robot(const Json& document, const std::vector<NodeType>& types, std::size_t scene,
                  Diagnostics& diag);

// The link node whose part each node is (-1: none): the nearest link node at or above it, where a
// joint node with joint properties hands what hangs from it to the link it moves (build_robot).
// The meshes, colliders and bodies of a link are those of the nodes it owns.
std::vector<int> owning_link_nodes(const Json& document, const std::vector<NodeType>& types);

// Warnings about a model that converts but is probably not what was meant (docs/format.md,
// "Checks on the modelled robot").
// Empties with children (they look like joints) or a skin, in a typed document (before
// completion) with no rdtf_* property anywhere: the exporter probably left custom properties out.
void check_missing_properties(const Json& document, const std::vector<NodeType>& types,
                              Diagnostics& diag);
// Custom properties that look like rdtf's but are not ("rdft_axis", "rdtf_axes_", "Rdtf_mass"): a
// typo leaves a property out without a word otherwise.
void check_extras_keys(const Json& document, Diagnostics& diag);
// Nodes with rdtf properties in a scene other than the one converted (`scene`, else the first):
// SCENE_NOT_CONVERTED names them and the scene (a robot in scene 1 of a file whose scene 0 is a
// decoy was left out without a word).
void check_other_scenes(const Json& document, std::size_t scene, const std::vector<NodeType>& types,
                        Diagnostics& diag);
// A leaf part typed a link (its node's origin is its joint's) whose mesh a quantizer centred on
// that origin (glTF-Transform's quantize moves a leaf's origin to its mesh's centre):
// JOINT_ORIGIN_QUANTIZED. On the typed document as read, before completion moves meshes.
void check_quantized_joint_origins(const Json& document, const std::vector<NodeType>& types, Diagnostics& diag);
// Extent or masses implausible for metres (a model drawn in millimetres); a link's density beyond
// any solid (g/cm^3 or grams typed); limits typed in node extras in degrees or millimetres; more
// than one root link (an object the modeller did not mean to export).
void check_units(const Json& document, const Robot& robot, Diagnostics& diag);
// NODE_ANIMATED: an animation that takes a node placing the robot (a link, a joint empty, a bone,
// a node above them) away from its rest transform, which is all RDTF describes. Channels whose
// every keyframe holds the rest value (Blender writes one for each bone of an action) move nothing.
void check_animations(const GltfAsset& asset, Diagnostics& diag);

// An error for each link whose mass, centre of mass or inertia is not finite (sizes or densities
// that overflow double precision: a scale of 1e38 on a node and its child). The output would hold
// JSON null in their place. False when there was one.
bool check_finite_inertials(const Json& document, const Robot& robot, Diagnostics& diag);

}  // namespace rdtf
