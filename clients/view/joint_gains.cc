#include "joint_gains.h"

#include <cmath>
#include <numbers>
#include <set>

namespace rdtf::view {
namespace {

// A rigid transform X_AB: B's origin and orientation in A.
struct Transform {
  urdf::Vector3 p{0, 0, 0};
  urdf::Rotation R{0, 0, 0, 1};
};

Transform compose(const Transform& X_AB, const urdf::Pose& X_BC) {
  Transform X_AC;
  const urdf::Vector3 p = X_AB.R * X_BC.position;
  X_AC.p = urdf::Vector3(X_AB.p.x + p.x, X_AB.p.y + p.y, X_AB.p.z + p.z);
  X_AC.R = X_AB.R * X_BC.rotation;
  return X_AC;
}

double dot(const urdf::Vector3& a, const urdf::Vector3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// The subtree below `link` (X_JL: link L's frame in the joint frame J) adds its links' inertia.
void add_subtree(const urdf::ModelInterface& model, const urdf::Link& link, const Transform& X_JL, const urdf::Vector3& n_J, bool rotation,
                 std::set<const urdf::Link*>& seen, double& sum) {
  if (!seen.insert(&link).second) return;  // urdfdom builds a tree; never loop on a bad one
  if (const auto& inertial = link.inertial; inertial && inertial->mass > 0) {
    const auto& i = *inertial;
    if (!rotation) {
      sum += i.mass;
    } else {
      const Transform X_JI = compose(X_JL, i.origin);   // I: the inertial frame, at the centre of mass
      const urdf::Vector3 p_JoIo_J = X_JI.p;
      const urdf::Vector3 n_I = X_JI.R.GetInverse() * n_J;
      const double about_com = n_I.x * (i.ixx * n_I.x + i.ixy * n_I.y + i.ixz * n_I.z) +
                               n_I.y * (i.ixy * n_I.x + i.iyy * n_I.y + i.iyz * n_I.z) +
                               n_I.z * (i.ixz * n_I.x + i.iyz * n_I.y + i.izz * n_I.z);
      const double along = dot(p_JoIo_J, n_J);
      const double off_axis_squared = std::max(0.0, dot(p_JoIo_J, p_JoIo_J) - along * along);
      sum += about_com + i.mass * off_axis_squared;  // parallel axis
    }
  }
  for (const auto& joint : link.child_joints) {
    if (!joint) continue;
    if (const auto child = model.getLink(joint->child_link_name)) {
      add_subtree(model, *child, compose(X_JL, joint->parent_to_joint_origin_transform), n_J, rotation, seen, sum);
    }
  }
}

}  // namespace

double moved_inertia(const urdf::ModelInterface& model, const urdf::Joint& joint) {
  const bool rotation = joint.type == urdf::Joint::REVOLUTE || joint.type == urdf::Joint::CONTINUOUS;
  if (!rotation && joint.type != urdf::Joint::PRISMATIC) return 0;
  const auto child = model.getLink(joint.child_link_name);
  if (!child) return 0;
  urdf::Vector3 n = joint.axis;
  const double norm = std::sqrt(dot(n, n));
  if (!(norm > 0)) return 0;
  n = urdf::Vector3(n.x / norm, n.y / norm, n.z / norm);
  // The child link's frame is the joint frame J in the rest pose (URDF: the joint's origin).
  std::set<const urdf::Link*> seen;
  double sum = 0;
  add_subtree(model, *child, Transform{}, n, rotation, seen, sum);
  return sum;
}

Gains gains_for(double moved_inertia, double frequency_hz) {
  const double w = 2 * std::numbers::pi * frequency_hz;
  return Gains{moved_inertia * w * w, 2 * moved_inertia * w};
}

}  // namespace rdtf::view
