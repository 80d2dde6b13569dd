// Physical checks of a robot before it is simulated (docs/dynamics.md, "Physical checks").
#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <numbers>
#include <string_view>

#include "ode_model.h"
#include "rdtf/diagnostic_codes.h"

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
    diag.error(codes::ROBOT_NO_LINKS, "", "the robot has no links: nothing to simulate");
    return;
  }
  if (roots.size() < 2) return;
  std::string names;
  for (int r : roots) names += (names.empty() ? "'" : ", '") + robot.links[r].name + "'";
  diag.error(codes::ROBOT_MULTIPLE_ROOTS, where(robot.links[roots[1]]),
             std::to_string(roots.size()) + " root links (" + names +
                 "): one robot has one root; join the others to it with joints");
  const std::vector<int> order = dynamics_internal::tree_order(robot);
  const std::vector<int> root = dynamics_internal::root_of(robot, order);
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    if (root[l] == roots[0]) continue;
    diag.error(codes::LINK_NOT_CONNECTED, where(robot.links[l]),
               "link '" + robot.links[l].name + "' is not connected to the root link '" +
                   robot.links[roots[0]].name + "' (its tree's root is '" +
                   robot.links[root[l]].name + "')");
  }
}

using dynamics_internal::WeldGroup;
using dynamics_internal::WeldGroups;

// "link 'T'" or "link 'T' and the N links fixed to it".
std::string body_text(const Robot& robot, const WeldGroup& group) {
  std::string text = "link '" + robot.links[group.top].name + "'";
  if (group.links.size() > 1) text += " and the " + std::to_string(group.links.size() - 1) + " links fixed to it";
  return text;
}

void check_mass(const Robot& robot, std::size_t l, const WeldGroups& welds, const PhysicalCheckOptions& options,
                Diagnostics& diag) {
  const Link& link = robot.links[l];
  const WeldGroup& group = welds.groups[welds.group_of[l]];
  const double mass = link.inertial.mass;
  const std::string name = "link '" + link.name + "': ";
  if (!std::isfinite(mass)) {
    diag.error(codes::LINK_MASS_NOT_FINITE, where(link), name + "mass " + number(mass) + " is not finite");
  } else if (mass < 0) {
    diag.error(codes::LINK_MASS_NEGATIVE, where(link), name + "mass " + number(mass) + " kg is negative");
  } else if (mass == 0 && !link.inertial.inertia.isZero(0)) {
    const std::string message = name + "mass is 0 but its inertia is not zero (largest moment " +
                                number(link.inertial.inertia.cwiseAbs().maxCoeff()) + " kg m^2)";
    if (group.welded_to_world) {
      // Welded to the world it never moves: neither its mass nor its inertia is used.
      diag.warning(codes::LINK_MASSLESS_WITH_INERTIA, where(link),
                   message + "; it is welded to the world and never moves, so its inertia is not used");
    } else if (group.merged.mass > 0) {
      diag.warning(codes::LINK_MASSLESS_WITH_INERTIA, where(link),
                   message + "; it is welded (fixed joints) into the body of " + body_text(robot, group) +
                       ", whose inertia it adds to (as MuJoCo's fusestatic does)");
    } else {
      diag.error(codes::LINK_MASSLESS_WITH_INERTIA, where(link), message);
    }
  } else if (mass == 0) {
    if (group.welded_to_world) {
      diag.info(codes::LINK_MASSLESS, where(link), name + "has no mass; the world holds it (fixed joints)");
    } else if (group.bounded) {
      // Alone in its body, it moves on its joint; with links fixed to it, with them (none has mass).
      const std::string how = group.links.size() > 1 ? "moves with " + body_text(robot, group) + ", which have none"
                              : link.parent_joint >= 0
                                  ? "moves on joint '" + robot.joints[link.parent_joint].name + "' (" +
                                        to_string(robot.joints[link.parent_joint].kind) + ")"
                                  : std::string("is a floating root");
      const std::string message = name + "has no mass and " + how + ": simulated with the bound mass " +
                                  number(options.bound_mass) + " kg and inertia " +
                                  number(options.bound_inertia) + " kg m^2";
      if (options.massless_link_error) {
        diag.error(codes::LINK_MASS_ZERO, where(link), message + " (massless moving links are errors by option)");
      } else {
        diag.warning(codes::LINK_MASS_ZERO, where(link), message);
      }
    } else if (group.merged.mass > 0) {
      diag.info(codes::LINK_MASSLESS, where(link),
                name + "has no mass; it is welded (fixed joints) into the body of " + body_text(robot, group));
    } else {
      const std::string how = link.parent_joint < 0
                                  ? std::string(options.floating_root ? "is a floating root" : "is a root")
                                  : "moves on joint '" + robot.joints[link.parent_joint].name + "' (" +
                                        to_string(robot.joints[link.parent_joint].kind) + ")";
      const Link& top = robot.links[group.top];
      const std::string on = group.top == static_cast<int>(l) || top.parent_joint < 0
                                 ? std::string()
                                 : " with link '" + top.name + "' on joint '" +
                                       robot.joints[top.parent_joint].name + "'";
      diag.error(codes::LINK_MASS_ZERO, where(link),
                 name + "mass is 0 and the link " + (group.top == static_cast<int>(l) ? how : "moves" + on) +
                     " without being fixed to a link with mass: a body without mass cannot move "
                     "(give it mass, e.g. rdtf_mass, or make its joint fixed; or simulate it with a "
                     "bound mass and inertia: rdtf validate --bound-mass KG --bound-inertia KGM2, "
                     "rdtfd bound_mass_kg and bound_inertia_kgm2)");
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

// Symmetry, positive definiteness and the triangle inequality of I; each failure goes to
// `report(code, message, triangle_breach)`, the last C - (A + B) when the principal moments break
// A + B >= C beyond triangle_tolerance (a negative moment does too), as MuJoCo judges every link,
// else 0. False when the moments could not be judged further.
template <typename Report>
bool principal_moments_check(const Eigen::Matrix3d& I, const std::string& name, const PhysicalCheckOptions& options,
                             const Report& report) {
  const double largest = I.cwiseAbs().maxCoeff();
  const double asymmetry = (I - I.transpose()).cwiseAbs().maxCoeff();
  if (asymmetry > options.symmetry_tolerance * largest) {
    report(codes::LINK_INERTIA_NOT_SYMMETRIC,
           name + "inertia is not symmetric: |I - I^T| reaches " + number(asymmetry) + " kg m^2 (largest entry " +
               number(largest) + ")",
           0.0);
    return false;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(0.5 * (I + I.transpose()), Eigen::EigenvaluesOnly);
  const Eigen::Vector3d moments = solver.eigenvalues();  // ascending
  const double a = moments[0], b = moments[1], c = moments[2];
  const std::string principal = "principal moments " + vector_text(moments) + " kg m^2";
  const bool breaks_triangle = a + b < c - options.triangle_tolerance * (std::abs(a) + b + c);
  const double breach = breaks_triangle ? c - (a + b) : 0.0;
  if (!(a > 0)) {
    report(codes::LINK_INERTIA_NOT_POSITIVE_DEFINITE,
           name + "inertia is not positive definite: " + principal +
               (breaks_triangle ? ", A + B = " + number(a + b) + " < C = " + number(c) : std::string()),
           breach);
    return false;
  }
  if (!(a > options.positive_definite_tolerance * c)) {
    report(codes::LINK_INERTIA_NOT_POSITIVE_DEFINITE,
           name + "inertia is singular to within rounding: " + principal + ", the smallest " + number(a / c) +
               " of the largest, at most positive_definite_tolerance " + number(options.positive_definite_tolerance) +
               " (an ideal rod's; no real part is that thin)",
           0.0);
    return false;
  }
  if (breaks_triangle) {
    report(codes::LINK_INERTIA_TRIANGLE_INEQUALITY,
           name + "inertia breaks the triangle inequality A + B >= C of a real body: " + principal +
               ", A + B = " + number(a + b) + " < C = " + number(c),
           breach);
  }
  return true;
}

// The body a moving weld group makes: what the simulation moves, so what must be a real body.
void check_combined_inertia(const Robot& robot, const WeldGroup& group, const PhysicalCheckOptions& options,
                            Diagnostics& diag) {
  if (group.links.size() < 2 || group.welded_to_world || group.bounded || !(group.merged.mass > 0) ||
      !group.merged.inertia.allFinite()) {
    return;
  }
  // With one link of mass or inertia the combined body is that link's, checked on its own.
  if (dynamics_internal::adding_links(robot, group) < 2) return;
  const Link& top = robot.links[group.top];
  principal_moments_check(group.merged.inertia, body_text(robot, group) + " (welded by fixed joints): combined ",
                          options, [&](const char* code, const std::string& message, double) {
                            diag.error(code, where(top), message);
                          });
}

void check_inertia(const Robot& robot, const Link& link, const WeldGroup& group, double extent,
                   const PhysicalCheckOptions& options, Diagnostics& diag) {
  const Eigen::Matrix3d& I = link.inertial.inertia;
  const std::string name = "link '" + link.name + "': ";
  if (!I.allFinite()) {
    diag.error(codes::LINK_INERTIA_NOT_FINITE, where(link), name + "inertia is not finite");
    return;
  }
  // Welded (fixed joints) to other links that add mass or inertia, or to the world, a link is no
  // body of its own: the simulation moves the body of the links welded together, whose combined
  // tensor is checked (check_combined_inertia), as MuJoCo's fusestatic (its default for URDF) and
  // Gazebo do, or nothing. That holds for the link a joint moves too (finger_edu's thin rod with
  // its fingertip welded on: MuJoCo loads it).
  const bool in_body = group.welded_to_world || dynamics_internal::adding_links(robot, group) >= 2;
  // A point mass (a sensor frame of a gram) is a sound part of a rigid body: it only adds m d^2
  // to the body's inertia. Alone on a joint it cannot turn.
  const bool point_mass = dynamics_internal::is_point_mass(link.inertial, extent);
  if (point_mass && in_body) {
    diag.info(codes::LINK_POINT_MASS, where(link),
              name + "a point mass (" +
                  (I.isZero(0) ? std::string("zero inertia")
                               : "inertia zero to rounding: its largest entry " + number(I.cwiseAbs().maxCoeff()) +
                                     " kg m^2 is below 4 eps m l^2 = " +
                                     number(4 * std::numeric_limits<double>::epsilon() * link.inertial.mass * extent * extent) +
                                     ", l = " + number(extent) + " m the robot's extent") +
                  "), welded (fixed joints) into the body of " +
                  (group.welded_to_world ? std::string("the world") : body_text(robot, group)));
    return;
  }
  // In a body, a tensor no real part has (a published 1 mg antenna's, a sensor frame's rounding
  // noise, an ideal rod's) is a warning; a tool that keeps every link a body (Drake) refuses it.
  // Alone, the link is the body: an error.
  if (point_mass) {
    diag.error(codes::LINK_INERTIA_NOT_POSITIVE_DEFINITE, where(link),
               name + "inertia is zero" + (I.isZero(0) ? std::string() : " to rounding (every entry within 4 eps m l^2)") +
                   ": a point mass of " + number(link.inertial.mass) +
                   " kg, and nothing welded to it adds inertia, so its joint turns a body without rotational "
                   "inertia; give it the inertia of its part");
    return;
  }
  // But a broken triangle inequality in a body that moves is an error, on the link a joint moves
  // and on a link welded to it alike, whether or not a moment is also negative: MuJoCo checks every
  // link's authored tensor for it before fusing welded links in (it refuses allegro_right_hand's
  // fingers, whose tips are welded on, a tool welded to a sound arm, and ur5_robotiq_85's 1 kg
  // finger pads of six entries 1e-10, moments 0, 0, 3e-10), though it accepts a singular one it
  // then fuses (finger_edu). The breach is judged on the link's own moments (triangle_tolerance x
  // (|A| + B + C)), never against the body around it, whose size says nothing of the part's
  // tensor, and must pass kTriangleNoise: a breach below 1e-12 kg m^2, the moment of a milligram a
  // millimetre from its axis, changes no robot (an exporter's residue a hundred times the
  // point-mass bound, iCub's ixz of 4.8e-15; MuJoCo too loads a lone product of 8e-13 and refuses
  // 1e-12). Welded to the world, the part never moves: a warning (TIAGo's antenna).
  constexpr double kTriangleNoise = 1e-12;  // kg m^2
  const auto report = [&](const char* code, const std::string& message, double triangle_breach) {
    if (!in_body) {
      diag.error(code, where(link), message);
      return;
    }
    const std::string welded =
        "; it is welded (fixed joints) into " +
        (group.welded_to_world ? std::string("the world, and never moves")
                               : "the body of " + body_text(robot, group) + ", whose combined inertia is what moves");
    if (!group.welded_to_world && triangle_breach > kTriangleNoise) {
      diag.error(code, where(link),
                 message + welded + ", but MuJoCo refuses a link whose moments break A + B >= C before it fuses it "
                 "into its body; give the part its real inertia");
      return;
    }
    diag.warning(code, where(link),
                 message + welded +
                     (triangle_breach > kTriangleNoise
                          ? " (its moments break A + B >= C, and MuJoCo refuses it: it checks every link before it "
                            "fuses welded ones)"
                      : triangle_breach > 0 ? " (its moments break A + B >= C by " + number(triangle_breach) +
                                                  " kg m^2, below 1e-12, a residue that changes no robot)"
                                            : " (a simulator that keeps each link a body refuses it)"));
  };
  if (!principal_moments_check(I, name, options, report)) return;
  if (link.inertial_source == InertialSource::kComputed) {
    const double polar = 0.5 * I.trace();
    const double bound = polar_lower_bound(link);
    if (polar < bound * (1 - options.solid_bound_tolerance)) {
      diag.error(codes::LINK_INERTIA_BELOW_SOLID_BOUND, where(link),
                 name + "polar moment tr(I)/2 = " + number(polar) +
                     " kg m^2 is below " + number(bound) +
                     ", the least any solid of its volume and mass can have (a ball's). A mass computed from "
                     "meshes falls below it only when some volume is counted twice: parts that overlap inside one "
                     "mesh (objects joined in Blender with Ctrl+J), or a shell inside another wound the same way. "
                     "Keep such parts separate objects, or unite them (Boolean Union)");
    }
  }
}

void check_center_of_mass(const Link& link, const std::optional<Eigen::AlignedBox3d>& box,
                          const PhysicalCheckOptions& options, Diagnostics& diag) {
  const Eigen::Vector3d& com = link.inertial.center_of_mass;
  const std::string name = "link '" + link.name + "': ";
  if (!com.allFinite()) {
    diag.error(codes::LINK_COM_NOT_FINITE, where(link), name + "centre of mass is not finite");
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
    diag.error(codes::LINK_COM_OUTSIDE_GEOMETRY, where(link), message);
  } else {
    diag.warning(codes::LINK_COM_OUTSIDE_GEOMETRY, where(link), message + " (authored inertial)");
  }
}

// An authored inertia no mass inside the link's geometry can have: about the centre of mass c,
// tr(I)/2 = integral of |p - c|^2 dm <= m R^2, R the farthest corner of the geometry's bounds from c.
// A CAD export in kg mm^2 read as kg m^2 is 1e6 times too large, and its link barely moves, so the
// run tests nothing. A warning, and only beyond options.inertia_geometry_factor times the bound:
// the geometry may be a simplified visual smaller than the body. (Computed inertials are integrals
// over that geometry, inside by construction.)
void check_inertia_within_geometry(const Link& link, const std::optional<Eigen::AlignedBox3d>& box,
                                   const PhysicalCheckOptions& options, Diagnostics& diag) {
  const MassProperties& inertial = link.inertial;
  if (link.inertial_source == InertialSource::kComputed || !box || box->isEmpty() || !(inertial.mass > 0) ||
      !std::isfinite(inertial.mass) || !inertial.center_of_mass.allFinite() || !inertial.inertia.allFinite()) {
    return;
  }
  double reach_squared = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const auto which = static_cast<Eigen::AlignedBox3d::CornerType>(corner);
    reach_squared = std::max(reach_squared, (box->corner(which) - inertial.center_of_mass).squaredNorm());
  }
  const double polar = 0.5 * inertial.inertia.trace();
  const double bound = inertial.mass * reach_squared;
  if (polar <= options.inertia_geometry_factor * bound) return;
  diag.warning(codes::LINK_INERTIA_ABOVE_GEOMETRY_BOUND, where(link),
               "link '" + link.name + "': polar moment tr(I)/2 = " + number(polar) + " kg m^2 is " +
                   number(polar / bound) + " times " + number(bound) + " kg m^2, the most " + number(inertial.mass) +
                   " kg inside the bounds " + vector_text(box->min()) + " - " + vector_text(box->max()) +
                   " of its geometry can have about its centre of mass (m R^2, R = " + number(std::sqrt(reach_squared)) +
                   " m to the farthest corner; warned beyond " + number(options.inertia_geometry_factor) +
                   " times) (authored inertial): an inertia in kg mm^2 or g cm^2 written as kg m^2 is 1e6 or 1e7 "
                   "times too large, a placeholder inertia far from the body's, and the link moves unlike the body");
}

void check_joint(const Robot& robot, const Joint& joint, const WeldGroups& welds, int largest_island,
                 const PhysicalCheckOptions& options, Diagnostics& diag) {
  const std::string name = "joint '" + joint.name + "' (" + to_string(joint.kind) + "): ";
  if (!joint.X_PJ.matrix().allFinite()) {
    diag.error(codes::JOINT_POSE_NOT_FINITE, where(joint), name + "origin is not finite");
  }
  const bool has_axis = dynamics_internal::one_dof(joint.kind) || joint.kind == JointKind::kPlanar;
  if (has_axis) {
    const double norm = joint.axis.norm();
    if (!joint.axis.allFinite()) {
      diag.error(codes::JOINT_AXIS_NOT_FINITE, where(joint), name + "axis is not finite");
    } else if (norm < 1e-12) {
      diag.error(codes::JOINT_AXIS_ZERO, where(joint),
                 name + "axis " + vector_text(joint.axis) + " is zero: it has no direction");
    } else if (std::abs(norm - 1) > 1e-6) {
      diag.warning(codes::JOINT_AXIS_NOT_UNIT, where(joint),
                   name + "axis " + vector_text(joint.axis) + " has length " + number(norm) +
                       "; it is normalized");
    }
  }
  if (position_limited(joint)) {
    const JointLimits& limits = *joint.limits;
    if (!std::isfinite(limits.lower) || !std::isfinite(limits.upper)) {
      diag.error(codes::JOINT_LIMITS_NOT_FINITE, where(joint),
                 name + "limits [" + number(limits.lower) + ", " + number(limits.upper) + "] are not finite");
    } else if (limits.lower > limits.upper) {
      diag.error(codes::JOINT_LIMITS_INVERTED, where(joint),
                 name + "lower limit " + number(limits.lower) + " is above the upper limit " +
                     number(limits.upper));
    } else if (limits.lower > 0 || limits.upper < 0) {
      diag.warning(codes::JOINT_REST_OUTSIDE_LIMITS, where(joint),
                   name + "the rest pose (position 0) is outside the limits [" +
                       number(limits.lower) + ", " + number(limits.upper) +
                       "]; simulations start at the nearest limit");
    }
  }
  const auto check_value = [&](const char* what, double value) {
    if (!std::isfinite(value) || value < 0) {
      diag.error(codes::JOINT_DYNAMICS_INVALID, where(joint),
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
  // The ratio ODE sees is that of the two bodies a moving joint connects: each link with those
  // welded to it. A fixed joint is inside one body, and the world, holding a body, has no mass.
  if (joint.kind == JointKind::kFixed) return;
  const WeldGroup& parent = welds.groups[welds.group_of[joint.parent_link]];
  const WeldGroup& child = welds.groups[welds.group_of[joint.child_link]];
  if (parent.welded_to_world || child.welded_to_world) return;
  // dWorldStep holds joints between bodies of any ratio (it solves each island exactly): judged
  // only where QuickStep's run is the verdict. The stepper is one for the whole world, chosen by
  // its largest island, so every joint is judged when that island is.
  if (largest_island < options.mass_ratio_island_bodies) return;
  const double mp = parent.merged.mass, mc = child.merged.mass;
  if (std::isfinite(mp) && std::isfinite(mc) && mp > 0 && mc > 0) {
    const double ratio = std::max(mp, mc) / std::min(mp, mc);
    if (ratio > options.max_mass_ratio) {
      diag.error(codes::JOINT_MASS_RATIO, where(joint),
                 name + "joins " + body_text(robot, parent) + " (" + number(mp) + " kg) and " +
                     body_text(robot, child) + " (" + number(mc) + " kg): mass ratio " + number(ratio) +
                     " is above the bound " + number(options.max_mass_ratio) + " (max_mass_ratio): QuickStep, " +
                     "whose run is the verdict for this model (its largest island has " + std::to_string(largest_island) +
                     " moving bodies), does not hold joints between bodies this unequal; make the masses "
                     "closer, raise the bound, or step the model with dWorldStep (exact, slower for large islands)");
    }
  }
}

}  // namespace

void check_physics(const Robot& robot, const PhysicalCheckOptions& options, const LinkBounds* bounds,
                   Diagnostics& diag) {
  if (!dynamics_internal::check_structure(robot, codes::ROBOT_INVALID_REFERENCE, diag)) return;
  check_roots(robot, diag);
  const std::vector<int> order = dynamics_internal::tree_order(robot);
  const WeldGroups welds = dynamics_internal::weld_groups(
      robot, order, dynamics_internal::forward_kinematics(robot, order, std::vector<double>(robot.joints.size(), 0.0)),
      options.floating_root, options.bound_mass, options.bound_inertia);
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    if (!link.X_SL.matrix().allFinite()) {
      diag.error(codes::LINK_POSE_NOT_FINITE, where(link), "link '" + link.name + "': pose is not finite");
    }
    check_mass(robot, l, welds, options, diag);
    if (std::isfinite(link.inertial.mass) && link.inertial.mass > 0) {
      check_inertia(robot, link, welds.groups[welds.group_of[l]], welds.extent, options, diag);
    }
    const std::optional<Eigen::AlignedBox3d> none;
    check_center_of_mass(link, bounds && l < bounds->size() ? (*bounds)[l] : none, options, diag);
    check_inertia_within_geometry(link, bounds && l < bounds->size() ? (*bounds)[l] : none, options, diag);
  }
  for (const WeldGroup& group : welds.groups) check_combined_inertia(robot, group, options, diag);
  const int largest_island = dynamics_internal::largest_island(robot, welds);
  for (const Joint& joint : robot.joints) check_joint(robot, joint, welds, largest_island, options, diag);
}

}  // namespace rdtf
