// Dynamics of an RDTF robot: physical checks on its mass properties and joints, an ODE model of it,
// the validation run that gates a model (docs/dynamics.md), and a live simulation for the daemon.
//
// Frames: every pose, position and velocity in this API is in the scene frame S (glTF: Y up) or a
// link frame L (the robot's frames, docs/format.md). ODE's body frames (link frame moved to the
// centre of mass) stay inside the implementation.
//
// ODE is process-global state: call init_ode() once before anything else touches ODE (Simulation
// and validate_dynamics call it themselves). A Simulation is thread-confined: one thread at a time
// uses it; any thread may own it (each thread's ODE data is allocated on first use).
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rdtf/convert.h"
#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/robot.h"

namespace rdtf {

inline constexpr double kStandardGravity = 9.80665;  // m/s^2

// ---------------------------------------------------------------------------------------------
// Physical checks: pure functions of the robot (and optionally its geometry's bounds).

struct PhysicalCheckOptions {
  // A joint whose two links' masses differ by more than this factor is an error, when QuickStep
  // steps it: when the model's largest island (bodies joined by joints), which chooses the stepper
  // for the whole world, has at least mass_ratio_island_bodies moving bodies. dWorldStep solves
  // each island's constraints exactly and holds such joints.
  // validate_dynamics sets it from the stepper it runs (SimulationOptions): for kAuto, islands
  // beyond exact_rerun_max_bodies (up to it, a failed QuickStep run is judged again with
  // dWorldStep); 0 for kQuickStep (every joint judged); none for kWorldStep.
  double max_mass_ratio = 1e3;
  int mass_ratio_island_bodies = 0;
  // |I - I^T| may reach this much of the largest |I_ij|.
  double symmetry_tolerance = 1e-9;
  // Principal moments A, B, C must satisfy A + B >= C - triangle_tolerance * (A + B + C).
  double triangle_tolerance = 1e-6;
  // The smallest principal moment A must exceed positive_definite_tolerance * C. A tensor that is
  // singular in decimal (an ideal rod's, as published) is stored with entries rounded by u = 1.1e-16
  // and its eigenvalues found to within a few u C, so its A comes out as +-1e-17 C by chance; this
  // is far above that noise and far below any real part (a rod of A / C = 1e-12 would be 0.8 um
  // thick per metre of length).
  double positive_definite_tolerance = 1e-12;
  // Computed inertials: half the trace (the polar moment) may fall this much (relative) below the
  // smallest any solid of the link's volumes and densities can have (that of balls).
  double solid_bound_tolerance = 1e-6;
  // The centre of mass may lie this far outside its link's geometry bounds, relative to the
  // bounds' diagonal.
  double geometry_tolerance = 1e-6;
  // An authored inertia's polar moment may reach this many times m R^2, the most a mass m inside
  // the geometry's bounds can have (LINK_INERTIA_ABOVE_GEOMETRY_BOUND). Published robots' visuals
  // are often simpler and smaller than the body (1.0 to 3.6 times the bound in a UR-like, a PR2-like
  // and a Gen3-like arm's links): 10 lets a body reach about 3 times further than its geometry, and
  // still flags what is wrong by orders (kg mm^2 as kg m^2: 1e6; placeholder inertias of 1 kg m^2
  // on a 1 kg, 7 cm wheel: 300).
  double inertia_geometry_factor = 10;
  // Whether the root links will float: a massless root is then not held by the world.
  bool floating_root = false;
  // A moving body without mass (a link, or links welded by fixed joints, with no mass at all) is
  // simulated with this mass (kg) and inertia (kg m^2 about each axis) when both are positive, as
  // MuJoCo's boundmass/boundinertia; validate_dynamics takes them from SimulationOptions. Off (0)
  // by default: such a link is then an error (LINK_MASS_ZERO) naming these options.
  double bound_mass = 0;
  double bound_inertia = 0;
  // With the bound, a massless moving link is a warning (default), or still an error if this is set.
  bool massless_link_error = false;
};

// Axis-aligned bounds of each link's geometry in its link frame (robot.links order); nothing for
// a link without geometry. Skinned meshes count whole in each bone they are bound to (a superset
// of the bone's part).
using LinkBounds = std::vector<std::optional<Eigen::AlignedBox3d>>;
LinkBounds link_geometry_bounds(const GltfAsset& asset, const Robot& robot);

// Appends one diagnostic per failed condition (docs/dynamics.md lists the codes), each naming the
// link or joint and its glTF node (/nodes/N) with the numbers that failed. `bounds` (optional)
// enables the centre-of-mass-inside-geometry check.
void check_physics(const Robot& robot, const PhysicalCheckOptions& options, const LinkBounds* bounds,
                   Diagnostics& diag);

// ---------------------------------------------------------------------------------------------
// ODE.

// dInitODE2 once per process (thread-safe, idempotent) and ODE's data for the calling thread.
// ODE's messages (e.g. "LCP internal error") are counted per thread instead of printed.
void init_ode();

enum class Stepper { kAuto, kWorldStep, kQuickStep };

struct SimulationOptions {
  // In the scene frame. glTF is Y up; a model whose content is Z up sets {0, 0, -g}.
  Eigen::Vector3d gravity{0, -kStandardGravity, 0};
  bool floating_root = false;  // Default: every root link is fixed to the world.
  double time_step = 1e-3;     // s; step() without an argument.
  Stepper stepper = Stepper::kAuto;
  // kAuto: dWorldStep while the largest island (bodies joined by joints; the world joins none)
  // has fewer bodies than this, QuickStep from it. dWorldStep solves each island on its own; 27 is
  // where QuickStep (50 iterations) became the cheaper of the two per step for one island, chains
  // and trees alike (docs/dynamics.md); below it dWorldStep is both cheaper and exact.
  int quickstep_min_bodies = 27;
  int quickstep_iterations = 50;  // Gazebo's defaults.
  double quickstep_sor = 1.3;
  double erp = 0.2;
  double cfm = 1e-10;
  // Mass (kg) and inertia (kg m^2 about each axis, at the top link's origin) given to a moving
  // body that has no mass, when both are positive (PhysicalCheckOptions::bound_mass). Off: 0.
  double bound_mass = 0;
  double bound_inertia = 0;
};

// A joint with one degree of freedom (revolute, continuous, prismatic). Position in rad or m
// (continuous joints unwrapped: they count turns), velocity in rad/s or m/s, effort the actuator
// torque or force applied in the last step (after clamping to the joint's effort limit).
struct JointState {
  std::string name;
  JointKind kind = JointKind::kRevolute;
  double position = 0;
  double velocity = 0;
  double effort = 0;
};

struct LinkPose {
  std::string name;
  Eigen::Isometry3d X_SL = Eigen::Isometry3d::Identity();  // Link frame in the scene frame.
  Eigen::Vector3d v_SLo_S = Eigen::Vector3d::Zero();       // Velocity of the link origin.
  Eigen::Vector3d w_SL_S = Eigen::Vector3d::Zero();        // Angular velocity.
};

enum class CommandMode { kTorque, kPosition, kVelocity };

// Held until replaced or cleared. Torque: effort. Position: kp (position - q) + kd (velocity -
// qdot) + effort. Velocity: kd (velocity - qdot) + effort. Clamped to the joint's effort limit.
// A command's effort (feed-forward plus the gains' terms) is clamped to the joint's authored effort
// limit, or to this where none is authored: N m (revolute) or N (prismatic). Any finite command,
// however large, then stays a force ODE can step.
inline constexpr double kDefaultEffortLimit = 1000;

struct JointCommand {
  std::string joint;
  CommandMode mode = CommandMode::kTorque;
  double effort = 0;    // N m or N (feed-forward in the position and velocity modes)
  double position = 0;  // rad or m
  double velocity = 0;  // rad/s or m/s
  double kp = 0;        // N m/rad or N/m
  double kd = 0;        // N m s/rad or N s/m
};

// What counts as a limit violated, a joint apart or out of line or a body out of its region, for
// SimulationHealth's ranking. The limit, separation and misalignment tolerances are floors: each
// joint's bound adds the error an exact step of ODE makes at its current speeds (docs/dynamics.md).
struct HealthTolerances {
  double limit_angular = 1e-2;           // rad
  double limit_linear = 1e-3;            // m
  double region_margin_relative = 0.1;   // of each body's reach bound
  double region_margin_absolute = 0.01;  // m
  double misalignment = 1e-2;            // rad
  double separation = 1e-3;              // m
};

// The state's physics, for watching a run (validation, or a live model).
struct SimulationHealth {
  bool finite = true;                   // Every body's position, orientation and velocities.
  int not_finite_link = -1;             // robot.links index of the first body that is not; -1: none
                                        // (or ODE stopped the run without saying which)
  double kinetic_energy = 0;            // J
  double potential_energy = 0;          // J: gravity (relative to the scene origin) and springs
  double spring_energy = 0;             // J: sum 1/2 k q^2 of the joint springs (in potential_energy)
  double dissipated_energy = 0;         // J: work of the joint damping so far
  double actuator_work = 0;             // J: work of the commands so far
  double worst_joint_separation = 0;    // m between a joint's anchor points on its two bodies
  int worst_separation_joint = -1;      // robot.joints index
  // The joint furthest apart relative to its bound: separation / (tolerances.separation + the
  // drift an exact step makes at its speeds), > 1: beyond it. Its separation and bound.
  double worst_separation_ratio = 0;
  double separation_at_worst_ratio = 0;  // m
  double separation_bound = 0;           // m
  int worst_separation_ratio_joint = -1;
  double worst_joint_misalignment = 0;  // rad: axis (hinge) or relative rotation (fixed, slider)
  int worst_misalignment_joint = -1;
  // The joint furthest out of line relative to its bound: misalignment / (tolerances.misalignment
  // + the drift an exact step makes at its speeds), > 1: beyond it. Its misalignment and bound.
  double worst_misalignment_ratio = 0;
  double misalignment_at_worst_ratio = 0;  // rad
  double misalignment_bound = 0;           // rad
  int worst_misalignment_ratio_joint = -1;
  double worst_limit_violation = 0;     // rad or m beyond a limit: the joint furthest beyond
  // Its violation relative to its bound (> 1: violated): the tolerance, plus for a stop ODE
  // enforces the joint's travel while past it (ODE's stops act once a joint is past them),
  // decaying at the stop's ERP.
  double worst_limit_ratio = 0;
  double limit_bound = 0;               // rad or m
  int worst_limit_joint = -1;
  // A body's centre of mass cannot get further from its root link's origin than its reach bound
  // (joint offsets, centre-of-mass offset and prismatic travel along its path) plus the margins.
  double worst_region_ratio = 0;        // distance / allowed distance (> 1: out of its region)
  double worst_region_distance = 0;     // m
  int worst_region_link = -1;           // robot.links index of that body's link
};

class Simulation {
 public:
  // Builds the ODE model of `robot` with the joints at `initial_positions` (by joint name; the
  // rest pose for the others; values outside a joint's limits are clamped into them). Unknown
  // names are reported as infos (a hot reload keeps what still exists). Returns nothing, with
  // errors in `diag`, when the robot cannot be simulated.
  static std::unique_ptr<Simulation> create(const Robot& robot, const SimulationOptions& options,
                                            const std::map<std::string, double>& initial_positions,
                                            Diagnostics& diag);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  void step();           // options.time_step
  void step(double dt);  // dt > 0, s

  double time() const;
  std::uint64_t steps() const;
  const Robot& robot() const;
  const SimulationOptions& options() const;
  std::string_view stepper_name() const;  // of the last (or next) step: "dWorldStep" or "dWorldQuickStep"
  Stepper stepper() const;                // the same: kWorldStep or kQuickStep
  int body_count() const;

  std::vector<JointState> joint_states() const;  // robot.joints order, one-dof joints only
  std::optional<JointState> joint_state(std::string_view joint) const;
  std::vector<LinkPose> link_poses() const;      // robot.links order
  std::optional<LinkPose> link_pose(std::string_view link) const;

  // Applies nothing and returns false, with the reason in *error, for an unknown joint, a joint
  // without one degree of freedom, non-finite values or negative gains.
  bool set_command(const JointCommand& command, std::string* error = nullptr);
  void clear_command(std::string_view joint);
  void clear_commands();

  SimulationHealth health(const HealthTolerances& tolerances = {}) const;
  // Whether the next step() would step: not stopped, and every body's state finite and within
  // the bound ODE may step (1e100). Cheap (no energies), for a caller about to publish the state.
  bool steppable() const;
  // ODE messages received while this simulation stepped (see init_ode).
  const std::vector<std::string>& ode_messages() const;

  struct Model;

 private:
  friend struct ValidationRun;  // validation.cc reads the model's bodies
  explicit Simulation(std::unique_ptr<Model> model);
  std::unique_ptr<Model> model_;
};

// ---------------------------------------------------------------------------------------------
// The validation run (the gate).

struct ValidationOptions {
  PhysicalCheckOptions checks;      // checks.floating_root is taken from simulation.floating_root.
  SimulationOptions simulation;
  double duration = 3.0;            // s of simulated time from the start pose, passive.
  // By joint name; joints not named start at rest. With start_offset_angular != 0, a revolute or
  // continuous joint not named starts that far from rest instead (within its limits), so that the
  // run moves: from an equilibrium (a chain hanging straight) a passive run tests little. The
  // default is the rest pose, as the model was drawn.
  std::map<std::string, double> initial_positions;
  double start_offset_angular = 0;  // rad
  // Failure thresholds.
  double energy_tolerance = 0.01;   // relative rise of kinetic + potential + dissipated energy
  // Joints may come apart by the larger of these (ODE's error grows with speed and size), plus,
  // per joint and step, the drift an exact step makes at its speeds.
  double joint_separation_tolerance = 1e-3;   // m
  double joint_separation_relative = 1e-3;    // of the model's size (its largest reach bound)
  // Plus, per joint and step, the drift an exact step makes at the joint's speeds; with
  // dWorldQuickStep a misalignment beyond that is the iterative solver's error and only a warning.
  double joint_misalignment_tolerance = 1e-2; // rad
  // Plus, for stops ODE enforces, the joint's travel while past the stop (ERP-decayed).
  double limit_tolerance_angular = 1e-2;      // rad
  double limit_tolerance_linear = 1e-3;       // m
  double region_margin_relative = 0.1;        // of each body's reach bound
  double region_margin_absolute = 0.01;       // m
  // CPU time (s, of the thread that validates) the checks, the model and the run may take
  // together; beyond it the run stops with the error SIM_BUDGET_EXCEEDED. 0: no limit.
  double cpu_budget = 30;
  // With Stepper::kAuto, a run that QuickStep failed is run again with dWorldStep when the largest
  // island has at most this many bodies, and that run is the verdict (SIM_QUICKSTEP_FAILED):
  // QuickStep's iterations let a sound robot's loaded stop or light finger overrun, dWorldStep
  // solves the joints exactly. A refusal withholds the whole model, so the bound is the CPU the
  // exact run takes, not real time: a 1 ms step of a chain of 40 / 60 / 80 / 100 bodies costs
  // about 0.28 / 0.9 / 2.2 / 4.8 ms with dWorldStep (3 s: 14 s of CPU at 100, inside the 30 s
  // budget). The live simulation then steps with dWorldStep and, beyond about 60 bodies, falls
  // behind real time, logged (docs/dynamics.md, "When QuickStep fails"). 0: never.
  int exact_rerun_max_bodies = 100;
  // When another thread sets it, the run stops with the error SIM_CANCELLED (e.g. rdtfd stopping).
  const std::atomic<bool>* cancel = nullptr;
};

struct ValidationReport {
  bool passed = false;       // No error diagnostic.
  bool simulated = false;    // The ODE model was built and stepped.
  Diagnostics diagnostics;   // Physical checks, ODE model, run: every one.
  double simulated_time = 0; // s
  std::uint64_t steps = 0;
  std::string stepper;
  int bodies = 0;
  int largest_island = 0;  // bodies of the largest island (what chooses the stepper)
  // The stepper of the run that is the verdict, kWorldStep or kQuickStep (kAuto: nothing was
  // stepped): a live simulation of the model takes it to behave as judged.
  Stepper verdict_stepper = Stepper::kAuto;
  // The automatic choice's QuickStep run failed and a dWorldStep run is the verdict
  // (ValidationOptions::exact_rerun_max_bodies; SIM_QUICKSTEP_FAILED says what failed).
  bool judged_again_exactly = false;
  double time_step = 0;
  // (E(t) + dissipated(t) - E(0)) / scale, E kinetic + potential; scale: the larger of the total
  // weight times the reach and the largest kinetic energy so far. Largest value over the run
  // (a rise is positive) and the value at its end.
  double energy_drift = 0;
  double final_energy_drift = 0;
  double worst_joint_error = 0;          // m, separation
  std::string worst_joint;               // its joint
  double worst_joint_misalignment = 0;   // rad
  // The joint furthest beyond a limit relative to its bound (SimulationHealth::worst_limit_ratio,
  // > 1: SIM_LIMIT_VIOLATED), over the run: how far past (rad or m, by its kind), and its name.
  double worst_limit_violation = 0;
  std::string worst_limit_joint;
  double worst_limit_ratio = 0;
  double wall_time = 0;                  // s, checks + model + run
  double cpu_time = 0;                   // s of the validating thread's CPU, the same
  bool cancelled = false;                // Stopped by ValidationOptions::cancel (SIM_CANCELLED)
  std::map<std::string, double> start_pose;  // rad or m by joint name; joints not listed start at rest
};

// The run's start pose: options.initial_positions, and every other revolute or continuous joint
// options.start_offset_angular from rest (or minus that, whichever its limits allow; else the
// middle of its limits). Prismatic joints stay at rest.
std::map<std::string, double> validation_start_pose(const Robot& robot, const ValidationOptions& options);

// Physical checks, then (when the ODE model can be built) the run.
ValidationReport validate_dynamics(const Robot& robot, const ValidationOptions& options,
                                   const LinkBounds* bounds = nullptr, std::string file = {});
// The same with the geometry bounds of a conversion.
ValidationReport validate_dynamics(const Conversion& conversion, const ValidationOptions& options,
                                   std::string file = {});

// {"passed", "simulated", "simulatedTime", "steps", "stepper", "bodies", "timeStep",
//  "energyDrift", "finalEnergyDrift", "worstJointError", "worstJoint", "worstJointMisalignment",
//  "worstLimitViolation", "worstLimitJoint", "worstLimitRatio", "wallTime", "cpuTime", "cancelled",
//  "startPose": {joint: position},
//  "diagnostics": [...]}
Json validation_report_json(const ValidationReport& report);
// One line: "PASS|FAIL: 3 s simulated in 3000 steps (dWorldStep, 3 bodies), ...".
std::string validation_summary_line(const ValidationReport& report);

}  // namespace rdtf
