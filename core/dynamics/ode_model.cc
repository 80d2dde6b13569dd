// The ODE model of a robot (docs/dynamics.md, "ODE model"): one body per link with mass, its
// origin at the link's centre of mass and its axes the link frame's; massless links ride on the
// body they are fixed to; joints by kind, created at the rest pose so that ODE's zero positions
// are the robot's.
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <mutex>
#include <numbers>
#include <stdexcept>

#include "ode_model.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace dynamics_internal {
namespace {

thread_local bool thread_ready = false;
thread_local std::vector<std::string> thread_messages;

void on_ode_message(int errnum, const char* message, va_list ap) {
  char text[512];
  std::vsnprintf(text, sizeof(text), message, ap);
  if (thread_messages.size() < 100) {
    thread_messages.push_back("ODE message " + std::to_string(errnum) + ": " + text);
  }
}

[[noreturn]] void on_ode_internal_error(int errnum, const char* message, va_list ap) {
  char text[512];
  std::vsnprintf(text, sizeof(text), message, ap);
  throw OdeInternalError("ODE internal error " + std::to_string(errnum) + ": " + text);
}

dBodyID body_id(const Simulation::Model& model, int body) {
  return body == kWorld ? nullptr : model.bodies[body].id;
}

void set_body_pose(dBodyID body, const Eigen::Isometry3d& X_SB) {
  const Eigen::Vector3d p = X_SB.translation();
  const Eigen::Quaterniond q(X_SB.linear());
  dBodySetPosition(body, p.x(), p.y(), p.z());
  const dQuaternion quaternion = {q.w(), q.x(), q.y(), q.z()};
  dBodySetQuaternion(body, quaternion);
}

std::string mass_text(const MassProperties& in) {
  const Eigen::Matrix3d& I = in.inertia;
  // Named entry by entry, in the frame they are in: the link's glTF frame (y up), which a URDF's
  // ixx .. izz (z up) differ from by a turn, so that its values are found as what they are.
  return "mass " + number(in.mass) + " kg with inertia (link frame, glTF axes: y up) Ixx " + number(I(0, 0)) +
         ", Ixy " + number(I(0, 1)) + ", Ixz " + number(I(0, 2)) + ", Iyy " + number(I(1, 1)) + ", Iyz " +
         number(I(1, 2)) + ", Izz " + number(I(2, 2)) + " kg m^2";
}

bool mass_checks(const MassProperties& in) {
  const Eigen::Matrix3d& I = in.inertia;
  dMass mass;
  dMassSetParameters(&mass, in.mass, 0, 0, 0, I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2));
  return dMassCheck(&mass) != 0;
}

// Errors for what ODE cannot take: the model is refused when there is one. Links welded to the
// world never move: their mass is not used. A moving group is one ODE body with the combined mass
// of its links, which ODE must accept; with one link adding mass, that link's own.
void check_mappable(const Robot& robot, const WeldGroups& welds, Diagnostics& diag) {
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    const std::string where = node_pointer(link.node);
    const std::string name = "link '" + link.name + "': ";
    if (!link.X_SL.matrix().allFinite()) diag.error(codes::ODE_INVALID_LINK, where, name + "pose is not finite");
    const WeldGroup& group = welds.groups[welds.group_of[l]];
    if (group.welded_to_world || is_massless(link)) continue;
    // Mass 0 with an inertia, in a body with mass: its inertia only adds to the body's.
    if (link.inertial.mass == 0 && group.merged.mass > 0 && link.inertial.inertia.allFinite()) continue;
    const MassProperties& inertial = link.inertial;
    if (!std::isfinite(inertial.mass) || !inertial.inertia.allFinite() ||
        !inertial.center_of_mass.allFinite()) {
      diag.error(codes::ODE_MASS_CHECK_FAILED, where, name + "mass, inertia or centre of mass is not finite");
      continue;
    }
    // A link is part of its group's body, one ODE body with the combined mass, checked below. The
    // top link's own is what ODE gets when no other link of the group adds mass or inertia.
    if (static_cast<int>(l) == group.top && adding_links(robot, group) < 2 && !mass_checks(inertial)) {
      diag.error(codes::ODE_MASS_CHECK_FAILED, where,
                 name + "dMassCheck refuses " + mass_text(inertial) +
                     " (mass must be positive, inertia positive definite)");
    }
  }
  for (const WeldGroup& group : welds.groups) {
    if (group.welded_to_world) continue;
    const Link& top = robot.links[group.top];
    if (group.merged.mass == 0) {
      for (int l : group.links) {
        diag.error(codes::ODE_MASSLESS_LINK, node_pointer(robot.links[l].node),
                   "link '" + robot.links[l].name +
                       "': has no mass and is not fixed to a link with mass or to the world: ODE "
                       "cannot move a body without mass (a bound mass and inertia simulate it: "
                       "rdtf validate --bound-mass KG --bound-inertia KGM2, rdtfd bound_mass_kg and "
                       "bound_inertia_kgm2)");
      }
    } else if (adding_links(robot, group) >= 2 && !mass_checks(group.merged)) {
      diag.error(codes::ODE_MASS_CHECK_FAILED, node_pointer(top.node),
                 "link '" + top.name + "' and the " + std::to_string(group.links.size() - 1) +
                     " links fixed to it: dMassCheck refuses their combined " + mass_text(group.merged));
    }
  }
  for (const Joint& joint : robot.joints) {
    const std::string where = node_pointer(joint.node);
    const std::string name = "joint '" + joint.name + "' (" + to_string(joint.kind) + "): ";
    if (joint.kind == JointKind::kPlanar) {
      diag.error(codes::ODE_UNSUPPORTED_JOINT, where,
                 name + "rdtf simulates no planar joint (ODE's only one, Plane2D, holds a body in the world's z = 0 "
                        "plane); not simulated");
    }
    if (!joint.X_PJ.matrix().allFinite()) diag.error(codes::ODE_INVALID_JOINT, where, name + "origin is not finite");
    if (one_dof(joint.kind) && (!joint.axis.allFinite() || joint.axis.norm() < 1e-12)) {
      diag.error(codes::ODE_INVALID_JOINT, where, name + "axis " + vector_text(joint.axis) + " has no direction");
    }
    if (position_limited(joint) &&
        !(joint.limits->lower <= joint.limits->upper && std::isfinite(joint.limits->lower) &&
          std::isfinite(joint.limits->upper))) {
      diag.error(codes::ODE_INVALID_JOINT, where,
                 name + "limits [" + number(joint.limits->lower) + ", " + number(joint.limits->upper) +
                     "] are not a finite interval");
    }
    for (double value : {joint.damping, joint.friction, joint.spring_stiffness}) {
      if (!(value >= 0) || !std::isfinite(value)) {
        diag.error(codes::ODE_INVALID_JOINT, where,
                   name + "damping, friction and stiffness must be finite and not negative");
        break;
      }
    }
  }
}

// Position of each joint at the start: named ones (clamped into limits), the rest pose else.
std::vector<double> start_positions(const Robot& robot, const std::map<std::string, double>& initial,
                                    Diagnostics& diag) {
  std::vector<double> q(robot.joints.size(), 0.0);
  std::map<std::string, int, std::less<>> index;
  for (std::size_t j = 0; j < robot.joints.size(); ++j) index.emplace(robot.joints[j].name, static_cast<int>(j));
  for (const auto& [name, value] : initial) {
    const auto found = index.find(name);
    if (found == index.end()) {
      diag.info(codes::SIM_UNKNOWN_JOINT, "", "initial position for '" + name + "': no such joint; ignored");
      continue;
    }
    const Joint& joint = robot.joints[found->second];
    if (!one_dof(joint.kind) || !std::isfinite(value)) {
      diag.warning(codes::SIM_INITIAL_POSITION_IGNORED, node_pointer(joint.node),
                   "initial position " + number(value) + " of joint '" + name + "' (" +
                       to_string(joint.kind) + ") ignored: not one finite degree of freedom");
      continue;
    }
    q[found->second] = value;
  }
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    const Joint& joint = robot.joints[j];
    if (!position_limited(joint)) continue;
    const double clamped = std::clamp(q[j], joint.limits->lower, joint.limits->upper);
    if (clamped != q[j]) {
      diag.info(codes::SIM_INITIAL_POSITION_CLAMPED, node_pointer(joint.node),
                "joint '" + joint.name + "' starts at " + number(clamped) + " (its limit), not " + number(q[j]));
      q[j] = clamped;
    }
  }
  return q;
}

// One ODE body per moving weld group: its origin at the group's centre of mass and its axes
// those of the group's top link T, X_SB = X_ST * translation(p_ToBcm_T). Every link keeps X_BL,
// its pose in its body (in the world, for a group the world holds).
void add_bodies(Simulation::Model& model, const WeldGroups& welds, const std::vector<int>& order,
                const std::vector<Eigen::Isometry3d>& rest) {
  const Robot& robot = model.robot;
  const std::vector<double> reach = reach_bounds(robot, order);
  const std::vector<int> root = root_of(robot, order);
  std::vector<int> body_of_group(welds.groups.size(), kWorld);
  for (std::size_t g = 0; g < welds.groups.size(); ++g) {
    const WeldGroup& group = welds.groups[g];
    if (!moves(group)) continue;
    BodyModel body;
    body.link = group.top;
    body.links = static_cast<int>(group.links.size());
    body.mass = group.merged.mass;
    body.inertia = group.merged.inertia;
    body.com_L = group.merged.center_of_mass;
    body.reach = reach[group.top] + body.com_L.norm();
    body.root_link = root[group.top];
    body.id = dBodyCreate(model.world);
    const Eigen::Matrix3d& I = body.inertia;
    dMass mass;
    dMassSetParameters(&mass, body.mass, 0, 0, 0, I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2));
    dBodySetMass(body.id, &mass);
    // ODE's default update turns a body by 2 atan(h |w| / 2) a step, not h |w|: a wheel spinning
    // at 1000 rad/s (h = 1 ms) published a position advancing at 927 rad/s beside its velocity of
    // 1000. The finite rotation mode turns it by exactly h |w| about w.
    dBodySetFiniteRotationMode(body.id, 1);
    set_body_pose(body.id, rest[group.top] * Eigen::Translation3d(body.com_L));
    body_of_group[g] = static_cast<int>(model.bodies.size());
    model.bodies.push_back(body);
  }
  model.links.resize(robot.links.size());
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    LinkModel& link = model.links[l];
    link.body = body_of_group[welds.group_of[l]];
    link.X_BL = link.body == kWorld ? rest[l] : body_pose(model.bodies[link.body].id).inverse() * rest[l];
  }
}

// Every limited hinge's stops are a one-axis angular motor in user mode, on the unwrapped position
// that Simulation::step hands it before every step (ODE tests the stops of both kinds the same way:
// against the position at the start of the step). The hinge's own stops act on ODE's angle, wrapped
// to (-pi, pi]: a stop near +-pi is overrun into the wrap, where the angle reads beyond the other
// stop and the stop's correction drives the joint on. +-3.14159 let a wrist through its stop by
// 0.72 rad (s70rob D1); [-3.14, 0], kept on the hinge's stops as narrower than pi, let a rod that
// overshot -pi by 2 mrad spin through its stop for ever (s101gate D2: 540 rad in 3 s). Moving the
// hinge's window with dJointSetHingeAxisOffset instead is wrong in ODE 0.16 when the child body is
// turned in the world: it composes the world axis with a rotation kept in body axes (measured: an
// offset of 0.23 read 1.70, and turning the body by 0.1 rad changed it by 0.035).
void add_hinge_limits(Simulation::Model& model, JointModel& jm, dBodyID child, dBodyID parent,
                      const Eigen::Vector3d& axis) {
  jm.stops = true;
  jm.limit_motor = dJointCreateAMotor(model.world, nullptr);
  dJointAttach(jm.limit_motor, child, parent);
  dJointSetAMotorMode(jm.limit_motor, dAMotorUser);
  dJointSetAMotorNumAxes(jm.limit_motor, 1);
  dJointSetAMotorAxis(jm.limit_motor, 0, 1, axis.x(), axis.y(), axis.z());  // fixed in the child
  dJointSetAMotorParam(jm.limit_motor, dParamLoStop, jm.lower);
  dJointSetAMotorParam(jm.limit_motor, dParamHiStop, jm.upper);
  dJointSetAMotorAngle(jm.limit_motor, 0, 0.0);
  dJointSetFeedback(jm.limit_motor, &jm.feedback);
}

// Each body's island (a body index standing for it): bodies joined by joints, the world joining
// none; largest_island counts the bodies of the largest. dWorldStep
// solves each island's constraints on their own, at a cost that grows as the cube of its rows, so
// the island, not the model, is what makes QuickStep the cheaper stepper: a humanoid whose pelvis
// the world holds is islands of 6, 6 and 19 bodies, which dWorldStep steps exactly in 188 ms of a
// 3 s validation where QuickStep took 353 ms and let the chest chatter on its stop (s101gate D1).
std::vector<std::size_t> islands(const Simulation::Model& model) {
  std::vector<std::size_t> root(model.bodies.size());
  for (std::size_t b = 0; b < root.size(); ++b) root[b] = b;
  const auto find = [&root](std::size_t b) {
    while (root[b] != b) {
      root[b] = root[root[b]];
      b = root[b];
    }
    return b;
  };
  for (const JointModel& jm : model.joints) {
    if (jm.id == nullptr || jm.child_body < 0 || jm.parent_body < 0) continue;
    root[find(static_cast<std::size_t>(jm.child_body))] = find(static_cast<std::size_t>(jm.parent_body));
  }
  for (std::size_t b = 0; b < root.size(); ++b) root[b] = find(b);
  return root;
}

int largest_island(const std::vector<std::size_t>& island) {
  std::vector<int> size(island.size(), 0);
  int largest = 0;
  for (const std::size_t root : island) largest = std::max(largest, ++size[root]);
  return largest;
}

// A body's mobility (1 / (kg m^2)) about the scene axis `a_S`: the angular speed a unit angular
// impulse about the axis gives it when nothing else holds it, a^T I^-1 a with a in the body's axes;
// 0 for the world. A hinge's axis is fixed in both of its bodies, so this stays what it is at the
// start. With `a_S` zero: the trace of I^-1, the sum over three orthonormal axes (a ball joint's).
double mobility(const Simulation::Model& model, int body, const Eigen::Vector3d& a_S) {
  if (body == kWorld) return 0;
  const BodyModel& b = model.bodies[static_cast<std::size_t>(body)];
  const Eigen::Matrix3d I_inverse = b.inertia.inverse();
  if (a_S.isZero(0)) return I_inverse.trace();
  const Eigen::Vector3d a_B = body_pose(b.id).linear().transpose() * a_S;
  return a_B.dot(I_inverse * a_B);
}

// The joint's damper motor (JointModel::damper), idle until Simulation::step chooses it.
void add_damper(Simulation::Model& model, JointModel& jm, dBodyID child, dBodyID parent, const Eigen::Vector3d& axis) {
  const double c = jm.damping;
  if (jm.kind == JointKind::kPrismatic) {
    jm.damper = dJointCreateLMotor(model.world, nullptr);
    dJointAttach(jm.damper, child, parent);
    dJointSetLMotorNumAxes(jm.damper, 1);
    dJointSetLMotorAxis(jm.damper, 0, 1, axis.x(), axis.y(), axis.z());
    dJointSetLMotorParam(jm.damper, dParamVel, 0);
    dJointSetLMotorParam(jm.damper, dParamCFM, 1 / c);
    dJointSetLMotorParam(jm.damper, dParamFMax, 0);
  } else {
    jm.damper = dJointCreateAMotor(model.world, nullptr);
    dJointAttach(jm.damper, child, parent);
    const bool ball = jm.kind == JointKind::kBall;
    dJointSetAMotorNumAxes(jm.damper, ball ? 3 : 1);
    if (ball) {
      // Three axes fixed in the child, its own: any three orthonormal axes damp the whole relative
      // angular velocity.
      const Eigen::Matrix3d R_SC = body_pose(child).linear();
      for (int i = 0; i < 3; ++i) dJointSetAMotorAxis(jm.damper, i, 1, R_SC(0, i), R_SC(1, i), R_SC(2, i));
    } else {
      dJointSetAMotorAxis(jm.damper, 0, 1, axis.x(), axis.y(), axis.z());
    }
    for (const int group : {0, int{dParamGroup}, 2 * int{dParamGroup}}) {
      dJointSetAMotorParam(jm.damper, group + dParamVel, 0);
      dJointSetAMotorParam(jm.damper, group + dParamCFM, 1 / c);
      dJointSetAMotorParam(jm.damper, group + dParamFMax, 0);
    }
  }
  dJointSetFeedback(jm.damper, &jm.damper_feedback);
  if (jm.kind == JointKind::kPrismatic) {
    // What a slider moves along its axis depends on where it is once its parent turns: no bound
    // fixed at the start, so its damper is always implicit.
    jm.damper_rate = kInfinity;
    return;
  }
  const Eigen::Vector3d about = jm.kind == JointKind::kBall ? Eigen::Vector3d::Zero() : axis;
  jm.damper_rate = c * (mobility(model, jm.child_body, about) + mobility(model, jm.parent_body, about));
}

void add_joint(Simulation::Model& model, int j, const Eigen::Isometry3d& X_SJ, Diagnostics& diag) {
  const Joint& joint = model.robot.joints[j];
  JointModel& jm = model.joints[j];
  jm.joint = j;
  jm.kind = joint.kind;
  jm.dof = one_dof(joint.kind);
  jm.damping = joint.damping;
  jm.stiffness = joint.spring_stiffness;
  jm.limited = position_limited(joint);
  if (jm.limited) {
    jm.lower = joint.limits->lower;
    jm.upper = joint.limits->upper;
  }
  if (joint.limits) {
    jm.effort_limit = joint.limits->effort;
    jm.velocity_limit = joint.limits->velocity;
  }
  jm.child_body = model.links[joint.child_link].body;
  jm.parent_body = model.links[joint.parent_link].body;
  const std::string where = node_pointer(joint.node);
  const std::string name = "joint '" + joint.name + "' (" + to_string(joint.kind) + "): ";
  const auto ignored = [&](const char* what) {
    diag.warning(codes::ODE_PROPERTY_IGNORED, where, name + what + " is not modelled for this kind; ignored");
  };
  if (joint.kind == JointKind::kFloating) {
    if (joint.damping > 0) ignored("damping");
  }
  if (joint.kind == JointKind::kFloating || joint.kind == JointKind::kBall) {
    if (joint.friction > 0) ignored("friction");
    if (joint.spring_stiffness > 0) ignored("spring stiffness");
  }
  // A fixed joint is inside one body (its weld group) or inside the world: no constraint.
  if (joint.kind == JointKind::kFloating || joint.kind == JointKind::kFixed) return;

  dBodyID child = model.bodies[jm.child_body].id;
  dBodyID parent = body_id(model, jm.parent_body);
  const Eigen::Vector3d p = X_SJ.translation();
  const Eigen::Vector3d axis = X_SJ.linear() * (jm.dof ? joint.axis.normalized() : Eigen::Vector3d::UnitX());
  switch (joint.kind) {
    case JointKind::kFixed:
      jm.id = dJointCreateFixed(model.world, nullptr);
      dJointAttach(jm.id, child, parent);
      dJointSetFixed(jm.id);
      break;
    case JointKind::kRevolute:
    case JointKind::kContinuous:
      jm.id = dJointCreateHinge(model.world, nullptr);
      dJointAttach(jm.id, child, parent);  // child first: the angle is the child's about the axis
      dJointSetHingeAnchor(jm.id, p.x(), p.y(), p.z());
      dJointSetHingeAxis(jm.id, axis.x(), axis.y(), axis.z());
      if (jm.limited) add_hinge_limits(model, jm, child, parent, axis);
      break;
    case JointKind::kPrismatic:
      jm.id = dJointCreateSlider(model.world, nullptr);
      dJointAttach(jm.id, child, parent);
      dJointSetSliderAxis(jm.id, axis.x(), axis.y(), axis.z());
      if (jm.limited) {
        dJointSetSliderParam(jm.id, dParamLoStop, jm.lower);
        dJointSetSliderParam(jm.id, dParamHiStop, jm.upper);
        dJointSetFeedback(jm.id, &jm.feedback);
        jm.stops = true;
      }
      break;
    case JointKind::kBall:
      jm.id = dJointCreateBall(model.world, nullptr);
      dJointAttach(jm.id, child, parent);
      dJointSetBallAnchor(jm.id, p.x(), p.y(), p.z());
      break;
    default:
      return;
  }
  // Coulomb friction: a motor holding zero relative speed with at most the friction torque.
  if (jm.dof && joint.friction > 0) {
    const bool hinge = joint.kind != JointKind::kPrismatic;
    jm.friction_motor = hinge ? dJointCreateAMotor(model.world, nullptr) : dJointCreateLMotor(model.world, nullptr);
    dJointAttach(jm.friction_motor, child, parent);
    if (hinge) {
      dJointSetAMotorNumAxes(jm.friction_motor, 1);
      dJointSetAMotorAxis(jm.friction_motor, 0, 1, axis.x(), axis.y(), axis.z());
      dJointSetAMotorParam(jm.friction_motor, dParamVel, 0);
      dJointSetAMotorParam(jm.friction_motor, dParamFMax, joint.friction);
    } else {
      dJointSetLMotorNumAxes(jm.friction_motor, 1);
      dJointSetLMotorAxis(jm.friction_motor, 0, 1, axis.x(), axis.y(), axis.z());
      dJointSetLMotorParam(jm.friction_motor, dParamVel, 0);
      dJointSetLMotorParam(jm.friction_motor, dParamFMax, joint.friction);
    }
  }
  if (joint.damping > 0 && (jm.dof || joint.kind == JointKind::kBall)) add_damper(model, jm, child, parent, axis);
  if (jm.dof && joint.spring_stiffness > 0) {
    // A slider's force acts on its bodies' centres of mass along the axis: 1/m of each.
    const auto linear = [&model](int body) {
      return body == kWorld ? 0.0 : 1 / model.bodies[static_cast<std::size_t>(body)].mass;
    };
    jm.spring_rate = joint.spring_stiffness * (jm.kind == JointKind::kPrismatic
                                                   ? linear(jm.child_body) + linear(jm.parent_body)
                                                   : mobility(model, jm.child_body, axis) + mobility(model, jm.parent_body, axis));
  }
  // Where the constraint holds, on each side, for measuring its error.
  const Eigen::Isometry3d X_SC = body_pose(child);
  const Eigen::Isometry3d X_SP = parent ? body_pose(parent) : Eigen::Isometry3d::Identity();
  jm.anchor_child = X_SC.inverse() * p;
  jm.anchor_parent = X_SP.inverse() * p;
  jm.axis_child = X_SC.linear().transpose() * axis;
  jm.axis_parent = X_SP.linear().transpose() * axis;
  jm.rotation0 = Eigen::Quaterniond(X_SP.linear().transpose() * X_SC.linear());
}

}  // namespace

Eigen::Isometry3d body_pose(dBodyID body) {
  const dReal* p = dBodyGetPosition(body);
  const dReal* q = dBodyGetQuaternion(body);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  X.translation() = Eigen::Vector3d(p[0], p[1], p[2]);
  return X;
}

void read_frames(Simulation::Model& model) {
  model.frames.resize(model.bodies.size());
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const dBodyID id = model.bodies[b].id;
    const dReal* p = dBodyGetPosition(id);
    const dReal* q = dBodyGetQuaternion(id);
    const dReal* v = dBodyGetLinearVel(id);
    const dReal* w = dBodyGetAngularVel(id);
    BodyFrame& frame = model.frames[b];
    frame.R = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
    frame.p = Eigen::Vector3d(p[0], p[1], p[2]);
    frame.v = Eigen::Vector3d(v[0], v[1], v[2]);
    frame.w = Eigen::Vector3d(w[0], w[1], w[2]);
    frame.finite = frame.p.allFinite() && frame.v.allFinite() && frame.w.allFinite() &&
                   Eigen::Vector4d(q[0], q[1], q[2], q[3]).allFinite();
    frame.steppable = frame.finite && frame.p.cwiseAbs().maxCoeff() <= kStateBound &&
                      frame.v.cwiseAbs().maxCoeff() <= kStateBound && frame.w.cwiseAbs().maxCoeff() <= kStateBound;
  }
}

std::vector<std::string> take_ode_messages() {
  std::vector<std::string> out;
  out.swap(thread_messages);
  return out;
}

double slider_rate(dJointID slider) {
  dVector3 axis;
  dJointGetSliderAxis(slider, axis);  // In the scene frame.
  const dBodyID child = dJointGetBody(slider, 0);
  const dBodyID parent = dJointGetBody(slider, 1);
  const auto vector = [](const dReal* v) { return Eigen::Vector3d(v[0], v[1], v[2]); };
  Eigen::Vector3d relative = vector(dBodyGetLinearVel(child));
  if (parent != nullptr) {
    const Eigen::Vector3d lever = vector(dBodyGetPosition(child)) - vector(dBodyGetPosition(parent));
    relative -= vector(dBodyGetLinearVel(parent)) + vector(dBodyGetAngularVel(parent)).cross(lever);
  }
  return relative.dot(Eigen::Vector3d(axis[0], axis[1], axis[2]));
}

void prime_joint_states(Simulation::Model& model) {
  for (JointModel& jm : model.joints) {
    if (!jm.dof || !jm.id) continue;
    if (jm.kind == JointKind::kPrismatic) {
      jm.q = dJointGetSliderPosition(jm.id);
      jm.qdot = slider_rate(jm.id);
    } else {
      jm.ode_angle = dJointGetHingeAngle(jm.id);
      jm.qdot = dJointGetHingeAngleRate(jm.id);
    }
  }
}

std::unique_ptr<Simulation::Model> build_model(const Robot& robot, const SimulationOptions& options,
                                               const std::map<std::string, double>& initial,
                                               Diagnostics& diag) {
  init_ode();
  if (!check_structure(robot, codes::ODE_INVALID_ROBOT, diag)) return nullptr;
  if (!options.gravity.allFinite() || !(options.time_step > 0) || !std::isfinite(options.time_step)) {
    diag.error(codes::SIM_INVALID_OPTIONS, "", "gravity must be finite and the time step positive");
    return nullptr;
  }
  const std::vector<int> order = tree_order(robot);
  const std::vector<Eigen::Isometry3d> rest =
      forward_kinematics(robot, order, std::vector<double>(robot.joints.size(), 0.0));
  const WeldGroups welds =
      weld_groups(robot, order, rest, options.floating_root, options.bound_mass, options.bound_inertia);
  const std::size_t errors = diag.error_count();
  check_mappable(robot, welds, diag);
  if (diag.error_count() > errors) return nullptr;

  auto model = std::make_unique<Simulation::Model>();
  model->robot = robot;
  model->options = options;
  model->world = dWorldCreate();
  // ODE reserves at least 64 KiB for each of a world's two step arenas (dWORLDSTEP_RESERVESIZE_
  // DEFAULT) whatever the world holds: 1.3 GB of address space for 10,000 live one-link models,
  // and glibc's heaps fragmented around them. Reserve what the world needs (ODE grows the arenas
  // when bodies or joints are added), with ODE's own margin.
  dWorldStepReserveInfo reserve{};
  reserve.struct_size = sizeof(reserve);
  reserve.reserve_factor = dWORLDSTEP_RESERVEFACTOR_DEFAULT;
  reserve.reserve_minimum = 0;
  dWorldSetStepMemoryReservationPolicy(model->world, &reserve);
  model->threading = dThreadingAllocateSelfThreadedImplementation();
  dWorldSetStepThreadingImplementation(model->world, dThreadingImplementationGetFunctions(model->threading),
                                       model->threading);
  dWorldSetGravity(model->world, options.gravity.x(), options.gravity.y(), options.gravity.z());
  dWorldSetERP(model->world, options.erp);
  dWorldSetCFM(model->world, options.cfm);
  dWorldSetQuickStepNumIterations(model->world, options.quickstep_iterations);
  dWorldSetQuickStepW(model->world, options.quickstep_sor);
  dWorldSetAutoDisableFlag(model->world, 0);

  const std::vector<double> q = start_positions(robot, initial, diag);
  add_bodies(*model, welds, order, rest);
  model->joints.resize(robot.joints.size());
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    add_joint(*model, static_cast<int>(j), rest[robot.joints[j].child_link], diag);
  }
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    if (robot.links[l].parent_joint >= 0) continue;
    // A root held by the world is in a group the world carries (no body); a floating one is free.
    model->root_links.push_back(static_cast<int>(l));
  }
  // Joints hold their rest pose as zero; now move the bodies to the start positions.
  const std::vector<Eigen::Isometry3d> start = forward_kinematics(robot, order, q);
  for (BodyModel& body : model->bodies) {
    set_body_pose(body.id, start[body.link] * Eigen::Translation3d(body.com_L));
  }
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    if (model->links[l].body == kWorld) model->links[l].X_BL = start[l];
  }
  prime_joint_states(*model);
  read_frames(*model);
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    JointModel& jm = model->joints[j];
    if (jm.dof && jm.kind != JointKind::kPrismatic) jm.q = q[j];
    if (jm.limit_motor) dJointSetAMotorAngle(jm.limit_motor, 0, jm.q);
    model->joint_index.emplace(robot.joints[j].name, static_cast<int>(j));
  }
  for (std::size_t l = 0; l < robot.links.size(); ++l) model->link_index.emplace(robot.links[l].name, static_cast<int>(l));
  const std::vector<std::size_t> island = islands(*model);
  model->largest_island = largest_island(island);
  for (JointModel& jm : model->joints) {
    if (jm.child_body >= 0) jm.island = static_cast<int>(island[static_cast<std::size_t>(jm.child_body)]);
  }
  model->quickstep = options.stepper == Stepper::kQuickStep ||
                     (options.stepper == Stepper::kAuto && model->largest_island >= options.quickstep_min_bodies);
  return model;
}

}  // namespace dynamics_internal

Simulation::Model::~Model() {
  if (world) dWorldDestroy(world);
  if (threading && !interrupted) dThreadingFreeImplementation(threading);
}

void init_ode() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (!dInitODE2(0)) throw std::runtime_error("dInitODE2 failed");
    dSetMessageHandler(&dynamics_internal::on_ode_message);
    dSetDebugHandler(&dynamics_internal::on_ode_internal_error);
    dSetErrorHandler(&dynamics_internal::on_ode_internal_error);
  });
  if (!dynamics_internal::thread_ready) {
    if (!dAllocateODEDataForThread(dAllocateFlagBasicData)) {
      throw std::runtime_error("dAllocateODEDataForThread failed");
    }
    dynamics_internal::thread_ready = true;
  }
}

}  // namespace rdtf
