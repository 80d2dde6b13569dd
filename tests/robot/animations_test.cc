// NODE_ANIMATED (core/robot/animations.cc): an animation is named only where it takes a node that
// places the robot away from its rest transform. Blender writes a channel for every bone of an
// action, constant at the rest pose for the bones the action leaves alone, and exports every action
// of the .blend file: those move nothing. Blender's own exports (tests/data/blender/make_animated.py)
// and channels written here on tests/data/frames/mount_empty.gltf (node 1 'mount', rotation 45
// degrees about Z; node 2 'arm', translation (0.1, 0, 0)).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

using nlohmann::json;

std::vector<Diagnostic> animated(const std::filesystem::path& path) {
  Diagnostics diag;
  EXPECT_TRUE(convert_file(path, {}, diag).has_value()) << path;
  EXPECT_FALSE(diag.has_errors()) << path;
  std::vector<Diagnostic> found;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == codes::NODE_ANIMATED) found.push_back(d);
  }
  return found;
}

struct Channel {
  int node;
  std::string path;
  std::string interpolation;
  std::vector<float> values;         // Float keyframes, row after row...
  std::vector<std::int16_t> shorts;  // ...or normalized shorts (a quantized rotation).
};
Channel floats(int node, const std::string& path, const std::string& interpolation, std::vector<float> values) {
  return Channel{node, path, interpolation, std::move(values), {}};
}
Channel quantized(int node, std::vector<std::int16_t> shorts) { return Channel{node, "rotation", "LINEAR", {}, std::move(shorts)}; }

// mount_empty with one animation of `channel` over two keys (six output rows for CUBICSPLINE), in
// a second buffer of its own.
std::vector<Diagnostic> animated_mount_empty(const Channel& channel, bool through_pointer = false,
                                             bool node_too = false) {
  json doc = json::parse(testing::read_file(testing::data_dir() / "frames" / "mount_empty.gltf"));
  const int n = channel.path == "rotation" ? 4 : 3;
  const bool quantized = !channel.shorts.empty();
  std::vector<std::uint8_t> bytes(8);
  const float times[2] = {0.0f, 1.0f};
  std::memcpy(bytes.data(), times, 8);
  const std::size_t output_bytes = quantized ? channel.shorts.size() * 2 : channel.values.size() * 4;
  bytes.resize(8 + output_bytes);
  std::memcpy(bytes.data() + 8, quantized ? static_cast<const void*>(channel.shorts.data()) : channel.values.data(),
              output_bytes);
  const std::size_t buffer = doc["buffers"].size();
  doc["buffers"].push_back({{"byteLength", bytes.size()},
                            {"uri", "data:application/octet-stream;base64," + testing::base64(bytes)}});
  const std::size_t view = doc["bufferViews"].size();
  doc["bufferViews"].push_back({{"buffer", buffer}, {"byteOffset", 0}, {"byteLength", 8}});
  doc["bufferViews"].push_back({{"buffer", buffer}, {"byteOffset", 8}, {"byteLength", output_bytes}});
  const std::size_t input = doc["accessors"].size();
  doc["accessors"].push_back(
      {{"bufferView", view}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}, {"min", {0.0}}, {"max", {1.0}}});
  json output = {{"bufferView", view + 1},
                 {"componentType", quantized ? 5122 : 5126},
                 {"count", (quantized ? channel.shorts.size() : channel.values.size()) / n},
                 {"type", n == 4 ? "VEC4" : "VEC3"}};
  if (quantized) output["normalized"] = true;
  doc["accessors"].push_back(output);
  json target = {{"node", channel.node}, {"path", channel.path}};
  if (through_pointer) {
    target = {{"path", "pointer"},
              {"extensions", {{"KHR_animation_pointer", {{"pointer", "/nodes/" + std::to_string(channel.node) + "/" + channel.path}}}}}};
    if (node_too) target["node"] = channel.node;  // which the extension forbids; the pointer is read
    doc["extensionsUsed"].push_back("KHR_animation_pointer");
  }
  doc["animations"] = json::array({{{"name", "pose"},
                                    {"samplers", {{{"input", input}, {"output", input + 1}, {"interpolation", channel.interpolation}}}},
                                    {"channels", {{{"sampler", 0}, {"target", target}}}}}});
  testing::TempDir dir;
  testing::write_file(dir / "animated.gltf", doc.dump());
  return animated(dir / "animated.gltf");
}

const float kHalf45 = static_cast<float>(std::sin(M_PI / 8)), kCos45 = static_cast<float>(std::cos(M_PI / 8));

TEST(Animations, BlendersConstantChannelsOfAnIdleActionMoveNothing) {
  EXPECT_TRUE(animated(testing::data_dir() / "blender" / "idle_bones.glb").empty());
}

// Blender exported both actions of the file: the idle one, and the one turning the upper bone.
// Only the upper bone is named, though the action has constant channels for the other two (and
// float32 noise of 5e-8 m on the hand's, which moves nothing).
TEST(Animations, OnlyTheBoneAnActionTurnsIsNamed) {
  const auto found = animated(testing::data_dir() / "blender" / "waving_bones.glb");
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].severity, Severity::kWarning);
  EXPECT_EQ(found[0].pointer, "/animations/1/channels/4");  // the upper bone's rotation
  EXPECT_NE(found[0].message.find("animation 1 'rigAction.001' moves node 1 'upper' (rotation): "), std::string::npos)
      << found[0].message;
  EXPECT_EQ(found[0].message.find("'hand'"), std::string::npos) << found[0].message;
  EXPECT_EQ(found[0].message.find("'lower'"), std::string::npos) << found[0].message;
}

// gltfpack -cc rounds keys through EXT_meshopt_compression's filters (here to 8 bits: 0.0056 a
// stored quaternion component), far more than float32 does: the idle bones come back off their
// rest by more than 1e-5 rad, and are still at rest as far as the file can say.
TEST(Animations, KeysRoundedByAMeshoptFilterAreReadAtTheFilesResolution) {
  EXPECT_TRUE(animated(testing::data_dir() / "blender" / "idle_bones_meshopt.glb").empty());
  const auto found = animated(testing::data_dir() / "blender" / "waving_bones_meshopt.glb");
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].pointer, "/animations/1/channels/4");
  EXPECT_NE(found[0].message.find("moves node 2 'upper' (rotation): "), std::string::npos) << found[0].message;
  EXPECT_EQ(found[0].message.find("'hand'"), std::string::npos) << found[0].message;
}

// One view holds every channel's keys, and each key is read at its own resolution: a coarse key
// elsewhere in the view (a 20 m translation, or a hostile zero stored with exponent 127 or a
// quaternion with sf = 3) widened the tolerance of every channel, and a 5 cm move or a 30 degree
// turn of the hand went unreported (review s70rev D3; tests/data/blender/meshopt_edits).
TEST(Animations, EachKeyIsReadAtItsOwnResolution) {
  const auto dir = testing::data_dir() / "blender" / "meshopt_edits";
  for (const char* file : {"control.glb", "hidden.glb", "hostile.glb"}) {
    SCOPED_TRACE(file);
    bool hand = false;
    for (const Diagnostic& d : animated(dir / file)) {
      if (d.pointer.rfind("/animations/1/", 0) == 0 && d.message.find("node 1 'hand' (translation)") != std::string::npos) {
        hand = true;
      }
    }
    EXPECT_TRUE(hand);
  }
  for (const char* file : {"qcontrol.glb", "qhostile.glb"}) {
    SCOPED_TRACE(file);
    bool hand = false;
    for (const Diagnostic& d : animated(dir / file)) {
      if (d.pointer.rfind("/animations/1/", 0) == 0 && d.message.find("node 1 'hand' (rotation)") != std::string::npos) hand = true;
    }
    EXPECT_TRUE(hand);
  }
}

TEST(Animations, KeysAtTheRestValueMoveNothing) {
  // The rest rotation and its negation (one rotation); a translation 1e-8 m off; scale 1 on a node
  // that has none.
  EXPECT_TRUE(animated_mount_empty(floats(1, "rotation", "LINEAR", {0, 0, kHalf45, kCos45, 0, 0, -kHalf45, -kCos45})).empty());
  EXPECT_TRUE(animated_mount_empty(floats(2, "translation", "LINEAR", {0.1f, 0, 0, 0.1f, 1e-8f, 0})).empty());
  EXPECT_TRUE(animated_mount_empty(floats(0, "scale", "LINEAR", {1, 1, 1, 1, 1, 1})).empty());
  // Quantized to normalized shorts: within half a step of the rest.
  const auto q = [](float x) { return static_cast<std::int16_t>(std::lround(x * 32767)); };
  EXPECT_TRUE(animated_mount_empty(quantized(1, {0, 0, q(kHalf45), q(kCos45), 0, 0, q(kHalf45), q(kCos45)})).empty());
}

TEST(Animations, AKeyAwayFromTheRestIsNamed) {
  // 1 mm along X.
  auto found = animated_mount_empty(floats(2, "translation", "LINEAR", {0.1f, 0, 0, 0.101f, 0, 0}));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].pointer, "/animations/0/channels/0");
  EXPECT_NE(found[0].message.find("animation 0 'pose' moves node 2 'arm' (translation): "), std::string::npos)
      << found[0].message;
  // A pose held constant, but not the rest one: 90 degrees about Z.
  const float half90 = static_cast<float>(std::sqrt(0.5));
  found = animated_mount_empty(floats(1, "rotation", "STEP", {0, 0, half90, half90, 0, 0, half90, half90}));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NE(found[0].message.find("moves node 1 'mount' (rotation)"), std::string::npos) << found[0].message;
  // Quantized, 10 degrees off the rest.
  const auto q = [](double x) { return static_cast<std::int16_t>(std::lround(x * 32767)); };
  const double half55 = 55.0 / 2 * M_PI / 180;
  EXPECT_EQ(animated_mount_empty(quantized(1, {0, 0, q(kHalf45), q(kCos45), 0, 0, q(std::sin(half55)), q(std::cos(half55))})).size(),
            1u);
}

// KHR_animation_pointer's channels name the node in a JSON pointer ("/nodes/2/translation").
TEST(Animations, AChannelOfKhrAnimationPointerIsReadAsItsNodes) {
  EXPECT_TRUE(animated_mount_empty(floats(2, "translation", "LINEAR", {0.1f, 0, 0, 0.1f, 0, 0}), true).empty());
  const auto found = animated_mount_empty(floats(2, "translation", "LINEAR", {0.1f, 0, 0, 0.2f, 0, 0}), true);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NE(found[0].message.find("moves node 2 'arm' (translation)"), std::string::npos) << found[0].message;
  // With a stray target.node beside the pointer, the pointer is still what moves.
  EXPECT_EQ(animated_mount_empty(floats(2, "translation", "LINEAR", {0.1f, 0, 0, 0.2f, 0, 0}), true, true).size(), 1u);
  // A pointer at anything else of a node (its weights, an extension's property) moves nothing.
  EXPECT_TRUE(animated_mount_empty(floats(2, "weights", "LINEAR", {0.1f, 0, 0, 0.2f, 0, 0}), true).empty());
}

// CUBICSPLINE keys are (in-tangent, value, out-tangent): equal values with a tangent that is not
// zero move the node between them; zero tangents do not.
TEST(Animations, ACubicSplineTangentMovesTheNode) {
  const std::vector<float> still = {0, 0, 0, 0.1f, 0, 0, 0, 0, 0, 0, 0, 0, 0.1f, 0, 0, 0, 0, 0};
  EXPECT_TRUE(animated_mount_empty(floats(2, "translation", "CUBICSPLINE", still)).empty());
  std::vector<float> swinging = still;
  swinging[7] = 0.5f;  // the first key's out-tangent along Y
  const auto found = animated_mount_empty(floats(2, "translation", "CUBICSPLINE", swinging));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NE(found[0].message.find("moves node 2 'arm' (translation)"), std::string::npos) << found[0].message;
}

}  // namespace
}  // namespace rdtf
