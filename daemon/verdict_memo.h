// The gate's last verdict on a model, kept so that a save which leaves everything the dynamics
// check reads exactly as it was does not run the check again.
//
// validate_dynamics is a function of the robot, the bounds of each link's geometry, the
// validation settings, the file name its diagnostics carry, and the code. A verdict is reused
// only when every one of them is the same as when it was computed, which the memo holds as one
// SHA-256 (check_digest) of:
// - the robot and the bounds, field by field and bit for bit (no tolerance: -0.0 and 0.0 differ,
//   so does any last bit of a double), each variable-length part after its length;
// - the settings and the code through settings_key() (every setting whose change reconverts,
//   rdtf's version and git commit, and for a modified tree the executable itself);
// - the model file's path.
// A digest rather than a copy: a copy of the robot and bounds was about 1.7 KB a model, 17 MiB at
// 10,000 models (docs/benchmarks.md); two different inputs with one SHA-256 is not a risk to plan for.
// A save that changes only what the check does not read (materials, colours, textures, the asset's
// metadata, names of nodes that are neither links nor joints) reuses the verdict; any change to
// the robot or its geometry's bounds runs the check before anything is published.
//
// A memo is immutable once made and shared (std::shared_ptr<const>) between the event loop, which
// keeps the latest per model, and the worker that compares a new conversion with it.
#pragma once

#include <array>
#include <memory>
#include <string>

#include "conversion.h"
#include "rdtf/dynamics.h"
#include "rdtf/robot.h"

namespace rdtf::daemon {

using CheckDigest = std::array<unsigned char, 32>;

// SHA-256 of what the check reads (see above).
CheckDigest check_digest(const std::string& source, const std::string& settings_key, const Robot& robot,
                         const LinkBounds& bounds);

struct VerdictMemo {
  CheckDigest digest{};  // check_digest of the check that gave the verdict.
  ValidationSummary verdict;
};

}  // namespace rdtf::daemon
