// The Khronos validator's checks of what accessor values *mean* where they are used: a skinned
// vertex's joints and weights, a skin's inverse bind matrices, an animation's key times. rdtf
// reads all three (the skin split of a link's mass, NODE_ANIMATED) and copies them into its
// output, which must stay a valid glTF: a value the validator refuses is refused here, at the
// same place, with the same code (tools/gltf-validator/node_modules/gltf-validator/ISSUES.md).
//
// Runs inside validate_data, after every accessor was located: `readable` says which were.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "rdtf/diagnostic_codes.h"
#include "rdtf/geometry.h"
#include "validate_semantics.h"
#include "validate_util.h"

namespace rdtf::internal {
namespace {

// An accessor validate_data located, of `type` and component type FLOAT when `float_only`.
bool usable(const Json& document, const std::vector<char>& readable, std::uint64_t accessor, const char* type,
            bool float_only) {
  if (accessor >= readable.size() || !readable[accessor]) return false;
  const Json& a = document["accessors"][static_cast<std::size_t>(accessor)];
  if (a.value("type", "") != type) return false;
  return !float_only || uint_at(a, "componentType") == kFloat;
}

// Whether an accessor has values of its own: without a bufferView and sparse it is zeros, which
// the validator does not check (its suite's valid animations and skins have such accessors).
bool holds_data(const Json& document, std::uint64_t accessor) {
  const Json& a = document["accessors"][static_cast<std::size_t>(accessor)];
  return a.contains("bufferView") || a.contains("sparse");
}

std::string accessor_named(std::uint64_t accessor) {
  return "accessor " + std::to_string(accessor) + " (" + json_pointer("/accessors", accessor) + ")";
}

// "3 vertices", "1 vertex".
std::string vertices_text(std::uint64_t n) { return std::to_string(n) + (n == 1 ? " vertex" : " vertices"); }

// The first offending place of one kind in a primitive, and how many vertices have one.
struct Finding {
  std::uint64_t vertices = 0;
  std::uint64_t vertex = 0;
  int set = 0, component = 0;
  double value = 0;
  void add(std::uint64_t v, int s, int c, double x) {
    if (vertices++ == 0) vertex = v, set = s, component = c, value = x;
  }
};

// float(a + b) as the validator sums weights: in a Float32Array. A volatile float, since g++
// 12.2 drops double -> float -> double round trips (validate_data.cc, nearest_float).
double float_sum(double a, double b) {
  const volatile float rounded = static_cast<float>(a + b);
  return rounded;
}

// One skinned primitive's JOINTS_n / WEIGHTS_n sets, vertex by vertex, as the validator reads
// them: for each of a vertex's 4 components in turn, each set; a joint above the skin's last is
// ACCESSOR_JOINTS_INDEX_OOB (validate_data) and left out here; a non-zero weight on a joint the
// vertex already uses is a duplicate; a negative weight is an error; the others, summed in float,
// must be 1 within 2e-7 per weight summed.
void check_primitive_influences(const GltfAsset& asset, const std::vector<std::uint64_t>& joints_accessors,
                                const std::vector<std::uint64_t>& weights_accessors, std::uint64_t vertex_count,
                                std::uint64_t joint_count, const std::string& attributes_pointer,
                                const std::string& skinned_by, Diagnostics& diag) {
  const std::size_t sets = joints_accessors.size();
  std::vector<std::vector<double>> joints(sets), weights(sets);
  for (std::size_t s = 0; s < sets; ++s) {
    joints[s] = read_accessor(asset, static_cast<std::size_t>(joints_accessors[s]));
    weights[s] = read_accessor(asset, static_cast<std::size_t>(weights_accessors[s]));
    if (joints[s].size() != vertex_count * 4 || weights[s].size() != vertex_count * 4) return;
  }
  Finding duplicate, negative, unnormalized;
  std::vector<double> used;
  for (std::uint64_t v = 0; v < vertex_count; ++v) {
    used.clear();
    double sum = 0, tolerance = 0;
    for (int c = 0; c < 4; ++c) {
      for (std::size_t s = 0; s < sets; ++s) {
        const double joint = joints[s][v * 4 + c];
        const double weight = weights[s][v * 4 + c];
        if (joint >= static_cast<double>(joint_count) || weight == 0) continue;
        const bool repeated = std::find(used.begin(), used.end(), joint) != used.end();
        if (repeated) {
          duplicate.add(v, static_cast<int>(s), c, joint);
        } else {
          used.push_back(joint);
        }
        if (weight < 0) {
          negative.add(v, static_cast<int>(s), c, weight);
        } else if (!repeated) {
          sum = float_sum(sum, weight);
          tolerance += 2e-7;
        }
      }
    }
    if (std::abs(sum - 1) > tolerance) unnormalized.add(v, 0, 0, sum);
  }
  const auto more = [](const Finding& f) {
    return f.vertices > 1 ? " (" + vertices_text(f.vertices) + " in all)" : std::string();
  };
  if (duplicate.vertices > 0) {
    const std::string set = std::to_string(duplicate.set);
    diag.error(codes::ACCESSOR_JOINTS_INDEX_DUPLICATE, attributes_pointer + "/JOINTS_" + set,
               "vertex " + std::to_string(duplicate.vertex) + " names joint " +
                   std::to_string(static_cast<std::uint64_t>(duplicate.value)) + " twice with a non-zero weight (JOINTS_" +
                   set + " component " + std::to_string(duplicate.component) + ", " +
                   accessor_named(joints_accessors[duplicate.set]) + ")" + more(duplicate) + ", skinned by " +
                   skinned_by + "; each joint may influence a vertex once");
  }
  if (negative.vertices > 0) {
    const std::string set = std::to_string(negative.set);
    diag.error(codes::ACCESSOR_WEIGHTS_NEGATIVE, attributes_pointer + "/WEIGHTS_" + set,
               "vertex " + std::to_string(negative.vertex) + " has weight " + number_text(negative.value) +
                   " (WEIGHTS_" + set + " component " + std::to_string(negative.component) + ", " +
                   accessor_named(weights_accessors[negative.set]) + ")" + more(negative) + ", skinned by " +
                   skinned_by + "; weights cannot be negative");
  }
  if (unnormalized.vertices > 0) {
    diag.error(codes::ACCESSOR_WEIGHTS_NON_NORMALIZED, attributes_pointer + "/WEIGHTS_0",
               "the weights of vertex " + std::to_string(unnormalized.vertex) + " sum to " +
                   number_text(unnormalized.value) + ", not 1" + more(unnormalized) + " (" +
                   (sets == 1 ? accessor_named(weights_accessors[0]) : std::to_string(sets) + " WEIGHTS sets") +
                   "), skinned by " + skinned_by +
                   "; each vertex's weights must sum to 1 (in Blender: Weights > Normalize All before export)");
  }
}

}  // namespace

std::vector<SkinnedPrimitive> skinned_primitives(const Json& doc) {
  std::vector<SkinnedPrimitive> found;
  if (!doc.contains("nodes") || !doc["nodes"].is_array()) return found;
  for (std::size_t n = 0; n < doc["nodes"].size(); ++n) {
    const Json& node = doc["nodes"][n];
    const Json* skin = node.is_object() ? element_at(doc, "skins", uint_at(node, "skin")) : nullptr;
    const Json* mesh = node.is_object() ? element_at(doc, "meshes", uint_at(node, "mesh")) : nullptr;
    if (skin == nullptr || mesh == nullptr || !skin->contains("joints") || !(*skin)["joints"].is_array() ||
        !mesh->contains("primitives") || !(*mesh)["primitives"].is_array()) {
      continue;
    }
    for (std::size_t p = 0; p < (*mesh)["primitives"].size(); ++p) {
      const Json& primitive = (*mesh)["primitives"][p];
      if (!primitive.is_object() || !primitive.contains("attributes") || !primitive["attributes"].is_object()) continue;
      found.push_back({n, (*skin)["joints"].size(), *uint_at(node, "mesh"), p, &primitive["attributes"]});
    }
  }
  return found;
}

void check_skin_influences(const GltfAsset& asset, const std::vector<char>& readable, Diagnostics& diag) {
  const Json& doc = asset.document;
  // A primitive's sets are read once per joint count, however many nodes draw it with a skin.
  std::set<std::pair<std::vector<std::uint64_t>, std::uint64_t>> checked;
  for (const SkinnedPrimitive& skinned : skinned_primitives(doc)) {
    const Json& attributes = *skinned.attributes;
    const std::uint64_t joint_count = skinned.joint_count;
    const auto position = uint_at(attributes, "POSITION");
    if (!position || *position >= readable.size() || !readable[*position]) continue;
    const auto vertex_count = uint_at(doc["accessors"][static_cast<std::size_t>(*position)], "count");
    std::vector<std::uint64_t> joints, weights;
    bool sound = vertex_count.has_value();
    for (int set = 0; sound; ++set) {
      const auto j = uint_at(attributes, ("JOINTS_" + std::to_string(set)).c_str());
      const auto w = uint_at(attributes, ("WEIGHTS_" + std::to_string(set)).c_str());
      if (!j && !w) break;
      // A set without its partner, of another count or format: validate_document's errors.
      sound = j && w && usable(doc, readable, *j, "VEC4", false) && usable(doc, readable, *w, "VEC4", false) &&
              uint_at(doc["accessors"][static_cast<std::size_t>(*j)], "count") == vertex_count &&
              uint_at(doc["accessors"][static_cast<std::size_t>(*w)], "count") == vertex_count;
      if (sound) joints.push_back(*j), weights.push_back(*w);
    }
    if (!sound || joints.empty()) continue;
    const auto zeros = [&](std::uint64_t a) { return !holds_data(doc, a); };
    if (std::any_of(joints.begin(), joints.end(), zeros) || std::any_of(weights.begin(), weights.end(), zeros)) continue;
    std::vector<std::uint64_t> key = joints;
    key.insert(key.end(), weights.begin(), weights.end());
    if (!checked.emplace(std::move(key), joint_count).second) continue;
    check_primitive_influences(asset, joints, weights, *vertex_count, joint_count,
                               json_pointer(json_pointer("/meshes", skinned.mesh) + "/primitives", skinned.primitive) +
                                   "/attributes",
                               node_named(doc, skinned.node), diag);
  }
}

// glTF 2.0 section 5.28: inverse bind matrices are affine, their last row (0, 0, 0, 1). The skin
// split of a link's mass maps vertices through them.
void check_inverse_bind_matrices(const GltfAsset& asset, const std::vector<char>& readable, Diagnostics& diag) {
  const Json& doc = asset.document;
  if (!doc.contains("skins") || !doc["skins"].is_array()) return;
  std::set<std::uint64_t> checked;
  for (std::size_t s = 0; s < doc["skins"].size(); ++s) {
    const auto accessor = uint_at(doc["skins"][s], "inverseBindMatrices");
    if (!accessor || !usable(doc, readable, *accessor, "MAT4", true) || !holds_data(doc, *accessor) ||
        !checked.insert(*accessor).second) {
      continue;
    }
    const std::vector<double> matrices = read_accessor(asset, static_cast<std::size_t>(*accessor));
    for (std::size_t k = 0; k < matrices.size(); ++k) {
      const std::size_t component = k % 16;
      const bool last_row = component == 3 || component == 7 || component == 11 || component == 15;
      if (!last_row || matrices[k] == (component == 15 ? 1.0 : 0.0)) continue;
      diag.error(codes::ACCESSOR_INVALID_IBM, json_pointer("/skins", s) + "/inverseBindMatrices",
                 "inverse bind matrix " + std::to_string(k / 16) + " of skin " + std::to_string(s) + " (" +
                     accessor_named(*accessor) + ") has " +
                     number_text(matrices[k]) + " at component " + std::to_string(component) +
                     " (column-major; its last row must be 0, 0, 0, 1): not an affine transform");
      break;
    }
  }
}

// An animation sampler's input accessor declares min and max, and its key times are >= 0 and
// rise strictly (glTF 2.0 section 3.11); NODE_ANIMATED reads the keys by them.
void check_animation_inputs(const GltfAsset& asset, const std::vector<char>& readable, Diagnostics& diag) {
  const Json& doc = asset.document;
  if (!doc.contains("animations") || !doc["animations"].is_array()) return;
  std::set<std::uint64_t> checked;
  for (std::size_t a = 0; a < doc["animations"].size(); ++a) {
    const Json& animation = doc["animations"][a];
    if (!animation.is_object() || !animation.contains("samplers") || !animation["samplers"].is_array()) continue;
    for (std::size_t s = 0; s < animation["samplers"].size(); ++s) {
      const auto input = uint_at(animation["samplers"][s], "input");
      if (!input || !usable(doc, readable, *input, "SCALAR", true) || !checked.insert(*input).second) continue;
      const Json& accessor = doc["accessors"][static_cast<std::size_t>(*input)];
      const std::string sampler = json_pointer(json_pointer("/animations", a) + "/samplers", s);
      if (!accessor.contains("min") || !accessor.contains("max")) {
        diag.error(codes::ANIMATION_SAMPLER_INPUT_ACCESSOR_WITHOUT_BOUNDS, sampler + "/input",
                   "the key times, " + accessor_named(*input) + ", have no " +
                       (accessor.contains("min") ? "max" : accessor.contains("max") ? "min" : "min and max") +
                       "; an animation's input accessor must declare both");
      }
      if (!holds_data(doc, *input)) continue;
      const std::vector<double> times = read_accessor(asset, static_cast<std::size_t>(*input));
      double previous = 0;
      bool any = false;
      for (std::size_t k = 0; k < times.size(); ++k) {
        if (times[k] < 0) {
          diag.error(codes::ACCESSOR_ANIMATION_INPUT_NEGATIVE, sampler + "/input",
                     "key time " + std::to_string(k) + " (" + accessor_named(*input) + ") is " + number_text(times[k]) +
                         " s; key times cannot be negative");
          break;
        }
        if (any && times[k] <= previous) {
          diag.error(codes::ACCESSOR_ANIMATION_INPUT_NON_INCREASING, sampler + "/input",
                     "key time " + std::to_string(k) + " (" + accessor_named(*input) + ") is " + number_text(times[k]) +
                         " s, not after the one before it, " + number_text(previous) +
                         " s; key times must rise strictly");
          break;
        }
        previous = times[k];
        any = true;
      }
    }
  }
}

}  // namespace rdtf::internal
