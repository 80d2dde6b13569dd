// The gains of rdtf-view's slider commands, per joint, from the inertia the joint moves.
//
// Rule (docs/view.md, "Sliders"): for a joint that moves an inertia M about (revolute,
// continuous) or along (prismatic) its axis in the rest pose, the PD law kp (q* - q) - kd q' on M
// alone is a critically damped second-order system of natural frequency w = 2 pi f:
//   kp = M w^2,   kd = 2 M w.
// Every joint then answers a slider in the same time (about 0.75 / f s to 95 %), whatever it moves,
// and ODE's explicit step stays stable alike for a fingertip and a shoulder (kd dt / M = 2 w dt, the
// same for every joint; below 1 for dt under 1 / (2 w): 20 ms at the default 4 Hz). Gravity, the
// coupling between joints and the links moving the joint's parent are left out; rdtfd clamps every
// PD effort to the joint's effort limit.
#pragma once

#include <map>
#include <string>

#include <urdf_model/model.h>

namespace rdtf::view {

struct Gains {
  double kp = 0;  // N m/rad (N/m)
  double kd = 0;  // N m s/rad (N s/m)
};

// What a joint moves, in its rest pose: the moment of inertia of the subtree below it about the
// joint's axis line (kg m^2) for a revolute or continuous joint, its mass (kg) for a prismatic
// one; 0 for other joints. From each link's URDF <inertial> (mass, centre of mass, tensor).
double moved_inertia(const urdf::ModelInterface& model, const urdf::Joint& joint);

// The gains of the rule above for a moved inertia and a natural frequency (Hz).
Gains gains_for(double moved_inertia, double frequency_hz);

}  // namespace rdtf::view
