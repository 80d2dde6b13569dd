// The validator's checks of skin influences, inverse bind matrices and animation key times
// (core/gltf/validate_semantics.cc), on Blender's own files with one value changed in their
// buffers: each change is one the Khronos validator reports as an error, and rdtf copied it into
// an output the validator then refused.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "rdtf/gltf.h"
#include "rdtf/validate.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

GltfAsset load_ok(const std::string& name) {
  Diagnostics diag;
  auto asset = load_gltf(testing::data_dir() / "blender" / name, LoadLimits{}, diag);
  EXPECT_TRUE(asset.has_value()) << name;
  EXPECT_FALSE(diag.has_errors()) << name;
  return std::move(*asset);
}

// Byte address of component `component` of element `element` of accessor `index` (dense).
std::uint8_t* at(GltfAsset& asset, std::size_t index, std::size_t element, std::size_t component) {
  const Json& accessor = asset.document["accessors"][index];
  const Json& view = asset.document["bufferViews"][accessor["bufferView"].get<std::size_t>()];
  const std::size_t size = accessor["componentType"] == 5126 ? 4 : accessor["componentType"] == 5121 ? 1 : 2;
  const std::size_t components = accessor["type"] == "VEC4" ? 4 : accessor["type"] == "MAT4" ? 16 : 1;
  const std::size_t stride = view.value("byteStride", size * components);
  return asset.buffers[view["buffer"].get<std::size_t>()].data() + view.value("byteOffset", 0) +
         accessor.value("byteOffset", 0) + element * stride + component * size;
}

float get_float(GltfAsset& asset, std::size_t index, std::size_t element, std::size_t component) {
  float value;
  std::memcpy(&value, at(asset, index, element, component), 4);
  return value;
}

void set_float(GltfAsset& asset, std::size_t index, std::size_t element, std::size_t component, float value) {
  std::memcpy(at(asset, index, element, component), &value, 4);
}

Diagnostics check(const GltfAsset& asset) {
  Diagnostics diag(asset.path.string());
  validate_data(asset, diag);
  return diag;
}

std::string listing(const Diagnostics& diag) {
  std::string text;
  for (const Diagnostic& d : diag.all()) text += "  " + format(d) + "\n";
  return text.empty() ? "  (no diagnostics)\n" : text;
}

// The error of `diag` with `code` at `pointer`, or null.
const Diagnostic* find(const Diagnostics& diag, const std::string& code, const std::string& pointer) {
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError && d.code == code && d.pointer == pointer) return &d;
  }
  return nullptr;
}

// The one error of `diag`, which must have `code` and `pointer` (a copy: `diag` may be a temporary).
Diagnostic only_error(const Diagnostics& diag, const std::string& code, const std::string& pointer) {
  static const Diagnostic kNone{};
  std::size_t errors = 0;
  const Diagnostic* found = &kNone;
  for (const Diagnostic& d : diag.all()) {
    if (d.severity != Severity::kError) continue;
    ++errors;
    if (d.code == code && d.pointer == pointer) found = &d;
  }
  EXPECT_EQ(errors, 1u) << listing(diag);
  EXPECT_NE(found, &kNone) << "expected " << code << " at " << pointer << ":\n" << listing(diag);
  return *found;
}

// skinned_arm.gltf (Blender 3.4): mesh 0's JOINTS_0 is accessor 3 (UNSIGNED_BYTE), WEIGHTS_0
// accessor 4 (FLOAT), 576 vertices; skin 0 has 3 joints and inverse bind matrices in accessor 6.
constexpr std::size_t kJoints = 3, kWeights = 4, kBindMatrices = 6;
const std::string kAttributes = "/meshes/0/primitives/0/attributes";

TEST(ValidateSemantics, BlendersSkinnedAndAnimatedFilesPass) {
  for (const char* name : {"skinned_arm.gltf", "modelled_bones.gltf", "keyframed.glb", "idle_bones.glb"}) {
    const GltfAsset asset = load_ok(name);
    EXPECT_FALSE(check(asset).has_errors()) << name << ":\n" << listing(check(asset));
  }
}

TEST(ValidateSemantics, WeightsThatDoNotSumToOneAreRefusedNamingTheVertex) {
  GltfAsset asset = load_ok("skinned_arm.gltf");
  // Vertex 10's weights halved: they sum to 0.5.
  for (int c = 0; c < 4; ++c) set_float(asset, kWeights, 10, c, get_float(asset, kWeights, 10, c) / 2);
  const Diagnostic d = only_error(check(asset), "ACCESSOR_WEIGHTS_NON_NORMALIZED", kAttributes + "/WEIGHTS_0");
  EXPECT_NE(d.message.find("vertex 10 sum to 0.5,"), std::string::npos) << d.message;
  EXPECT_NE(d.message.find("node 3 'arm_skin'"), std::string::npos) << d.message;

  // Off by 1e-6, five times the validator's 2e-7 for a vertex with one weight: refused too.
  GltfAsset slightly = load_ok("skinned_arm.gltf");
  for (int c = 0; c < 4; ++c) set_float(slightly, kWeights, 20, c, c == 0 ? 1.0f - 1e-6f : 0.0f);
  only_error(check(slightly), "ACCESSOR_WEIGHTS_NON_NORMALIZED", kAttributes + "/WEIGHTS_0");
  // Within it (one float step below 1, 6e-8): accepted, as the validator accepts it.
  GltfAsset within = load_ok("skinned_arm.gltf");
  for (int c = 0; c < 4; ++c) set_float(within, kWeights, 20, c, c == 0 ? std::nextafter(1.0f, 0.0f) : 0.0f);
  EXPECT_FALSE(check(within).has_errors()) << listing(check(within));
}

TEST(ValidateSemantics, NegativeWeightsAndJointsNamedTwiceAreRefused) {
  GltfAsset negative = load_ok("skinned_arm.gltf");
  // Weights (1.5, -0.5, 0, 0) on joints 0 and 1: they sum to 1, but one is negative.
  *at(negative, kJoints, 7, 0) = 0;
  *at(negative, kJoints, 7, 1) = 1;
  for (int c = 0; c < 4; ++c) set_float(negative, kWeights, 7, c, c == 0 ? 1.5f : c == 1 ? -0.5f : 0.0f);
  // As the validator: the negative weight is left out of the sum, which is then 1.5 as well.
  const Diagnostics negatives = check(negative);
  const Diagnostic* n = find(negatives, "ACCESSOR_WEIGHTS_NEGATIVE", kAttributes + "/WEIGHTS_0");
  ASSERT_NE(n, nullptr) << listing(negatives);
  EXPECT_NE(n->message.find("vertex 7 has weight -0.5"), std::string::npos) << n->message;
  EXPECT_NE(find(negatives, "ACCESSOR_WEIGHTS_NON_NORMALIZED", kAttributes + "/WEIGHTS_0"), nullptr);

  GltfAsset twice = load_ok("skinned_arm.gltf");
  // Joint 2 twice, weights 0.5 each: the validator counts the second as a duplicate and leaves it
  // out of the sum, so the vertex is also not normalized (0.5).
  *at(twice, kJoints, 9, 0) = 2;
  *at(twice, kJoints, 9, 1) = 2;
  for (int c = 0; c < 4; ++c) set_float(twice, kWeights, 9, c, c < 2 ? 0.5f : 0.0f);
  const Diagnostics diag = check(twice);
  const Diagnostic* duplicate = find(diag, "ACCESSOR_JOINTS_INDEX_DUPLICATE", kAttributes + "/JOINTS_0");
  ASSERT_NE(duplicate, nullptr) << listing(diag);
  EXPECT_NE(duplicate->message.find("vertex 9 names joint 2 twice"), std::string::npos) << duplicate->message;
  EXPECT_NE(find(diag, "ACCESSOR_WEIGHTS_NON_NORMALIZED", kAttributes + "/WEIGHTS_0"), nullptr) << listing(diag);

  // A joint named again with weight 0 is no duplicate (the validator's
  // ACCESSOR_JOINTS_USED_ZERO_WEIGHT is a warning, about a non-zero joint index only).
  GltfAsset zero = load_ok("skinned_arm.gltf");
  *at(zero, kJoints, 9, 0) = 2;
  *at(zero, kJoints, 9, 1) = 2;
  for (int c = 0; c < 4; ++c) set_float(zero, kWeights, 9, c, c == 0 ? 1.0f : 0.0f);
  EXPECT_FALSE(check(zero).has_errors()) << listing(check(zero));
}

TEST(ValidateSemantics, AnInverseBindMatrixMustBeAffine) {
  GltfAsset asset = load_ok("skinned_arm.gltf");
  set_float(asset, kBindMatrices, 1, 7, 0.25f);  // Matrix 1, row 3 of column 1.
  const Diagnostic d = only_error(check(asset), "ACCESSOR_INVALID_IBM", "/skins/0/inverseBindMatrices");
  EXPECT_NE(d.message.find("inverse bind matrix 1 of skin 0 (accessor 6 (/accessors/6)) has 0.25 at component 7"),
            std::string::npos)
      << d.message;
  GltfAsset scaled = load_ok("skinned_arm.gltf");
  set_float(scaled, kBindMatrices, 2, 15, 2.0f);
  only_error(check(scaled), "ACCESSOR_INVALID_IBM", "/skins/0/inverseBindMatrices");
}

TEST(ValidateSemantics, KeyTimesRiseStrictlyFromZeroWithDeclaredBounds) {
  const GltfAsset original = load_ok("keyframed.glb");
  const std::size_t input = original.document["animations"][0]["samplers"][0]["input"].get<std::size_t>();
  const std::string at_input = "/animations/0/samplers/0/input";
  ASSERT_GE(original.document["accessors"][input]["count"].get<int>(), 3);

  GltfAsset repeated = original;
  set_float(repeated, input, 2, 0, get_float(repeated, input, 1, 0));
  const Diagnostic r = only_error(check(repeated), "ACCESSOR_ANIMATION_INPUT_NON_INCREASING", at_input);
  EXPECT_NE(r.message.find("key time 2 (accessor " + std::to_string(input) + " "), std::string::npos) << r.message;

  GltfAsset negative = original;
  set_float(negative, input, 0, 0, -0.5f);
  negative.document["accessors"][input]["min"][0] = -0.5;  // Bounds kept true: only the sign is wrong.
  only_error(check(negative), "ACCESSOR_ANIMATION_INPUT_NEGATIVE", at_input);

  GltfAsset unbounded = original;
  unbounded.document["accessors"][input].erase("max");
  const Diagnostic u =
      only_error(check(unbounded), "ANIMATION_SAMPLER_INPUT_ACCESSOR_WITHOUT_BOUNDS", "/animations/0/samplers/0/input");
  EXPECT_NE(u.message.find("have no max"), std::string::npos) << u.message;
}

}  // namespace
}  // namespace rdtf
