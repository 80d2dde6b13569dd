// Frames shared by reading and writing KHR_physics_rigid_bodies motion.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rdtf/geometry.h"
#include "rdtf/robot.h"

namespace rdtf {

// The draft puts centerOfMass in node space (the link node's local coordinates, its scale
// included) and turns the principal axes into node space by inertiaOrientation. A tensor has no
// meaning in a scaled frame, so the axes are the node's with scale removed (its rotation).
struct MotionFrame {
  Eigen::Affine3d X_NL;  // Link frame -> node coordinates (points).
  Eigen::Matrix3d R_NL;  // Link frame axes -> node axes with scale removed (tensors).
};

inline MotionFrame motion_frame(const std::vector<Eigen::Affine3d>& X_SN, const Link& link) {
  const Eigen::Affine3d& X_SNode = X_SN[static_cast<std::size_t>(link.node)];
  MotionFrame frame;
  frame.X_NL = X_SNode.inverse() * Eigen::Affine3d(link.X_SL.matrix());
  frame.R_NL = rigid_part(X_SNode).linear().transpose() * link.X_SL.linear();
  return frame;
}

}  // namespace rdtf
