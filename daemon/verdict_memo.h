// The gate's last verdict on a model, kept so that a save which leaves everything the dynamics
// check reads exactly as it was does not run the check again.
//
// validate_dynamics is a function of the robot, the bounds of each link's geometry, the
// validation settings, the file name its diagnostics carry, and the code. A verdict is reused
// only when every one of them is the same as when it was computed:
// - the robot and the bounds, compared field by field and bit for bit (no tolerance, no hash:
//   -0.0 and 0.0 differ, so does any last bit of a double);
// - the settings and the code through settings_key() (every setting whose change reconverts,
//   rdtf's version and git commit, and for a modified tree the executable itself);
// - the model file's path.
// A save that changes only what the check does not read (materials, colours, textures, the asset's
// metadata, names of nodes that are neither links nor joints) reuses the verdict; any change to
// the robot or its geometry's bounds runs the check before anything is published.
//
// A memo is immutable once made and shared (std::shared_ptr<const>) between the event loop, which
// keeps the latest per model, and the worker that compares a new conversion with it.
#pragma once

#include <memory>
#include <string>

#include "conversion.h"
#include "rdtf/dynamics.h"
#include "rdtf/robot.h"

namespace rdtf::daemon {

struct VerdictMemo {
  std::string source;        // The model file (its path names the file in the diagnostics).
  std::string settings_key;  // settings_key() of the config the check ran under.
  Robot robot;
  LinkBounds bounds;
  ValidationSummary verdict;
};

// Bit for bit, every field (see above).
bool same_robot(const Robot& a, const Robot& b);
bool same_bounds(const LinkBounds& a, const LinkBounds& b);

// Whether `memo` is the verdict of exactly this check.
bool verdict_applies(const VerdictMemo& memo, const std::string& source, const std::string& settings_key,
                     const Robot& robot, const LinkBounds& bounds);

}  // namespace rdtf::daemon
