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
// meaning in a scaled frame, so the axes are the node's with scale removed: the orthogonal factor
// of its world map, a mirror kept (the tensor in a mirrored node's own axes; the link frame's
// rotation put a mirrored wheel's spin moment on the wrong axis: s101fmt D2).
struct MotionFrame {
  Eigen::Affine3d X_NL;  // Link frame -> node coordinates (points).
  Eigen::Matrix3d R_NL;  // Link frame axes -> node axes with scale removed (tensors; det -1 under a mirror).
};

inline MotionFrame motion_frame(const std::vector<Eigen::Affine3d>& X_SN, const Link& link) {
  const Eigen::Affine3d& X_SNode = X_SN[static_cast<std::size_t>(link.node)];
  MotionFrame frame;
  frame.X_NL = X_SNode.inverse() * Eigen::Affine3d(link.X_SL.matrix());
  frame.R_NL = orthogonal_part(X_SNode.linear()).transpose() * link.X_SL.linear();
  return frame;
}

}  // namespace rdtf
