// Generated models: a chain of `links` boxes (cube half-size `half` metres each, default density:
// 1000 * (2 half)^3 kg per link), joined by revolute joints. The base link is named `name`, so the
// RDTF JSON shows which version a description carries. With `bin_name` empty the buffer is
// embedded as a data: URI; otherwise the model refers to `bin_name` and `bin` holds its bytes.
#pragma once

#include <string>

#include "support/harness/basics.h"

namespace rdtf::itest {

struct GeneratedModel {
  std::string gltf;
  std::string bin;       // "" when embedded.
  std::string bin_name;  // "" when embedded.
  int links = 0;
  double link_mass = 0;  // Each box at 1000 kg/m^3.
};

std::string base64(const std::string& bytes);

GeneratedModel box_model(const std::string& name, double half, int links = 1, const std::string& bin_name = "");

// One link made of `parts` boxes side by side (one mesh used by `parts` nodes): a small file with
// a large document, for descriptions that need chunks. Buffer embedded.
GeneratedModel many_parts_model(const std::string& name, int parts, double half);

// Writes a generated model into `folder` as `file_name` (and its .bin), in place.
fs::path write_model(const fs::path& folder, const std::string& file_name, const GeneratedModel& model);

// The daemon's content_hash for a generated model.
std::string content_hash(const GeneratedModel& model);

// A model that parses but cannot be converted: a mesh refers to an accessor that does not exist.
std::string broken_model();

// A two-link chain that converts but fails the dynamics check: link_1 weighs a millionth of the
// base (JOINT_MASS_RATIO, beyond the default bound of 1e3; docs/dynamics.md).
GeneratedModel gate_failing_model(const std::string& name, double half, const std::string& bin_name = "");

}  // namespace rdtf::itest
