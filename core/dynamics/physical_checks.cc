// Physical checks of a robot before it is simulated (docs/dynamics.md, "Physical checks").
#include <cmath>

#include <Eigen/Eigenvalues>
#include <numbers>

#include "ode_model.h"

namespace rdtf {
namespace {

using dynamics_internal::number;
using dynamics_internal::vector_text;

std::string where(const Link& link) { return dynamics_internal::node_pointer(link.node); }
std::string where(const Joint& joint) { return dynamics_internal::node_pointer(joint.node); }

void check_roots(const Robot& robot, Diagnostics& diag) {
  std::vector<int> roots;
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    if (robot.links[l].parent_joint < 0) roots.push_back(static_cast<int>(l));
  }
  if (robot.links.empty()) {
    diag.error("ROBOT_NO_LINKS", "", "the robot has no links: nothing to simulate");
    return;
  }
  if (roots.size() < 2) return;
  std::string names;
  for (int r : roots) names += (names.empty() ? "'" : ", '") + robot.links[r].name + "'";
  diag.error("ROBOT_MULTIPLE_ROOTS", where(robot.links[roots[1]]),
             std::to_string(roots.size()) + " root links (" + names +
                 "): one robot has one root; join the others to it with joints");
  const std::vector<int> order = dynamics_internal::tree_order(robot);
  const std::vector<int> root = dynamics_internal::root_of(robot, order);
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    if (root[l] == roots[0]) continue;
    diag.error("LINK_NOT_CONNECTED", where(robot.links[l]),
               "link '" + robot.links[l].name + "' is not connected to the root link '" +
                   robot.links[roots[0]].name + "' (its tree's root is '" +
                   robot.links[root[l]].name + "')");
  }
}

void check_mass(const Robot& robot, std::size_t l, const std::vector<int>& carrier,
                const PhysicalCheckOptions& options, Diagnostics& diag) {
  const Link& link = robot.links[l];
  const double mass = link.inertial.mass;
  const std::string name = "link '" + link.name + "': ";
  if (!std::isfinite(mass)) {
    diag.error("LINK_MASS_NOT_FINITE", where(link), name + "mass " + number(mass) + " is not finite");
  } else if (mass < 0) {
    diag.error("LINK_MASS_NEGATIVE", where(link), name + "mass " + number(mass) + " kg is negative");
  } else if (mass == 0 && !link.inertial.inertia.isZero(0)) {
    diag.error("LINK_MASSLESS_WITH_INERTIA", where(link),
               name + "mass is 0 but its inertia is not zero (largest moment " +
                   number(link.inertial.inertia.cwiseAbs().maxCoeff()) + " kg m^2)");
  } else if (mass == 0) {
    const int c = carrier[l];
    if (c == dynamics_internal::kUnresolved) {
      const std::string how = link.parent_joint < 0
                                  ? std::string(options.floating_root ? "is a floating root" : "is a root")
                                  : "moves on joint '" + robot.joints[link.parent_joint].name + "' (" +
                                        to_string(robot.joints[link.parent_joint].kind) + ")";
      diag.error("LINK_MASS_ZERO", where(link),
                 name + "mass is 0 and the link " + how +
                     " without being fixed to a link with mass: a body without mass cannot move "
                     "(give it mass, e.g. rdtf_mass, or make its joint fixed)");
    } else {
      diag.info("LINK_MASSLESS", where(link),
                name + "has no mass; it is carried by " +
                    (c == dynamics_internal::kWorld ? std::string("the world")
                                                    : "link '" + robot.links[c].name + "'") +
                    " (fixed joints)");
    }
  }
}

// The smallest polar moment (integral of r^2 dm about the centre of mass) the link's solids can
// have: a solid of volume V and mass m has at least that of a ball, 3/5 m R^2.
double polar_lower_bound(const Link& link) {
  double mass = 0;
  double bound = 0;
  for (const LinkMesh& mesh : link.meshes) {
    if (!(mesh.volume > 0) || !(mesh.density > 0)) continue;
    const double m = mesh.density * mesh.volume;
    const double radius = std::cbrt(3 * mesh.volume / (4 * std::numbers::pi));
    mass += m;
    bound += 0.6 * m * radius * radius;
  }
  if (!(mass > 0)) return 0;
  return bound * (link.inertial.mass / mass);  // rdtf_mass on a link rescales its inertia so
}

void check_inertia(const Link& link, const PhysicalCheckOptions& options, Diagnostics& diag) {
  const Eigen::Matrix3d& I = link.inertial.inertia;
  const std::string name = "link '" + link.name + "': ";
  if (!I.allFinite()) {
    diag.error("LINK_INERTIA_NOT_FINITE", where(link), name + "inertia is not finite");
    return;
  }
  const double largest = I.cwiseAbs().maxCoeff();
  const double asymmetry = (I - I.transpose()).cwiseAbs().maxCoeff();
  if (asymmetry > options.symmetry_tolerance * largest) {
    diag.error("LINK_INERTIA_NOT_SYMMETRIC", where(link),
               name + "inertia is not symmetric: |I - I^T| reaches " + number(asymmetry) +
                   " kg m^2 (largest entry " + number(largest) + ")");
    return;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(0.5 * (I + I.transpose()),
                                                              Eigen::EigenvaluesOnly);
  const Eigen::Vector3d moments = solver.eigenvalues();  // ascending
  const double a = moments[0], b = moments[1], c = moments[2];
  const std::string principal = "principal moments " + vector_text(moments) + " kg m^2";
  if (!(a > 0)) {
    diag.error("LINK_INERTIA_NOT_POSITIVE_DEFINITE", where(link),
               name + "inertia is not positive definite: " + principal);
    return;
  }
  if (a + b < c - options.triangle_tolerance * (a + b + c)) {
    diag.error("LINK_INERTIA_TRIANGLE_INEQUALITY", where(link),
               name + "inertia breaks the triangle inequality A + B >= C of a real body: " +
                   principal + ", A + B = " + number(a + b) + " < C = " + number(c));
  }
  if (link.inertial_source == InertialSource::kComputed) {
    const double polar = 0.5 * I.trace();
    const double bound = polar_lower_bound(link);
    if (polar < bound * (1 - options.solid_bound_tolerance)) {
      diag.error("LINK_INERTIA_BELOW_SOLID_BOUND", where(link),
                 name + "polar moment tr(I)/2 = " + number(polar) +
                     " kg m^2 is below " + number(bound) +
                     ", the least any solid of its volume and mass can have (a ball's)");
    }
  }
}

void check_center_of_mass(const Link& link, const std::optional<Eigen::AlignedBox3d>& box,
                          const PhysicalCheckOptions& options, Diagnostics& diag) {
  const Eigen::Vector3d& com = link.inertial.center_of_mass;
  const std::string name = "link '" + link.name + "': ";
  if (!com.allFinite()) {
    diag.error("LINK_COM_NOT_FINITE", where(link), name + "centre of mass is not finite");
    return;
  }
  if (!box || box->isEmpty() || link.inertial.mass <= 0) return;
  const double outside = box->exteriorDistance(com);
  if (outside <= options.geometry_tolerance * box->diagonal().norm()) return;
  const std::string message = name + "centre of mass " + vector_text(com) + " m (link frame) is " +
                              number(outside) + " m outside the bounds " +
                              vector_text(box->min()) + " - " + vector_text(box->max()) +
                              " of its geometry";
  if (link.inertial_source == InertialSource::kComputed) {
    diag.error("LINK_COM_OUTSIDE_GEOMETRY", where(link), message);
  } else {
    diag.warning("LINK_COM_OUTSIDE_GEOMETRY", where(link), message + " (authored inertial)");
  }
}

void check_joint(const Robot& robot, const Joint& joint, const PhysicalCheckOptions& options,
                 Diagnostics& diag) {
  const std::string name = "joint '" + joint.name + "' (" + to_string(joint.kind) + "): ";
  if (!joint.X_PJ.matrix().allFinite()) {
    diag.error("JOINT_POSE_NOT_FINITE", where(joint), name + "origin is not finite");
  }
  const bool has_axis = dynamics_internal::one_dof(joint.kind) || joint.kind == JointKind::kPlanar;
  if (has_axis) {
    const double norm = joint.axis.norm();
    if (!joint.axis.allFinite()) {
      diag.error("JOINT_AXIS_NOT_FINITE", where(joint), name + "axis is not finite");
    } else if (norm < 1e-12) {
      diag.error("JOINT_AXIS_ZERO", where(joint),
                 name + "axis " + vector_text(joint.axis) + " is zero: it has no direction");
    } else if (std::abs(norm - 1) > 1e-6) {
      diag.warning("JOINT_AXIS_NOT_UNIT", where(joint),
                   name + "axis " + vector_text(joint.axis) + " has length " + number(norm) +
                       "; it is normalized");
    }
  }
  if (joint.limits && (joint.kind == JointKind::kRevolute || joint.kind == JointKind::kPrismatic)) {
    const JointLimits& limits = *joint.limits;
    if (!std::isfinite(limits.lower) || !std::isfinite(limits.upper)) {
      diag.error("JOINT_LIMITS_NOT_FINITE", where(joint),
                 name + "limits [" + number(limits.lower) + ", " + number(limits.upper) + "] are not finite");
    } else if (limits.lower > limits.upper) {
      diag.error("JOINT_LIMITS_INVERTED", where(joint),
                 name + "lower limit " + number(limits.lower) + " is above the upper limit " +
                     number(limits.upper));
    } else if (limits.lower > 0 || limits.upper < 0) {
      diag.warning("JOINT_REST_OUTSIDE_LIMITS", where(joint),
                   name + "the rest pose (position 0) is outside the limits [" +
                       number(limits.lower) + ", " + number(limits.upper) +
                       "]; simulations start at the nearest limit");
    }
  }
  const auto check_value = [&](const char* what, double value) {
    if (!std::isfinite(value) || value < 0) {
      diag.error("JOINT_DYNAMICS_INVALID", where(joint),
                 name + what + " " + number(value) + " must be finite and not negative");
    }
  };
  check_value("damping", joint.damping);
  check_value("friction", joint.friction);
  check_value("spring stiffness", joint.spring_stiffness);
  if (joint.limits) {
    check_value("effort limit", joint.limits->effort);
    check_value("velocity limit", joint.limits->velocity);
  }
  const Link& parent = robot.links[joint.parent_link];
  const Link& child = robot.links[joint.child_link];
  const double mp = parent.inertial.mass, mc = child.inertial.mass;
  if (std::isfinite(mp) && std::isfinite(mc) && mp > 0 && mc > 0) {
    const double ratio = std::max(mp, mc) / std::min(mp, mc);
    if (ratio > options.max_mass_ratio) {
      diag.error("JOINT_MASS_RATIO", where(joint),
                 name + "joins '" + parent.name + "' (" + number(mp) + " kg) and '" + child.name +
                     "' (" + number(mc) + " kg): mass ratio " + number(ratio) +
                     " is above the bound " + number(options.max_mass_ratio) +
                     " (ODE goes unstable)");
    }
  }
}

}  // namespace

void check_physics(const Robot& robot, const PhysicalCheckOptions& options, const LinkBounds* bounds,
                   Diagnostics& diag) {
  if (!dynamics_internal::check_structure(robot, "ROBOT_INVALID_REFERENCE", diag)) return;
  check_roots(robot, diag);
  const std::vector<int> carrier = dynamics_internal::carriers(robot, options.floating_root);
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    if (!link.X_SL.matrix().allFinite()) {
      diag.error("LINK_POSE_NOT_FINITE", where(link), "link '" + link.name + "': pose is not finite");
    }
    check_mass(robot, l, carrier, options, diag);
    if (std::isfinite(link.inertial.mass) && link.inertial.mass > 0) check_inertia(link, options, diag);
    const std::optional<Eigen::AlignedBox3d> none;
    check_center_of_mass(link, bounds && l < bounds->size() ? (*bounds)[l] : none, options, diag);
  }
  for (const Joint& joint : robot.joints) check_joint(robot, joint, options, diag);
}

}  // namespace rdtf
