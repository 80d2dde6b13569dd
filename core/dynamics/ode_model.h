// Internals of rdtf_dynamics shared by its .cc files: the robot's structure (tree order, where
// massless links go, kinematics) and the ODE model behind a Simulation. Not installed.
#pragma once

#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <ode/ode.h>

#include "rdtf/dynamics.h"

namespace rdtf::dynamics_internal {

inline constexpr int kWorld = -1;       // Carried by the world (does not move).
inline constexpr int kUnresolved = -2;  // A massless link nothing carries: cannot be simulated.
inline constexpr double kInfinity = std::numeric_limits<double>::infinity();
// No body's position, speed or angular speed may exceed this (SI units) before a step: a state
// that blew up this far is meaningless, and stepping it further overflows into NaN, on which ODE
// asserts and aborts the process.
inline constexpr double kStateBound = 1e100;
// A step resolves a body's rotation while it turns by less than this many radians (|w| h): the
// errors an exact step makes (Simulation::step) are allowed only then.
inline constexpr double kResolvedTurn = 1.0;

std::string number(double value);  // "%.6g"
std::string vector_text(const Eigen::Vector3d& v);
std::string node_pointer(int node);  // "/nodes/N", or "" for no node
const char* kind_name(JointKind kind);

bool one_dof(JointKind kind);  // revolute, continuous, prismatic
bool is_massless(const Link& link);  // mass and inertia exactly zero (an empty link)

// Checks the cross references (indices in range, parent/child agree, no cycle). Each problem is
// an error with `code`; returns false when there was one (nothing else can then be trusted).
bool check_structure(const Robot& robot, const char* code, Diagnostics& diag);

// Links parents first (roots in robot order, then depth first). Assumes check_structure passed.
std::vector<int> tree_order(const Robot& robot);
// The root link of each link's tree.
std::vector<int> root_of(const Robot& robot, const std::vector<int>& order);

// Links welded together by fixed joints move as one rigid body (as MuJoCo's fusestatic and
// SDFormat's lumping do): one ODE body per group, with the group's combined mass properties.
struct WeldGroup {
  int top = -1;           // The group's link nearest the root: its frame T is the group's frame
  std::vector<int> links;  // Tree order, top first
  bool welded_to_world = false;  // Holds a root the world holds: the group never moves
  // Combined over the links with mass: m, p_ToBcm_T (centre of mass in T) and I_Bcm_T (about
  // it, T's axes), by the parallel-axis theorem. Zero for a group without mass.
  MassProperties merged;
  bool bounded = false;  // merged is the bound mass and inertia (a massless moving group)
};

struct WeldGroups {
  std::vector<int> group_of;  // robot.links order
  std::vector<WeldGroup> groups;
  // The robot's extent at rest (m): the diagonal of the box holding every link origin and centre
  // of mass. It scales what counts as an inertia of zero (is_point_mass).
  double extent = 0;
};

// A link with mass whose inertia is zero to rounding: every entry within 4 eps m l^2, l the
// robot's extent. Moving a point mass m across the robot adds m (d^2 1 - d d^T), d <= l, to the
// inertia of any body or joint it joins, whose rounding (three products and two sums) is up to
// 4 eps m l^2: a tensor below it is lost in that arithmetic, so it cannot tell the part from a
// point. CAD exporters leave such residues where a part's tensor is zero (iCub's l_ankle_2: 0.27
// kg with only ixz = 2^-66 kg m^2), and a tensor of one nonzero product is not positive definite.
bool is_point_mass(const MassProperties& inertial, double extent);

// How many links of the group add mass or inertia to its body. With two or more, the body's
// combined tensor is its own, not any one link's: that is what is checked and simulated.
long adding_links(const Robot& robot, const WeldGroup& group);

// The moving bodies (weld groups that move) in the largest island: bodies joined by the joints
// ODE makes (not fixed ones, inside a body; not floating or planar ones, which it does not
// constrain), as Simulation::Model counts them once built. It chooses the stepper.
int largest_island(const Robot& robot, const WeldGroups& welds);

// Assumes check_structure passed. `rest`: X_SL of every link at the rest pose (fixed joints keep
// the poses within a group at rest anyway). Links whose mass properties are not finite are left
// out of the sums (they are errors of their own). A moving group without mass gets `bound_mass`
// at its top's origin with inertia bound_inertia x identity when both are positive.
WeldGroups weld_groups(const Robot& robot, const std::vector<int>& order,
                       const std::vector<Eigen::Isometry3d>& rest, bool floating_root, double bound_mass = 0,
                       double bound_inertia = 0);
// A group that needs an ODE body: not welded to the world, and with mass (or bounded).
bool moves(const WeldGroup& group);

// The pose of the joint frame relative to the parent link frame at position q.
Eigen::Isometry3d joint_motion(const Joint& joint, double q);
// X_SL of every link with the one-dof joints at q (robot.joints order; others at rest). Roots
// stay at their X_SL.
std::vector<Eigen::Isometry3d> forward_kinematics(const Robot& robot, const std::vector<int>& order,
                                                  const std::vector<double>& q);

// A bound on the distance of each link's origin from its root's origin, over every position
// (infinite below an unlimited prismatic or a floating joint).
std::vector<double> reach_bounds(const Robot& robot, const std::vector<int>& order);

struct BodyModel {
  dBodyID id = nullptr;
  int link = -1;   // The top link of its weld group
  int links = 1;   // Links welded into it
  double mass = 0;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // About the COM, top link axes (= body axes)
  Eigen::Vector3d com_L = Eigen::Vector3d::Zero();     // p_ToBcm_T: the body origin in the top link
  double reach = kInfinity;  // Bound on the COM's distance from its root link's origin
  int root_link = -1;
};

// A body's state in the scene frame, read from ODE once per step (read_frames) for the health
// measurements, the exact-step errors and the check before the next step: ODE's state changes only
// in a step, so one read serves them all (quaternion to matrix once, not once per use).
struct BodyFrame {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  bool finite = true;      // position, quaternion and velocities all finite
  bool steppable = true;   // finite, and no position or velocity component beyond kStateBound
};

struct LinkModel {
  int body = kWorld;  // Index into bodies, or kWorld.
  Eigen::Isometry3d X_BL = Eigen::Isometry3d::Identity();  // In its body (X_SL for the world)
};

struct JointModel {
  int joint = -1;  // robot.joints index
  JointKind kind = JointKind::kFixed;
  dJointID id = nullptr;  // Nothing for a floating joint or one inside a body (massless link)
  dJointID friction_motor = nullptr;
  // Commands in position and velocity mode: a one-axis motor (angular on a hinge, linear on a
  // slider) through which the solver applies the PD law implicitly (Simulation::step), made at
  // the first such command; its feedback gives the effort it applied.
  dJointID command_motor = nullptr;
  dJointFeedback command_feedback{};
  // A limited hinge's stops: a user-mode angular motor whose stops act on the unwrapped position
  // (set before every step), not the hinge's own, which act on the wrapped angle.
  dJointID limit_motor = nullptr;
  int child_body = -1;
  int parent_body = kWorld;
  // The joint frame's origin on each side (child body, parent body or world), and the axis.
  Eigen::Vector3d anchor_child = Eigen::Vector3d::Zero();
  Eigen::Vector3d anchor_parent = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_child = Eigen::Vector3d::UnitX();
  Eigen::Vector3d axis_parent = Eigen::Vector3d::UnitX();
  Eigen::Quaterniond rotation0 = Eigen::Quaterniond::Identity();  // R_parent^T R_child at q0
  bool dof = false;
  double q = 0;           // unwrapped position
  double qdot = 0;
  double ode_angle = 0;   // ODE's (wrapped) hinge angle after the last step
  bool limited = false;
  bool stops = false;  // ODE enforces the limits (every limited hinge and slider)
  double lower = 0;
  double upper = 0;
  // What an exact step leaves, for the health bounds (updated by Simulation::step):
  // `drift` (rad), the misalignment that integrating each body's rotation over a step adds (a
  // second-order term, 1/2 h^2 |w_parent x w_child| across the axis) and ERP removes at the rate
  // erp per step; `stop_overshoot` (rad or m), how far past a stop the joint may be, since ODE's
  // stop acts once the joint is past it: its travel while past the stop, taken back at erp per step.
  // `separation_drift` (m): likewise for the anchor points, which an exact step leaves
  // h^2/2 |w_c x (w_c x r_c) - w_p x (w_p x r_p)| apart (r: the anchor from each body's centre of
  // mass; across the axis for a slider).
  double drift = 0;
  double separation_drift = 0;
  double stop_overshoot = 0;
  // A stop is a soft constraint, a spring k = ERP / (h CFM): under the load F it carries it gives
  // F / k (rad or m), read from the constraint forces ODE reports (feedback) after each step.
  double stop_yield = 0;
  dJointFeedback feedback{};  // Of `id` (or of limit_motor), for stop_yield

  double effort_limit = 0;  // 0: none
  double velocity_limit = 0;  // 0: none; bounds the speed a command drives the joint at
  double damping = 0;
  double stiffness = 0;
  std::optional<JointCommand> command;
  double effort = 0;  // actuator effort applied in the last step
  double motor_fmax = 0;  // the command motor's force bound in the last step (0: idle)
  // Within a step: the position and speed before it and the damping effort applied in it (for the
  // work).
  double q_before = 0;
  double qdot_before = 0;
  double damping_effort = 0;
  // Damping (docs/dynamics.md, "Joint forces"). A torque -c qdot from the state before the step is
  // forward Euler: it reverses the joint's speed once c h exceeds the inertia it moves and blows up
  // past twice that (arm3 with a 6 cm forearm: c h / I = 3.1). Where that can happen the damper is
  // this motor instead (angular on a hinge, three axes on a ball, linear on a slider): speed 0,
  // unbounded force, constraint force mixing 1 / c, which the solver makes the implicit damper
  // tau = -c qdot(t + h). Made for every damped joint, idle (no row) while the damping is explicit.
  dJointID damper = nullptr;
  dJointFeedback damper_feedback{};
  // c times the joint's mobility with every constraint removed (1/s): a^T I^-1 a of its two bodies
  // (on a ball, tr I^-1, its three axes summed); the constraints only lower the mobility. Infinite
  // on a slider, which is always implicit (what it moves depends on where it is).
  double damper_rate = 0;
  bool damper_implicit = false;
  // The spring's share of the energy balance (docs/dynamics.md, "Energy balance"). ODE applies the
  // spring from the position before the step and moves the position with the speed after it
  // (symplectic Euler), which keeps 1/2 k q^2 - 1/2 h k q qdot, not 1/2 k q^2: the latter ripples
  // by about h omega / 2 of the energy, and a 20 g finger on a spring of 0.2 N m/rad (omega 135
  // rad/s) read as 7% of energy created (s101gate D8). The kept form is positive definite only
  // while h^2 k / I < 4; `spring_rate`, k times the joint's mobility with every constraint removed
  // (1/s^2, an upper bound of k / I, as damper_rate bounds c / I; on a slider k (1/m_c + 1/m_p)),
  // says which springs are inside that (Simulation::step, choose_spring_energy).
  double spring_rate = 0;
  bool spring_energy_kept = false;  // the balance counts this spring as symplectic Euler keeps it
  int island = -1;  // the island of the joint's bodies (ode_model.cc, islands): springs of two never meet
};

}  // namespace rdtf::dynamics_internal

namespace rdtf {

struct Simulation::Model {
  Robot robot;
  SimulationOptions options;
  dWorldID world = nullptr;
  // Each world steps with its own threading implementation: ODE's default one is a single global
  // object, and worlds stepped on two threads at once (validation workers, the live simulation)
  // corrupt it ("ODE INTERNAL ERROR ... ReleaseAJob").
  dThreadingImplementationID threading = nullptr;
  std::vector<dynamics_internal::BodyModel> bodies;
  std::vector<dynamics_internal::BodyFrame> frames;   // bodies order, as of the last step
  std::vector<dynamics_internal::LinkModel> links;    // robot.links order
  std::vector<dynamics_internal::JointModel> joints;  // robot.joints order
  std::vector<int> root_links;
  std::map<std::string, int, std::less<>> joint_index;
  std::map<std::string, int, std::less<>> link_index;
  bool quickstep = false;
  int largest_island = 0;  // Bodies of the largest island (ode_model.cc, largest_island).
  double time = 0;
  std::uint64_t steps = 0;
  double dissipated = 0;
  double actuator_work = 0;
  double damper_step = 0;  // the step for which the dampers were last chosen explicit or implicit
  double spring_step = 0;  // the step for which the springs' energy was last chosen (0: none yet)
  std::vector<std::string> messages;
  // The state left what ODE can step (a value not finite or beyond kStateBound), or ODE stopped a
  // step with an internal error: the state is unusable, health() reports it not finite, and
  // step() does nothing more. `interrupted`: ODE was left mid-step by an exception, so its
  // threading object still holds jobs and is not freed (freeing it asserts).
  bool failed = false;
  int failed_link = -1;  // The body's top link when a state beyond stepping stopped it; -1 otherwise
  bool interrupted = false;

  Model() = default;
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;
  ~Model();
};

namespace dynamics_internal {

// Builds the ODE world (ode_model.cc). Nothing, with errors, when the robot cannot be simulated.
std::unique_ptr<Simulation::Model> build_model(const Robot& robot, const SimulationOptions& options,
                                               const std::map<std::string, double>& initial,
                                               Diagnostics& diag);

Eigen::Isometry3d body_pose(dBodyID body);  // X_SB
void read_frames(Simulation::Model& model);  // model.frames from ODE's bodies (after set-up and every step)
// Reads back the ODE state of the one-dof joints without unwrapping (after set-up).
void prime_joint_states(Simulation::Model& model);
// The rate of a slider's position: the exact time derivative of dJointGetSliderPosition, the
// child's centre of mass moving along the axis relative to the point of the parent it passes,
// v_c - v_p - w_p x (p_c - p_p). ODE's dJointGetSliderPositionRate leaves out the parent's
// rotation, so a slider on a turning parent reported a speed it did not have, and its damping
// pushed it (s90ctrl D2, D3).
double slider_rate(dJointID slider);
// The ODE messages the calling thread received since the last call.
std::vector<std::string> take_ode_messages();

// ODE's debug and error handlers throw this instead of letting ODE abort() the process (which it
// does after either handler returns). Only Simulation::step lets ODE run where it can be raised.
struct OdeInternalError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace dynamics_internal
}  // namespace rdtf
