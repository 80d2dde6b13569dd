// The export's self-check: urdfdom parses the text back and every value equals the model's.
#pragma once

#include <string>

#include <urdf_model/model.h>

namespace rdtf::urdf_internal {

// True when urdfdom parses `text` and finds exactly `model` (names, tree, every number bit for
// bit); else false and what differs (or urdfdom's messages) in `why`.
bool reads_back_exactly(const std::string& text, const urdf::ModelInterface& model, std::string& why);

}  // namespace rdtf::urdf_internal
