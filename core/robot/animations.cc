// NODE_ANIMATED: animations that move the nodes placing the robot. RDTF describes each node where
// the file puts it (its rest transform), never at a frame of an animation; a modeller who
// keyframed a joint and exported at another frame sees one pose and gets another, silently
// (Blender writes keyframed objects at their frame-1 transform whatever frame it shows).
//
// A channel moves its node only when some keyframe differs from the node's rest value: Blender
// writes a channel for every bone of an action (and exports every action of the .blend file), most
// of them constant at the rest pose, and warning of those would drown the one that matters.
#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <optional>
#include <string_view>
#include <utility>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "rdtf/completion.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/geometry.h"
#include "rdtf/robot.h"
#include "scene_nodes.h"

namespace rdtf {
namespace {

// What counts as the same value. Exporters sample float32 matrices and decompose them, so a
// keyframe of an unmoved node differs from its rest by a few float32 ulps of the largest magnitude
// involved (Blender 3.4: 5e-8 m on a 0.3 m offset, 1.2e-7 in scale, 3e-8 in a quaternion; see
// tests/data/blender/make_animated.py). 1e-5 relative (10 um at 1 m) and 1e-5 rad are a hundred
// times that and far below anything a robot description resolves.
constexpr double kRelative = 1e-5;
constexpr double kAngle = 1e-5;

std::vector<double> rest_value(const Json& node, const std::string& path) {
  std::vector<double> fallback = path == "rotation" ? std::vector<double>{0, 0, 0, 1}
                                 : path == "scale"  ? std::vector<double>{1, 1, 1}
                                                    : std::vector<double>{0, 0, 0};
  if (!node.contains(path) || !node[path].is_array() || node[path].size() != fallback.size()) return fallback;
  std::vector<double> value;
  for (const Json& x : node[path]) value.push_back(x.is_number() ? x.get<double>() : 0.0);
  return value;
}

// How far a key may lie from the value it stands for, by how the file stores it: an angle for
// rotations, a distance for translation and scale (beside kRelative).
struct Resolution {
  double angle = kAngle;
  double distance = 0.0;
};

// A quantized rotation (normalized byte or short, glTF 2.0 3.11) is off by up to half a step in
// each component: an angle of at most 2 |dq| <= 2 step. A key decoded through a meshopt filter
// (GltfAsset::filter_steps, per element) was rounded before that:
// - QUATERNION keeps three components to within s/2 (s its step) and recomputes the largest, w >=
//   1/2, from them: |dw| <= |x| |dx| / w <= (sqrt(3)/2)(sqrt(3) s/2)/(1/2) = 1.5 s, so |dq| <=
//   sqrt(3 (s/2)^2 + (1.5 s)^2) = sqrt(3) s, then int16 rounding adds up to 1/32767: the angle is
//   at most 2 (sqrt(3) s + 1/32767), within 4 s + 2/32767;
// - EXPONENTIAL keeps each component to within half its step 2^e: a distance of one step is twice that.
Resolution resolution(const Json& accessor) {
  Resolution r;
  if (accessor.value("normalized", false)) {
    const int type = accessor.value("componentType", 0);
    const double step = (type == 5120 || type == 5121) ? 1.0 / 127 : (type == 5122 || type == 5123) ? 1.0 / 32767 : 0.0;
    r.angle = std::max(kAngle, 2 * step);
  }
  return r;
}

// The filter steps of an accessor's keys, one per key (empty: not filtered).
std::vector<double> key_steps(const GltfAsset& asset, const Json& accessor, std::size_t keys) {
  if (!accessor.contains("bufferView") || !accessor["bufferView"].is_number_unsigned()) return {};
  const auto filtered = asset.filter_steps.find(accessor["bufferView"].get<std::size_t>());
  if (filtered == asset.filter_steps.end() || filtered->second.stride == 0) return {};
  const auto offset = accessor.value("byteOffset", std::uint64_t{0});
  const std::size_t first = static_cast<std::size_t>(offset / filtered->second.stride);
  std::vector<double> steps(keys, 0.0);
  for (std::size_t k = 0; k < keys && first + k < filtered->second.steps.size(); ++k) {
    steps[k] = filtered->second.steps[first + k];
  }
  return steps;
}

bool differs(const std::string& path, const double* key, const std::vector<double>& rest, const Resolution& resolution) {
  if (path == "rotation") {
    const Eigen::Vector4d q(key[0], key[1], key[2], key[3]), r(rest[0], rest[1], rest[2], rest[3]);
    if (!(q.norm() > 0) || !(r.norm() > 0)) return true;
    // The angle between the two rotations; q and -q are one rotation.
    const double cos_half = std::min(1.0, std::abs(q.normalized().dot(r.normalized())));
    return 2 * std::acos(cos_half) > resolution.angle;
  }
  double scale = 1.0, distance = 0.0;
  for (int k = 0; k < 3; ++k) {
    scale = std::max({scale, std::abs(key[k]), std::abs(rest[k])});
    distance = std::max(distance, std::abs(key[k] - rest[k]));
  }
  return !(distance <= std::max(kRelative * scale, resolution.distance));
}

// A CUBICSPLINE tangent that is not zero moves the node between equal keys.
bool tangent_moves(const std::string& path, const double* tangent, const std::vector<double>& rest) {
  const int n = path == "rotation" ? 4 : 3;
  double norm = 0.0, scale = 1.0;
  for (int k = 0; k < n; ++k) norm = std::max(norm, std::abs(tangent[k]));
  for (int k = 0; k < 3; ++k) scale = std::max(scale, std::abs(rest[k]));
  return !(norm <= (path == "rotation" ? kAngle : kRelative * scale));
}

// Answers already found: a file may point many channels at one sampler, and its keys are read and
// compared once for each rest value they are compared with, not once per channel.
struct Memo {
  std::map<std::tuple<std::size_t, std::string, bool, std::vector<double>>, bool> moves;
};

// Whether `channel` of `animation` takes its node anywhere but its rest transform. Anything this
// cannot read (a sampler or accessor out of range, a node with a matrix, which an animation must not
// target) counts as moving: the warning is the safe side.
bool channel_moves(const GltfAsset& asset, const Json& animation, const Json& channel, const Json& node,
                   const std::string& path, Memo& memo) {
  const Json& document = asset.document;
  if (node.contains("matrix") || !channel.contains("sampler") || !channel["sampler"].is_number_unsigned()) return true;
  const auto sampler_index = channel["sampler"].get<std::size_t>();
  const auto samplers = animation.find("samplers");  // not value(): that copies them for each channel
  if (samplers == animation.end() || !samplers->is_array() || sampler_index >= samplers->size() ||
      !(*samplers)[sampler_index].is_object()) {
    return true;
  }
  const Json& sampler = (*samplers)[sampler_index];
  if (!sampler.contains("output") || !sampler["output"].is_number_unsigned() || !document.contains("accessors")) return true;
  const auto output = sampler["output"].get<std::size_t>();
  if (output >= document["accessors"].size()) return true;
  const Json& accessor = document["accessors"][output];
  const int n = path == "rotation" ? 4 : 3;
  if (accessor.value("type", "") != (n == 4 ? "VEC4" : "VEC3")) return true;
  const std::vector<double> rest = rest_value(node, path);
  const bool cubic = sampler.value("interpolation", "LINEAR") == "CUBICSPLINE";
  const auto [known, added] = memo.moves.try_emplace({output, path, cubic, rest}, false);
  if (!added) return known->second;
  const std::vector<double> values = read_accessor(asset, output);
  const Resolution base = resolution(accessor);
  const std::size_t keys = values.size() / static_cast<std::size_t>(n);
  const std::vector<double> steps = key_steps(asset, accessor, keys);
  for (std::size_t k = 0; k < keys && !known->second; ++k) {
    const double* key = values.data() + k * static_cast<std::size_t>(n);
    Resolution within = base;
    if (!steps.empty() && steps[k] > 0) {
      within.angle = std::max(within.angle, n == 4 ? 4 * steps[k] + 2.0 / 32767 : 0.0);
      within.distance = steps[k];
    }
    // CUBICSPLINE keys are (in-tangent, value, out-tangent).
    known->second = cubic && k % 3 != 1 ? tangent_moves(path, key, rest) : differs(path, key, rest, within);
  }
  return known->second;
}

}  // namespace

namespace internal {

// The node and property a channel's target animates: target.node and target.path, or
// KHR_animation_pointer's "pointer" path with a JSON pointer such as "/nodes/3/rotation".
std::optional<std::pair<std::size_t, std::string>> animated_property(const Json& target) {
  if (target.value("path", std::string()) != "pointer") {
    if (!target.contains("node") || !target["node"].is_number_unsigned()) return std::nullopt;
    return std::pair{target["node"].get<std::size_t>(), target.value("path", std::string())};
  }
  const Json* extension = nullptr;
  if (target.contains("extensions") && target["extensions"].is_object() &&
      target["extensions"].contains("KHR_animation_pointer")) {
    extension = &target["extensions"]["KHR_animation_pointer"];
  }
  if (!extension || !extension->is_object() || !extension->contains("pointer") || !(*extension)["pointer"].is_string()) {
    return std::nullopt;
  }
  const std::string pointer = (*extension)["pointer"].get<std::string>();
  constexpr std::string_view kNodes = "/nodes/";
  if (pointer.rfind(kNodes, 0) != 0) return std::nullopt;
  const auto slash = pointer.find('/', kNodes.size());
  if (slash == std::string::npos || slash == kNodes.size()) return std::nullopt;
  const std::string index = pointer.substr(kNodes.size(), slash - kNodes.size());
  if (index.size() > 9 || !std::all_of(index.begin(), index.end(), [](char ch) { return ch >= '0' && ch <= '9'; }) ||
      (index.size() > 1 && index[0] == '0')) {
    return std::nullopt;
  }
  return std::pair{static_cast<std::size_t>(std::stoul(index)), pointer.substr(slash + 1)};
}

}  // namespace internal

void check_animations(const GltfAsset& asset, Diagnostics& diag) {
  const Json& document = asset.document;
  if (!document.contains("animations") || !document["animations"].is_array() || !document.contains("nodes")) return;
  const Json& nodes = document["nodes"];
  const auto parents = node_parents(document);
  std::vector<char> in_scene;
  std::vector<char> placing = internal::nodes_placing_the_robot(document, parents, &in_scene);
  // A skin's joints (bones) in the scene converted place the links made of them, and the parts
  // they hold.
  for (const Json& skin : document.value("skins", Json::array())) {
    if (!skin.is_object()) continue;
    for (const Json& joint : skin.value("joints", Json::array())) {
      if (!joint.is_number_unsigned() || joint.get<std::size_t>() >= nodes.size()) continue;
      if (in_scene.empty() || !in_scene[joint.get<std::size_t>()]) continue;
      for (int up = joint.get<int>(); up >= 0 && !placing[up]; up = parents[up]) placing[up] = 1;
    }
  }
  const Json& animations = document["animations"];
  Memo memo;
  for (std::size_t a = 0; a < animations.size(); ++a) {
    if (!animations[a].is_object() || !animations[a].contains("channels")) continue;
    const Json& channels = animations[a]["channels"];
    std::vector<std::pair<std::size_t, std::string>> moved;  // node, paths
    std::size_t first_channel = 0;
    for (std::size_t c = 0; c < channels.size(); ++c) {
      const Json* target = channels[c].is_object() && channels[c].contains("target") ? &channels[c]["target"] : nullptr;
      if (!target || !target->is_object()) continue;
      const auto animated = internal::animated_property(*target);
      if (!animated) continue;
      const std::size_t node = animated->first;  // not a structured binding: clang 14 cannot capture one
      const std::string path = animated->second;
      if (node >= nodes.size() || !placing[node] || (path != "translation" && path != "rotation" && path != "scale")) continue;
      if (!channel_moves(asset, animations[a], channels[c], nodes[node], path, memo)) continue;
      const auto known = std::find_if(moved.begin(), moved.end(), [&](const auto& m) { return m.first == node; });
      if (moved.empty()) first_channel = c;
      if (known == moved.end()) {
        moved.emplace_back(node, path);
      } else if (known->second.find(path) == std::string::npos) {
        known->second += ", " + path;
      }
    }
    if (moved.empty()) continue;
    std::string which;
    for (std::size_t k = 0; k < moved.size() && k < 3; ++k) {
      which += (k ? ", " : "") + node_label(document, moved[k].first) + " (" + moved[k].second + ")";
    }
    if (moved.size() > 3) which += " and " + std::to_string(moved.size() - 3) + " more nodes";
    const std::string name = animations[a].value("name", "");
    diag.warning(codes::NODE_ANIMATED, "/animations/" + std::to_string(a) + "/channels/" + std::to_string(first_channel),
                 "animation " + std::to_string(a) + (name.empty() ? "" : " '" + name + "'") + " moves " + which +
                     ": the robot is described where the file places its nodes, in no frame of an animation; "
                     "Blender writes keyframed objects at their frame-1 transform whatever frame it shows. "
                     "Clear the keyframes of the parts and joint empties (Object > Animation > Clear "
                     "Keyframes), or set frame 1 to the pose the robot is modelled in, and export again");
  }
}

}  // namespace rdtf
