// The live simulation of one robot: stepping with the joint force model (docs/dynamics.md),
// joint states and link poses in the scene frame, commands, and the health of the state.
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>

#include "ode_model.h"

namespace rdtf {
namespace {

using dynamics_internal::body_pose;
using dynamics_internal::BodyFrame;
using dynamics_internal::BodyModel;
using dynamics_internal::JointModel;
using dynamics_internal::kWorld;

Eigen::Vector3d vec(const dReal* v) { return {v[0], v[1], v[2]}; }

// The bound of a joint's commanded effort: its authored effort limit, else kDefaultEffortLimit.
double effort_bound(const JointModel& jm) { return jm.effort_limit > 0 ? jm.effort_limit : kDefaultEffortLimit; }

// What a command does over one step of h. The feed-forward effort is applied as it is. The PD
// law, tau = kp (q* - q) + kd (v* - qdot), goes to the solver as a motor row, implicitly: with
// q' = q + h qdot' at the step's end, tau = kp (q* - q) + kd v* - (kp h + kd) qdot', which is the
// force of a velocity motor whose target is (kp (q* - q) + kd v*) / (kp h + kd) and whose
// constraint force mixing is 1 / (kp h + kd) (ODE's manual, "How do I make a spring"). Applied
// from the state before the step instead, as it was, the law is unstable once kd h / I > 2 or
// kp h^2 / I > 4 for the inertia I the joint moves: arm3's shoulder turns the arm about its own
// length (I = 3.2e-3 kg m^2, so kd h / I = 3.1) and the default kd of 10 made it swing by 2 rad
// within 10 ms. The
// motor's force is at most the joint's effort bound less the feed-forward, so their sum stays
// within it, as each term did before.
constexpr double kFastestTarget = 1e30;  // m/s or rad/s; far below the state bound (1e100)
constexpr double kSoftestMotor = 1e-12;  // kp h + kd below this: the law is applied as a torque

struct Drive {
  double feed_forward = 0;
  bool motor = false;
  double velocity = 0;  // the motor's target, rad/s or m/s
  double cfm = 0;
  double fmax = 0;
};

Drive command_drive(const JointModel& jm, double h) {
  Drive d;
  if (!jm.command) return d;
  const JointCommand& c = *jm.command;
  const double bound = effort_bound(jm);
  d.feed_forward = std::isnan(c.effort) ? 0.0 : std::clamp(c.effort, -bound, bound);
  double kp = 0;
  double kd = 0;
  if (c.mode == CommandMode::kPosition) {
    kp = c.kp;
    kd = c.kd;
  } else if (c.mode == CommandMode::kVelocity) {
    kd = c.kd;
  } else {
    return d;
  }
  const double stiffness = kp * h + kd;
  if (!std::isfinite(stiffness)) return d;
  if (stiffness < kSoftestMotor) {
    // Gains this soft are stable applied as a torque (kd h / I > 2 would need I below 5e-13
    // kg m^2), and a motor of CFM 1 / stiffness would not be a number the solver can use.
    const auto bounded = [bound](double term) { return std::isnan(term) ? 0.0 : std::clamp(term, -bound, bound); };
    const double target = jm.velocity_limit > 0 ? std::clamp(c.velocity, -jm.velocity_limit, jm.velocity_limit) : c.velocity;
    d.feed_forward = bounded(d.feed_forward + bounded(kp * (c.position - jm.q)) + bounded(kd * (target - jm.qdot)));
    return d;
  }
  // Weighed, not multiplied out; a target beyond any speed (a gain of 1e308 on an error of 1e308)
  // only says which way the motor pushes, with all its force.
  const double velocity = (kp / stiffness) * (c.position - jm.q) + (kd / stiffness) * c.velocity;
  const double fmax = bound - std::abs(d.feed_forward);
  if (std::isnan(velocity) || !(fmax > 0)) return d;
  d.motor = true;
  // The joint's velocity limit bounds the speed the motor drives it at (as ros_control's limits
  // saturate a command); gravity or a collision may still carry it faster. A velocity command of
  // 10 rad/s on a joint limited to 3 rad/s drove it at 10 (s90ctrl D5).
  const double fastest = jm.velocity_limit > 0 ? jm.velocity_limit : kFastestTarget;
  d.velocity = std::clamp(velocity, -fastest, fastest);
  d.cfm = 1 / stiffness;
  d.fmax = fmax;
  return d;
}

// Sets the joint's command motor to `drive`, made on first use; an idle motor (fmax 0) adds no
// row to the solver.
void set_command_motor(Simulation::Model& m, JointModel& jm, const Drive& drive) {
  const bool hinge = jm.kind != JointKind::kPrismatic;
  if (!drive.motor) {
    if (jm.command_motor == nullptr) return;
    if (hinge) {
      dJointSetAMotorParam(jm.command_motor, dParamFMax, 0);
    } else {
      dJointSetLMotorParam(jm.command_motor, dParamFMax, 0);
    }
    return;
  }
  if (jm.command_motor == nullptr) {
    dBodyID child = m.bodies[static_cast<std::size_t>(jm.child_body)].id;
    dBodyID parent = jm.parent_body == kWorld ? nullptr : m.bodies[static_cast<std::size_t>(jm.parent_body)].id;
    dVector3 axis;
    if (hinge) {
      dJointGetHingeAxis(jm.id, axis);
      jm.command_motor = dJointCreateAMotor(m.world, nullptr);
      dJointAttach(jm.command_motor, child, parent);
      dJointSetAMotorNumAxes(jm.command_motor, 1);
      dJointSetAMotorAxis(jm.command_motor, 0, 1, axis[0], axis[1], axis[2]);  // fixed in the child
    } else {
      dJointGetSliderAxis(jm.id, axis);
      jm.command_motor = dJointCreateLMotor(m.world, nullptr);
      dJointAttach(jm.command_motor, child, parent);
      dJointSetLMotorNumAxes(jm.command_motor, 1);
      dJointSetLMotorAxis(jm.command_motor, 0, 1, axis[0], axis[1], axis[2]);
    }
    dJointSetFeedback(jm.command_motor, &jm.command_feedback);
  }
  if (hinge) {
    dJointSetAMotorParam(jm.command_motor, dParamVel, drive.velocity);
    dJointSetAMotorParam(jm.command_motor, dParamCFM, drive.cfm);
    dJointSetAMotorParam(jm.command_motor, dParamFMax, drive.fmax);
  } else {
    dJointSetLMotorParam(jm.command_motor, dParamVel, drive.velocity);
    dJointSetLMotorParam(jm.command_motor, dParamCFM, drive.cfm);
    dJointSetLMotorParam(jm.command_motor, dParamFMax, drive.fmax);
  }
}

// The force (slider) or torque (hinge) a one-axis motor of the joint applied on the child in the
// last step, along the joint's axis.
double motor_load(const JointModel& jm, dJointID motor, const dJointFeedback& feedback) {
  dVector3 axis;
  const dReal* load = feedback.t1;
  if (jm.kind != JointKind::kPrismatic) {
    dJointGetAMotorAxis(motor, 0, axis);
  } else {
    // The slider's axis in the scene frame, as the feedback is: dJointGetLMotorAxis returns the
    // motor's axis as stored, in the child's frame, and a turned parent scaled the effort by the
    // cosine of its turn, or flipped it (s90ctrl D1).
    dJointGetSliderAxis(jm.id, axis);
    load = feedback.f1;
  }
  const double along = load[0] * axis[0] + load[1] * axis[1] + load[2] * axis[2];
  const double length2 = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2];
  return along / length2;
}

// Chooses, for a step of h, which dampers act as a torque from the state before the step and which
// through their motor (JointModel::damper). Explicit damping is the iteration v' = (1 - h M^-1 C) v
// in joint velocities (M the joint-space inertia, C the dampings, one per axis): every mode decays
// without reversing while h lambda_max(M^-1 C) <= 1, and lambda_max(M^-1 C) <= trace(C^1/2 M^-1
// C^1/2) = sum c_i (M^-1)_ii <= sum of the joints' damper_rate ((M^-1)_ii is the mobility of joint
// i's axis under every other constraint, which only lower it). M is block diagonal over islands (the
// world joins none), so M^-1 C is too and its eigenvalues are those of its blocks: the bound holds
// island by island. So in each island the joints of least rate stay explicit while h times their
// sum is at most 1, and the rest are implicit: each implicit damper is one more row for the solver
// (a third more time on 24 bodies), and a light link's damper cannot blow up (docs/dynamics.md).
void choose_dampers(Simulation::Model& m, double h) {
  if (m.damper_step == h) return;
  m.damper_step = h;
  std::vector<JointModel*> damped;
  for (JointModel& jm : m.joints) {
    if (jm.damper) damped.push_back(&jm);
  }
  std::sort(damped.begin(), damped.end(),
            [](const JointModel* a, const JointModel* b) { return a->damper_rate < b->damper_rate; });
  std::map<int, double> explicit_sum;  // by island
  for (JointModel* jm : damped) {
    double& island = explicit_sum[jm->island];
    island += jm->damper_rate * h;
    jm->damper_implicit = !(island <= 1);
    const double fmax = jm->damper_implicit ? dInfinity : 0;
    if (jm->kind == JointKind::kPrismatic) {
      dJointSetLMotorParam(jm->damper, dParamFMax, fmax);
    } else {
      for (int axis = 0; axis < dJointGetAMotorNumAxes(jm->damper); ++axis) {
        dJointSetAMotorParam(jm->damper, axis * dParamGroup + dParamFMax, fmax);
      }
    }
  }
}

// Chooses, for a step of h, which springs the energy balance counts as symplectic Euler keeps them
// (JointModel::spring_energy_kept). Explicit springs move as x' = x + h A x, stable and with a
// positive definite kept energy while the eigenvalues of h^2 M^-1 K are below 4; they are at most
// h^2 sum k_i (M^-1)_ii <= h^2 times the sum of the spring rates, over one island (M is block
// diagonal over islands: fingers on a palm the world holds never exchange energy). So in each
// island the springs of least rate are kept while h^2 times their sum is below 4, and a stiffer
// spring counts 1/2 k q^2, whose rise shows it: such a spring may be past what the step can carry.
// (Summed over the whole model with a bound of 1, three sprung fingers on a held palm were refused
// where each alone passed: s105spring D1.)
void choose_spring_energy(Simulation::Model& m, double h) {
  if (m.spring_step == h) return;
  m.spring_step = h;
  std::vector<JointModel*> springs;
  for (JointModel& jm : m.joints) {
    if (jm.spring_rate > 0) springs.push_back(&jm);
  }
  std::sort(springs.begin(), springs.end(),
            [](const JointModel* a, const JointModel* b) { return a->spring_rate < b->spring_rate; });
  std::map<int, double> sum;  // by island
  for (JointModel* jm : springs) {
    double& island = sum[jm->island];
    island += jm->spring_rate * h * h;
    jm->spring_energy_kept = island < 4;
  }
}

Eigen::Vector3d angular_velocity(const Simulation::Model& model, int body) {
  return body == kWorld ? Eigen::Vector3d::Zero() : vec(dBodyGetAngularVel(model.bodies[body].id));
}

// The world's frame: identity, at rest (a constant, not a function-local static whose guard every
// call would test).
const BodyFrame kWorldFrame{};

// The frame of a body, or the world's.
const BodyFrame& frame_of(const Simulation::Model& m, int body) {
  return body == kWorld ? kWorldFrame : m.frames[static_cast<std::size_t>(body)];
}

// The misalignment an exact step adds to a joint. ODE solves the constraints on velocities and
// then turns each body by its own angular velocity w over the step h. The two sides' relative
// rotation is then exp(-h w_p) exp(h w_c) = exp(h (w_c - w_p) - h^2/2 w_p x w_c + O(h^3)): the first
// term is about the hinge axis (the constraint makes it so; for fixed joints and sliders it is
// zero), the second turns the two sides out of line by h^2/2 |w_p x w_c| across the axis. ERP
// corrects the accumulated misalignment at the rate erp per step, hence the recurrence. Measured
// with dWorldStep on chains of 15 to 50 links whipping at up to 160 rad/s, the misalignment stayed
// within 1% (at most 2e-4 rad) of this drift (docs/dynamics.md).
//
// The anchor points likewise: each moves by h (v + w x r) + h^2/2 w x (w x r) + O(h^3) with r the
// anchor from its body's centre of mass; the constraint makes the first terms agree, the second
// leaves them h^2/2 |w_c x (w_c x r_c) - w_p x (w_p x r_p)| apart (across the axis for a slider).
//
// Only while the step resolves the motion: these are the leading terms of a series in |w| h, and
// a body turning a radian or more per step (a model blowing up) is no longer integrated at all;
// it earns no allowance (else a blow-up would excuse itself). Returns whether it was resolved.
bool update_exact_step_errors(Simulation::Model& m, JointModel& jm, double dt, double erp) {
  const BodyFrame& child = frame_of(m, jm.child_body);
  const BodyFrame& parent = frame_of(m, jm.parent_body);
  const Eigen::Vector3d& w_p = parent.w;
  const Eigen::Vector3d& w_c = child.w;
  const bool resolved = std::max(w_p.norm(), w_c.norm()) * dt < dynamics_internal::kResolvedTurn;
  if (!resolved) {
    jm.separation_drift *= 1 - erp;
    jm.drift *= 1 - erp;
    return false;
  }
  const Eigen::Vector3d axis = parent.R * jm.axis_parent;
  const Eigen::Vector3d r_c = child.R * jm.anchor_child, r_p = parent.R * jm.anchor_parent;
  Eigen::Vector3d apart = w_c.cross(w_c.cross(r_c)) - w_p.cross(w_p.cross(r_p));
  if (jm.kind == JointKind::kPrismatic) apart -= apart.dot(axis) * axis;
  jm.separation_drift = (1 - erp) * jm.separation_drift + 0.5 * dt * dt * apart.norm();
  if (jm.kind == JointKind::kBall) return true;  // no misalignment measured
  Eigen::Vector3d turn = w_p.cross(w_c);
  if (jm.kind == JointKind::kRevolute || jm.kind == JointKind::kContinuous) turn -= turn.dot(axis) * axis;
  jm.drift = (1 - erp) * jm.drift + 0.5 * dt * dt * turn.norm();
  return true;
}

// The force (N) or torque (N m) a joint's stop carried in the last step, from the constraint
// forces ODE reports on the child body. A slider's other rows act across its axis, so the force
// along the axis is the stop's. A hinge's stops are its limit motor, which has the stop's row only.
double stop_load(const Simulation::Model& m, const JointModel& jm) {
  const Eigen::Vector3d axis = frame_of(m, jm.parent_body).R * jm.axis_parent;
  const Eigen::Vector3d load = jm.kind == JointKind::kPrismatic ? vec(jm.feedback.f1) : vec(jm.feedback.t1);
  return std::abs(load.dot(axis));
}

}  // namespace

Simulation::Simulation(std::unique_ptr<Model> model) : model_(std::move(model)) {}
Simulation::~Simulation() = default;

std::unique_ptr<Simulation> Simulation::create(const Robot& robot, const SimulationOptions& options,
                                               const std::map<std::string, double>& initial_positions,
                                               Diagnostics& diag) {
  auto model = dynamics_internal::build_model(robot, options, initial_positions, diag);
  if (!model) return nullptr;
  // The energy at the start counts the springs as the steps will (a start speed makes the kept
  // form differ from 1/2 k q^2 already).
  if (model->options.time_step > 0 && std::isfinite(model->options.time_step)) {
    choose_spring_energy(*model, model->options.time_step);
  }
  return std::unique_ptr<Simulation>(new Simulation(std::move(model)));
}

void Simulation::step() { step(model_->options.time_step); }

void Simulation::step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("Simulation::step: dt must be positive");
  init_ode();
  Model& m = *model_;
  if (m.failed) return;
  choose_dampers(m, dt);
  choose_spring_energy(m, dt);
  // The state as of the last step (or the set-up), read once then (read_frames).
  for (std::size_t b = 0; b < m.bodies.size(); ++b) {
    if (!m.frames[b].steppable) {
      m.failed = true;
      m.failed_link = m.bodies[b].link;
      m.messages.push_back("the state of link '" + m.robot.links[m.bodies[b].link].name + "' at t = " +
                           std::to_string(m.time) +
                           " s is not finite or beyond 1e100: the simulation stopped");
      return;
    }
  }
  for (JointModel& jm : m.joints) {
    if (!jm.id) continue;
    if (jm.dof) {
      // A linear motor's row already measures the slider's rate: ODE decouples its torque (the
      // angular terms of addLimot's linear rows), so no correction for the parent's turn here.
      const Drive drive = command_drive(jm, dt);
      set_command_motor(m, jm, drive);
      jm.motor_fmax = drive.motor ? drive.fmax : 0.0;
      jm.effort = drive.feed_forward;
      jm.damping_effort = jm.damper_implicit ? 0.0 : -jm.damping * jm.qdot;
      const double total = jm.effort + jm.damping_effort - jm.stiffness * jm.q;
      if (jm.kind == JointKind::kPrismatic) {
        dJointAddSliderForce(jm.id, total);
      } else {
        dJointAddHingeTorque(jm.id, total);
      }
      jm.q_before = jm.q;
      jm.qdot_before = jm.qdot;
    } else if (jm.kind == JointKind::kBall && jm.damping > 0 && !jm.damper_implicit) {
      const Eigen::Vector3d w = angular_velocity(m, jm.child_body) - angular_velocity(m, jm.parent_body);
      const Eigen::Vector3d tau = -jm.damping * w;
      dBodyAddTorque(m.bodies[jm.child_body].id, tau.x(), tau.y(), tau.z());
      if (jm.parent_body != kWorld) dBodyAddTorque(m.bodies[jm.parent_body].id, -tau.x(), -tau.y(), -tau.z());
    }
  }
  // Stops of ranges of 2 pi or more act on the unwrapped position (ode_model.cc).
  for (JointModel& jm : m.joints) {
    if (jm.limit_motor) dJointSetAMotorAngle(jm.limit_motor, 0, jm.q);
  }
  try {
    if (m.quickstep) {
      dWorldQuickStep(m.world, dt);
    } else {
      dWorldStep(m.world, dt);
    }
  } catch (const dynamics_internal::OdeInternalError& error) {
    m.failed = true;
    m.interrupted = true;
    m.messages.push_back(std::string(error.what()) + " (at t = " + std::to_string(m.time) +
                         " s; the simulation stopped)");
    return;
  }
  dynamics_internal::read_frames(m);
  const double erp = m.options.erp;
  for (JointModel& jm : m.joints) {
    if (!jm.id) continue;
    const bool resolved = update_exact_step_errors(m, jm, dt, erp);
    if (jm.dof) {
      if (jm.kind == JointKind::kPrismatic) {
        jm.q = dJointGetSliderPosition(jm.id);
        jm.qdot = dynamics_internal::slider_rate(jm.id);
      } else {
        const double angle = dJointGetHingeAngle(jm.id);
        jm.q += std::remainder(angle - jm.ode_angle, 2 * std::numbers::pi);
        jm.ode_angle = angle;
        jm.qdot = dJointGetHingeAngleRate(jm.id);
      }
      if (jm.motor_fmax > 0) {
        // At most fmax: the projection's rounding never reports more.
        jm.effort += std::clamp(motor_load(jm, jm.command_motor, jm.command_feedback), -jm.motor_fmax, jm.motor_fmax);
      }
      if (jm.damper_implicit) jm.damping_effort = motor_load(jm, jm.damper, jm.damper_feedback);
      const double dq = jm.q - jm.q_before;
      // A stop acts once the joint is past it: the step that crosses it can carry the joint its
      // whole travel beyond, and the stop's ERP (the world's) then takes back erp of the excess per
      // step. Every step's travel while past the stop counts (QuickStep resolves the stop only in
      // part, and the joint may go on a little before it turns back).
      const bool past = jm.stops && (jm.q < jm.lower || jm.q > jm.upper);
      jm.stop_overshoot = (1 - erp) * jm.stop_overshoot + (past && resolved ? std::abs(dq) : 0.0);
      if (jm.stops) jm.stop_yield = stop_load(m, jm) * dt * m.options.cfm / erp;
      // The work of a force over a step: symplectic Euler changes the speed by h F / M and the
      // kinetic energy by exactly h F (qdot before + qdot after) / 2, and that (not F dq = h F qdot
      // after) is what the kept energy of the springs balances against (choose_spring_energy): a
      // damped 20 g finger on a stiff spring read F dq's difference, h^2 F^2 / 2M a step, as 1%
      // of energy created.
      const double travel = 0.5 * dt * (jm.qdot_before + jm.qdot);
      m.dissipated -= jm.damping_effort * travel;
      m.actuator_work += jm.effort * travel;
    } else if (jm.kind == JointKind::kBall && jm.damping > 0) {
      const Eigen::Vector3d w = angular_velocity(m, jm.child_body) - angular_velocity(m, jm.parent_body);
      const Eigen::Vector3d tau = jm.damper_implicit ? vec(jm.damper_feedback.t1) : Eigen::Vector3d(-jm.damping * w);
      m.dissipated -= tau.dot(w) * dt;
    }
  }
  m.time += dt;
  ++m.steps;
  for (std::string& message : dynamics_internal::take_ode_messages()) {
    if (m.messages.size() < 100) m.messages.push_back(std::move(message));
  }
}

double Simulation::time() const { return model_->time; }
std::uint64_t Simulation::steps() const { return model_->steps; }
const Robot& Simulation::robot() const { return model_->robot; }
const SimulationOptions& Simulation::options() const { return model_->options; }
Stepper Simulation::stepper() const { return model_->quickstep ? Stepper::kQuickStep : Stepper::kWorldStep; }
std::string_view Simulation::stepper_name() const {
  return model_->quickstep ? "dWorldQuickStep" : "dWorldStep";
}
int Simulation::body_count() const { return static_cast<int>(model_->bodies.size()); }

bool Simulation::steppable() const {
  if (model_->failed) return false;
  for (const dynamics_internal::BodyFrame& frame : model_->frames) {
    if (!frame.steppable) return false;
  }
  return true;
}
const std::vector<std::string>& Simulation::ode_messages() const { return model_->messages; }

std::vector<JointState> Simulation::joint_states() const {
  std::vector<JointState> states;
  for (const JointModel& jm : model_->joints) {
    if (!jm.dof) continue;
    states.push_back({model_->robot.joints[jm.joint].name, jm.kind, jm.q, jm.qdot, jm.effort});
  }
  return states;
}

std::optional<JointState> Simulation::joint_state(std::string_view joint) const {
  const auto found = model_->joint_index.find(joint);
  if (found == model_->joint_index.end() || !model_->joints[found->second].dof) return std::nullopt;
  const JointModel& jm = model_->joints[found->second];
  return JointState{model_->robot.joints[jm.joint].name, jm.kind, jm.q, jm.qdot, jm.effort};
}

std::vector<LinkPose> Simulation::link_poses() const {
  std::vector<LinkPose> poses;
  poses.reserve(model_->links.size());
  for (std::size_t l = 0; l < model_->links.size(); ++l) {
    const dynamics_internal::LinkModel& link = model_->links[l];
    LinkPose pose;
    pose.name = model_->robot.links[l].name;
    if (link.body == kWorld) {
      pose.X_SL = link.X_BL;
    } else {
      const dBodyID id = model_->bodies[link.body].id;
      const Eigen::Isometry3d X_SB = body_pose(id);
      pose.X_SL = X_SB * link.X_BL;
      pose.w_SL_S = vec(dBodyGetAngularVel(id));
      pose.v_SLo_S = vec(dBodyGetLinearVel(id)) + pose.w_SL_S.cross(pose.X_SL.translation() - X_SB.translation());
    }
    poses.push_back(std::move(pose));
  }
  return poses;
}

std::optional<LinkPose> Simulation::link_pose(std::string_view link) const {
  const auto found = model_->link_index.find(link);
  if (found == model_->link_index.end()) return std::nullopt;
  return link_poses()[found->second];
}

bool Simulation::set_command(const JointCommand& command, std::string* error) {
  const auto fail = [&](std::string why) {
    if (error) *error = "command for '" + command.joint + "' rejected: " + why;
    return false;
  };
  const auto found = model_->joint_index.find(command.joint);
  if (found == model_->joint_index.end()) return fail("no such joint");
  JointModel& jm = model_->joints[found->second];
  if (!jm.dof) return fail(std::string("a ") + to_string(jm.kind) + " joint takes no command");
  for (double value : {command.effort, command.position, command.velocity, command.kp, command.kd}) {
    if (!std::isfinite(value)) return fail("values must be finite");
  }
  if (command.kp < 0 || command.kd < 0) return fail("gains must not be negative");
  jm.command = command;
  return true;
}

void Simulation::clear_command(std::string_view joint) {
  const auto found = model_->joint_index.find(joint);
  if (found != model_->joint_index.end()) model_->joints[found->second].command.reset();
}

void Simulation::clear_commands() {
  for (JointModel& jm : model_->joints) jm.command.reset();
}

SimulationHealth Simulation::health(const HealthTolerances& tolerances) const {
  const Model& m = *model_;
  SimulationHealth h;
  h.finite = !m.failed;
  h.not_finite_link = m.failed_link;
  h.dissipated_energy = m.dissipated;
  h.actuator_work = m.actuator_work;
  // Poses and angular velocities as of the last step (Model::frames), which is when the state
  // last changed.
  for (std::size_t b = 0; b < m.bodies.size(); ++b) {
    const BodyModel& body = m.bodies[b];
    const BodyFrame& f = m.frames[b];
    if (!f.finite) {
      h.finite = false;
      if (h.not_finite_link < 0) h.not_finite_link = body.link;
    }
    const Eigen::Vector3d& v = f.v;
    const Eigen::Vector3d Iw = f.R * (body.inertia * (f.R.transpose() * f.w));
    h.kinetic_energy += 0.5 * body.mass * v.squaredNorm() + 0.5 * f.w.dot(Iw);
    h.potential_energy -= body.mass * m.options.gravity.dot(f.p);
  }
  if (!h.finite) return h;
  for (const JointModel& jm : m.joints) {
    if (jm.dof) {
      h.spring_energy += 0.5 * jm.stiffness * jm.q * jm.q;
      h.potential_energy += 0.5 * jm.stiffness * jm.q * jm.q;
      if (jm.spring_energy_kept) h.potential_energy -= 0.5 * m.spring_step * jm.stiffness * jm.q * jm.qdot;
    }
    if (jm.limited) {
      const double violation = std::max({jm.lower - jm.q, jm.q - jm.upper, 0.0});
      const double bound = (jm.kind == JointKind::kPrismatic ? tolerances.limit_linear : tolerances.limit_angular) +
                           (jm.stops ? jm.stop_overshoot + jm.stop_yield : 0.0);
      if (violation / bound > h.worst_limit_ratio) {
        h.worst_limit_ratio = violation / bound;
        h.worst_limit_violation = violation;
        h.limit_bound = bound;
        h.worst_limit_joint = jm.joint;
      }
    }
    if (!jm.id) continue;
    const BodyFrame& C = frame_of(m, jm.child_body);
    const BodyFrame& P = frame_of(m, jm.parent_body);
    Eigen::Vector3d d = (C.R * jm.anchor_child + C.p) - (P.R * jm.anchor_parent + P.p);
    if (jm.kind == JointKind::kPrismatic) {
      const Eigen::Vector3d a = P.R * jm.axis_parent;
      d -= a.dot(d) * a;
    }
    const double separation = d.norm();
    if (separation > h.worst_joint_separation) {
      h.worst_joint_separation = separation;
      h.worst_separation_joint = jm.joint;
    }
    const double separation_bound = tolerances.separation + jm.separation_drift;
    if (separation / separation_bound > h.worst_separation_ratio) {
      h.worst_separation_ratio = separation / separation_bound;
      h.separation_at_worst_ratio = separation;
      h.separation_bound = separation_bound;
      h.worst_separation_ratio_joint = jm.joint;
    }
    double misalignment = 0;
    if (jm.kind == JointKind::kRevolute || jm.kind == JointKind::kContinuous) {
      const Eigen::Vector3d ac = C.R * jm.axis_child, ap = P.R * jm.axis_parent;
      misalignment = std::atan2(ac.cross(ap).norm(), ac.dot(ap));
    } else if (jm.kind == JointKind::kFixed || jm.kind == JointKind::kPrismatic) {
      const Eigen::Quaterniond relative(Eigen::Matrix3d(P.R.transpose() * C.R));
      misalignment = jm.rotation0.angularDistance(relative);
    }
    if (misalignment > h.worst_joint_misalignment) {
      h.worst_joint_misalignment = misalignment;
      h.worst_misalignment_joint = jm.joint;
    }
    const double bound = tolerances.misalignment + jm.drift;
    if (misalignment / bound > h.worst_misalignment_ratio) {
      h.worst_misalignment_ratio = misalignment / bound;
      h.misalignment_at_worst_ratio = misalignment;
      h.misalignment_bound = bound;
      h.worst_misalignment_ratio_joint = jm.joint;
    }
  }
  // Region: each body's centre of mass against its reach from its root link's origin.
  for (std::size_t b = 0; b < m.bodies.size(); ++b) {
    const BodyModel& body = m.bodies[b];
    if (!std::isfinite(body.reach)) continue;
    const dynamics_internal::LinkModel& root = m.links[body.root_link];
    const BodyFrame& R = frame_of(m, root.body);
    const Eigen::Vector3d origin = R.R * root.X_BL.translation() + R.p;
    const double distance = (m.frames[b].p - origin).norm();
    const double allowed = body.reach * (1 + tolerances.region_margin_relative) + tolerances.region_margin_absolute;
    if (distance / allowed > h.worst_region_ratio) {
      h.worst_region_ratio = distance / allowed;
      h.worst_region_distance = distance;
      h.worst_region_link = body.link;
    }
  }
  return h;
}

}  // namespace rdtf
