// Which nodes place the robot: shared by the checks of core/robot (checks.cc, animations.cc) and
// by typing (core/typing/typing.cc: a part an animation places is no part of a group).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rdtf/gltf.h"

namespace rdtf::internal {

// The nodes whose transforms place the robot: in the scene converted (typing's default_scene:
// "scene", else the first) with a mesh or joint properties (a pivot, or a frame of its own: a
// camera's empty) at or below them. Empty when there is no scene. `scene_nodes`, when given, gets
// every node of that scene.
std::vector<char> nodes_placing_the_robot(const Json& document, const std::vector<int>& parents,
                                          std::vector<char>* scene_nodes = nullptr);

// The node and property a channel's target animates: target.node and target.path, or
// KHR_animation_pointer's "pointer" path with a JSON pointer such as "/nodes/3/rotation".
std::optional<std::pair<std::size_t, std::string>> animated_property(const Json& target);

}  // namespace rdtf::internal
