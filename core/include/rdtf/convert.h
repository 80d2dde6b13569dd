// The whole glTF -> RDTF conversion: load, type, complete, compute mass properties, build the
// robot. Pure: bytes or a path in, a value out, diagnostics alongside; nothing is written.
#pragma once

#include <filesystem>
#include <optional>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/robot.h"

namespace rdtf {

struct ConvertOptions {
  LoadLimits limits;
  double default_density = 1000.0;  // kg/m^3 (Gazebo's default), used when no node sets one.
  // Write KHR_physics_rigid_bodies (motion and joints) beside extras.RDTF. Authored KHR physics
  // in the input is read either way.
  bool khr_physics = true;
};

struct Conversion {
  GltfAsset asset;  // The input, its document now the RDTF document (nodes inserted, extras.RDTF).
  Robot robot;      // Links, joints and mass properties, cross-referenced by index.
};

// Converts an already loaded asset. Returns nothing when the model cannot give a robot.
std::optional<Conversion> convert(GltfAsset asset, const ConvertOptions& options,
                                  Diagnostics& diagnostics);

// load_gltf + convert.
std::optional<Conversion> convert_file(const std::filesystem::path& path,
                                       const ConvertOptions& options, Diagnostics& diagnostics);

}  // namespace rdtf
