// The long chains and trees of the dynamics benchmarks (bench/dynamics_bench.cc) as Robot values,
// shared by the benchmarks and the gate's tests (header-only, no test framework: bench/robot_models.cc
// includes it too). Boxes of 0.5 kg, 0.04 x 0.2 x 0.04 m, hanging along -Y from their joint;
// revolute joints 0.2 m apart, about Z and X in turn, limits +-3 rad, damping 0.01 N m s; the root
// link is held by the world. Node indices in creation order (joint node, then its child link).
#pragma once

#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rdtf/robot.h"

namespace rdtf::benchmark_robots {

inline constexpr double kLinkMass = 0.5;    // kg
inline constexpr double kLinkLength = 0.2;  // m between a link's joint and its children's

// A solid box hanging along -Y from its link origin: I_cm = m/12 diag(y^2 + z^2, x^2 + z^2, x^2 + y^2).
inline MassProperties hanging_box() {
  const Eigen::Vector3d size{0.04, 0.2, 0.04};
  MassProperties inertial;
  inertial.mass = kLinkMass;
  inertial.volume = size.prod();
  inertial.center_of_mass = Eigen::Vector3d(0, -kLinkLength / 2, 0);
  const Eigen::Vector3d s2 = size.cwiseProduct(size);
  inertial.inertia = (kLinkMass / 12.0) * Eigen::Vector3d(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y()).asDiagonal();
  return inertial;
}

// `links` links; link l (l >= 1) on joint "joint_<l>" below link parent(l).
template <class Parent>
Robot hanging_boxes(const std::string& name, int links, Parent parent) {
  Robot robot;
  robot.name = name;
  int node = 0;
  Link root;
  root.name = "link_0";
  root.node = node++;
  root.inertial = hanging_box();
  root.inertial_source = InertialSource::kAuthored;
  robot.links.push_back(root);
  robot.root_links.push_back(0);
  for (int l = 1; l < links; ++l) {
    const int p = parent(l);
    Joint joint;
    joint.name = "joint_" + std::to_string(l);
    joint.node = node++;
    joint.kind = JointKind::kRevolute;
    joint.parent_link = p;
    joint.child_link = l;
    joint.X_PJ = Eigen::Isometry3d(Eigen::Translation3d(0, -kLinkLength, 0));
    joint.axis = l % 2 == 0 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    joint.limits = JointLimits{-3.0, 3.0, 0, 0};
    joint.damping = 0.01;
    Link link;
    link.name = "link_" + std::to_string(l);
    link.node = node++;
    link.parent_joint = static_cast<int>(robot.joints.size());
    link.inertial = hanging_box();
    link.inertial_source = InertialSource::kAuthored;
    link.X_SL = robot.links[p].X_SL * joint.X_PJ;
    robot.links[p].child_joints.push_back(link.parent_joint);
    robot.joints.push_back(joint);
    robot.links.push_back(link);
  }
  return robot;
}

// A serial chain: link l hangs from link l - 1.
inline Robot chain_robot(int links) {
  return hanging_boxes("chain_" + std::to_string(links), links, [](int l) { return l - 1; });
}

// A binary tree: link l hangs from link (l - 1) / 2; about seven levels deep for 100 links.
inline Robot tree_robot(int links) {
  return hanging_boxes("tree_" + std::to_string(links), links, [](int l) { return (l - 1) / 2; });
}

}  // namespace rdtf::benchmark_robots
