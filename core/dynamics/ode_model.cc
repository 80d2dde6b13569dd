// The ODE model of a robot (docs/dynamics.md, "ODE model"): one body per link with mass, its
// origin at the link's centre of mass and its axes the link frame's; massless links ride on the
// body they are fixed to; joints by kind, created at the rest pose so that ODE's zero positions
// are the robot's.
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <mutex>
#include <numbers>
#include <stdexcept>

#include "ode_model.h"

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

// Errors for what ODE cannot take: the model is refused when there is one.
void check_mappable(const Robot& robot, const std::vector<int>& carrier, Diagnostics& diag) {
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    const std::string where = node_pointer(link.node);
    const std::string name = "link '" + link.name + "': ";
    if (!link.X_SL.matrix().allFinite()) diag.error("ODE_INVALID_LINK", where, name + "pose is not finite");
    if (carrier[l] == kUnresolved) {
      diag.error("ODE_MASSLESS_LINK", where,
                 name + "has no mass and is not fixed to a link with mass or to the world: ODE "
                        "cannot move a body without mass");
      continue;
    }
    if (carrier[l] != static_cast<int>(l)) continue;
    const MassProperties& inertial = link.inertial;
    if (!std::isfinite(inertial.mass) || !inertial.inertia.allFinite() ||
        !inertial.center_of_mass.allFinite()) {
      diag.error("ODE_MASS_CHECK_FAILED", where, name + "mass, inertia or centre of mass is not finite");
      continue;
    }
    const Eigen::Matrix3d& I = inertial.inertia;
    dMass mass;
    dMassSetParameters(&mass, inertial.mass, 0, 0, 0, I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2));
    if (!dMassCheck(&mass)) {
      diag.error("ODE_MASS_CHECK_FAILED", where,
                 name + "dMassCheck refuses mass " + number(inertial.mass) + " kg with inertia [" +
                     number(I(0, 0)) + ", " + number(I(0, 1)) + ", " + number(I(0, 2)) + ", " +
                     number(I(1, 1)) + ", " + number(I(1, 2)) + ", " + number(I(2, 2)) +
                     "] kg m^2 (mass must be positive, inertia positive definite)");
    }
  }
  for (const Joint& joint : robot.joints) {
    const std::string where = node_pointer(joint.node);
    const std::string name = "joint '" + joint.name + "' (" + to_string(joint.kind) + "): ";
    if (joint.kind == JointKind::kPlanar) {
      diag.error("ODE_UNSUPPORTED_JOINT", where,
                 name + "ODE has no planar joint between two bodies; not simulated");
    }
    if (!joint.X_PJ.matrix().allFinite()) diag.error("ODE_INVALID_JOINT", where, name + "origin is not finite");
    if (one_dof(joint.kind) && (!joint.axis.allFinite() || joint.axis.norm() < 1e-12)) {
      diag.error("ODE_INVALID_JOINT", where, name + "axis " + vector_text(joint.axis) + " has no direction");
    }
    if (joint.limits && (joint.kind == JointKind::kRevolute || joint.kind == JointKind::kPrismatic) &&
        !(joint.limits->lower <= joint.limits->upper)) {
      diag.error("ODE_INVALID_JOINT", where,
                 name + "limits [" + number(joint.limits->lower) + ", " + number(joint.limits->upper) +
                     "] are not an interval");
    }
    for (double value : {joint.damping, joint.friction, joint.spring_stiffness}) {
      if (!(value >= 0) || !std::isfinite(value)) {
        diag.error("ODE_INVALID_JOINT", where,
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
      diag.info("SIM_UNKNOWN_JOINT", "", "initial position for '" + name + "': no such joint; ignored");
      continue;
    }
    const Joint& joint = robot.joints[found->second];
    if (!one_dof(joint.kind) || !std::isfinite(value)) {
      diag.warning("SIM_INITIAL_POSITION_IGNORED", node_pointer(joint.node),
                   "initial position " + number(value) + " of joint '" + name + "' (" +
                       to_string(joint.kind) + ") ignored: not one finite degree of freedom");
      continue;
    }
    q[found->second] = value;
  }
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    const Joint& joint = robot.joints[j];
    if (!joint.limits || (joint.kind != JointKind::kRevolute && joint.kind != JointKind::kPrismatic)) continue;
    const double clamped = std::clamp(q[j], joint.limits->lower, joint.limits->upper);
    if (clamped != q[j]) {
      diag.info("SIM_INITIAL_POSITION_CLAMPED", node_pointer(joint.node),
                "joint '" + joint.name + "' starts at " + number(clamped) + " (its limit), not " + number(q[j]));
      q[j] = clamped;
    }
  }
  return q;
}

void add_bodies(Simulation::Model& model, const std::vector<int>& carrier, const std::vector<int>& order,
                const std::vector<Eigen::Isometry3d>& rest) {
  const Robot& robot = model.robot;
  const std::vector<double> reach = reach_bounds(robot, order);
  const std::vector<int> root = root_of(robot, order);
  std::vector<int> body_of(robot.links.size(), kWorld);
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    if (carrier[l] != static_cast<int>(l)) continue;
    const MassProperties& inertial = robot.links[l].inertial;
    BodyModel body;
    body.link = static_cast<int>(l);
    body.mass = inertial.mass;
    body.inertia = 0.5 * (inertial.inertia + inertial.inertia.transpose());
    body.com_L = inertial.center_of_mass;
    body.reach = reach[l] + body.com_L.norm();
    body.root_link = root[l];
    body.id = dBodyCreate(model.world);
    const Eigen::Matrix3d& I = body.inertia;
    dMass mass;
    dMassSetParameters(&mass, body.mass, 0, 0, 0, I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2));
    dBodySetMass(body.id, &mass);
    set_body_pose(body.id, rest[l] * Eigen::Translation3d(body.com_L));
    body_of[l] = static_cast<int>(model.bodies.size());
    model.bodies.push_back(body);
  }
  model.links.resize(robot.links.size());
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    LinkModel& link = model.links[l];
    link.body = carrier[l] == kWorld ? kWorld : body_of[carrier[l]];
    link.X_BL = link.body == kWorld ? rest[l] : body_pose(model.bodies[link.body].id).inverse() * rest[l];
  }
}

void add_joint(Simulation::Model& model, int j, const Eigen::Isometry3d& X_SJ, Diagnostics& diag) {
  const Joint& joint = model.robot.joints[j];
  JointModel& jm = model.joints[j];
  jm.joint = j;
  jm.kind = joint.kind;
  jm.dof = one_dof(joint.kind);
  jm.damping = joint.damping;
  jm.stiffness = joint.spring_stiffness;
  jm.limited = joint.limits && (joint.kind == JointKind::kRevolute || joint.kind == JointKind::kPrismatic);
  if (jm.limited) {
    jm.lower = joint.limits->lower;
    jm.upper = joint.limits->upper;
  }
  if (joint.limits) jm.effort_limit = joint.limits->effort;
  jm.child_body = model.links[joint.child_link].body;
  jm.parent_body = model.links[joint.parent_link].body;
  const std::string where = node_pointer(joint.node);
  const std::string name = "joint '" + joint.name + "' (" + to_string(joint.kind) + "): ";
  const auto ignored = [&](const char* what) {
    diag.warning("ODE_PROPERTY_IGNORED", where, name + what + " is not modelled for this kind; ignored");
  };
  if (joint.kind == JointKind::kFloating) {
    if (joint.damping > 0) ignored("damping");
  }
  if (joint.kind == JointKind::kFloating || joint.kind == JointKind::kBall) {
    if (joint.friction > 0) ignored("friction");
    if (joint.spring_stiffness > 0) ignored("spring stiffness");
  }
  // A fixed joint inside one body (a massless link riding on the body it is fixed to, or two
  // massless links the world carries) is no constraint. Deciding by the massless side alone left a
  // body whose massless parent is a root (Khronos RiggedSimple) unheld: it fell.
  if (joint.kind == JointKind::kFloating || (joint.kind == JointKind::kFixed && jm.child_body == jm.parent_body)) {
    return;
  }

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
      if (jm.limited && jm.lower > -std::numbers::pi && jm.upper < std::numbers::pi) {
        dJointSetHingeParam(jm.id, dParamLoStop, jm.lower);
        dJointSetHingeParam(jm.id, dParamHiStop, jm.upper);
        jm.stops = true;
      } else if (jm.limited) {
        diag.warning("ODE_LIMIT_NOT_ENFORCED", where,
                     name + "ODE enforces hinge limits inside (-pi, pi) only; [" + number(jm.lower) +
                         ", " + number(jm.upper) + "] is watched (validation) but not enforced");
      }
      break;
    case JointKind::kPrismatic:
      jm.id = dJointCreateSlider(model.world, nullptr);
      dJointAttach(jm.id, child, parent);
      dJointSetSliderAxis(jm.id, axis.x(), axis.y(), axis.z());
      if (jm.limited) {
        dJointSetSliderParam(jm.id, dParamLoStop, jm.lower);
        dJointSetSliderParam(jm.id, dParamHiStop, jm.upper);
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
    const dReal* w = dBodyGetAngularVel(id);
    BodyFrame& frame = model.frames[b];
    frame.R = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
    frame.p = Eigen::Vector3d(p[0], p[1], p[2]);
    frame.w = Eigen::Vector3d(w[0], w[1], w[2]);
  }
}

std::vector<std::string> take_ode_messages() {
  std::vector<std::string> out;
  out.swap(thread_messages);
  return out;
}

void prime_joint_states(Simulation::Model& model) {
  for (JointModel& jm : model.joints) {
    if (!jm.dof || !jm.id) continue;
    if (jm.kind == JointKind::kPrismatic) {
      jm.q = dJointGetSliderPosition(jm.id);
      jm.qdot = dJointGetSliderPositionRate(jm.id);
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
  if (!check_structure(robot, "ODE_INVALID_ROBOT", diag)) return nullptr;
  if (!options.gravity.allFinite() || !(options.time_step > 0) || !std::isfinite(options.time_step)) {
    diag.error("SIM_INVALID_OPTIONS", "", "gravity must be finite and the time step positive");
    return nullptr;
  }
  const std::vector<int> carrier = carriers(robot, options.floating_root);
  const std::size_t errors = diag.error_count();
  check_mappable(robot, carrier, diag);
  if (diag.error_count() > errors) return nullptr;

  auto model = std::make_unique<Simulation::Model>();
  model->robot = robot;
  model->options = options;
  model->world = dWorldCreate();
  model->threading = dThreadingAllocateSelfThreadedImplementation();
  dWorldSetStepThreadingImplementation(model->world, dThreadingImplementationGetFunctions(model->threading),
                                       model->threading);
  dWorldSetGravity(model->world, options.gravity.x(), options.gravity.y(), options.gravity.z());
  dWorldSetERP(model->world, options.erp);
  dWorldSetCFM(model->world, options.cfm);
  dWorldSetQuickStepNumIterations(model->world, options.quickstep_iterations);
  dWorldSetQuickStepW(model->world, options.quickstep_sor);
  dWorldSetAutoDisableFlag(model->world, 0);

  const std::vector<int> order = tree_order(robot);
  const std::vector<double> q = start_positions(robot, initial, diag);
  const std::vector<Eigen::Isometry3d> rest =
      forward_kinematics(robot, order, std::vector<double>(robot.joints.size(), 0.0));
  add_bodies(*model, carrier, order, rest);
  model->joints.resize(robot.joints.size());
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    add_joint(*model, static_cast<int>(j), rest[robot.joints[j].child_link], diag);
  }
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    if (robot.links[l].parent_joint >= 0) continue;
    model->root_links.push_back(static_cast<int>(l));
    // A root is held by the world unless the roots float: through the body that carries it (its
    // own, or that of the nearest link with mass it is fixed to); a root the world carries is.
    if (!options.floating_root && carrier[l] >= 0) {
      dJointID hold = dJointCreateFixed(model->world, nullptr);
      dJointAttach(hold, model->bodies[model->links[l].body].id, nullptr);
      dJointSetFixed(hold);
    }
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
    if (model->joints[j].dof && model->joints[j].kind != JointKind::kPrismatic) model->joints[j].q = q[j];
    model->joint_index.emplace(robot.joints[j].name, static_cast<int>(j));
  }
  for (std::size_t l = 0; l < robot.links.size(); ++l) model->link_index.emplace(robot.links[l].name, static_cast<int>(l));
  model->quickstep = options.stepper == Stepper::kQuickStep ||
                     (options.stepper == Stepper::kAuto &&
                      static_cast<int>(model->bodies.size()) >= options.quickstep_min_bodies);
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
