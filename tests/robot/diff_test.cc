// diff_robots on robots converted from generated glTF documents: each edit of a save names the
// elements it touched and the aspects of each, and nothing else.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rdtf/convert.h"
#include "rdtf/diff.h"

namespace rdtf {
namespace {

using nlohmann::json;

std::string base64(const std::string& bytes) {
  static const char* const kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) | static_cast<unsigned char>(bytes[i + 2]);
    for (int shift : {18, 12, 6, 0}) out += kTable[v >> shift & 63];
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kTable[v >> 18 & 63];
    out += kTable[v >> 12 & 63];
    out += i + 1 < bytes.size() ? kTable[v >> 6 & 63] : '=';
    out += '=';
  }
  return out;
}

// base (box) -> joint_1 (revolute) -> link_1 (box) -> joint_2 (revolute, limits) -> link_2 (box).
// Each link has a mesh of its own: positions[link] are the box's 8 corners, editable per test.
struct Chain {
  std::vector<std::vector<float>> positions = std::vector<std::vector<float>>(3);
  json nodes;

  Chain() {
    for (auto& p : positions) {
      for (int c = 0; c < 8; ++c) {
        for (int axis = 0; axis < 3; ++axis) p.push_back(c & (1 << axis) ? 0.05f : -0.05f);
      }
    }
    nodes = json::array({
        {{"name", "base"}, {"mesh", 0}, {"children", {1}}},
        {{"name", "joint_1"}, {"translation", {0.0, 0.2, 0.0}},
         {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", {0.0, 0.0, 1.0}}}}, {"children", {2}}},
        {{"name", "link_1"}, {"mesh", 1}, {"children", {3}}},
        {{"name", "joint_2"}, {"translation", {0.0, 0.2, 0.0}},
         {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", {1.0, 0.0, 0.0}}, {"rdtf_lower", -1.0},
                     {"rdtf_upper", 1.0}, {"rdtf_effort", 5.0}, {"rdtf_velocity", 2.0}}},
         {"children", {4}}},
        {{"name", "link_2"}, {"mesh", 2}},
    });
  }

  std::string gltf() const {
    std::string bin;
    const std::uint16_t quads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
    for (const auto& p : positions) bin.append(reinterpret_cast<const char*>(p.data()), p.size() * sizeof(float));
    for (const auto& q : quads) {
      for (std::uint16_t v : {q[0], q[1], q[2], q[0], q[2], q[3]}) bin.append(reinterpret_cast<const char*>(&v), 2);
    }
    json meshes = json::array(), accessors = json::array(), views = json::array();
    for (std::size_t m = 0; m < positions.size(); ++m) {
      float lo[3] = {1e9f, 1e9f, 1e9f}, hi[3] = {-1e9f, -1e9f, -1e9f};
      for (std::size_t k = 0; k < positions[m].size(); ++k) {
        lo[k % 3] = std::min(lo[k % 3], positions[m][k]);
        hi[k % 3] = std::max(hi[k % 3], positions[m][k]);
      }
      views.push_back({{"buffer", 0}, {"byteOffset", 96 * m}, {"byteLength", 96}});
      accessors.push_back({{"bufferView", m}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"},
                           {"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}});
      const json primitive = {{"attributes", {{"POSITION", m}}}, {"indices", positions.size()}};
      meshes.push_back({{"primitives", json::array({primitive})}});
    }
    views.push_back({{"buffer", 0}, {"byteOffset", 96 * positions.size()}, {"byteLength", 72}});
    accessors.push_back({{"bufferView", positions.size()}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}});
    const json document = {
        {"asset", {{"version", "2.0"}}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0}}}}},
        {"nodes", nodes},
        {"meshes", meshes},
        {"accessors", accessors},
        {"bufferViews", views},
        {"buffers", {{{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}}}};
    return document.dump();
  }
};

// A digest good enough to tell contents apart in a test (the daemon passes SHA-256): FNV-1a 64, as hex.
std::string test_digest(std::span<const std::uint8_t> bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::uint8_t b : bytes) {
    h ^= b;
    h *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

RobotFacts facts_of(const Chain& chain) {
  const std::string text = chain.gltf();
  Diagnostics diag("chain.gltf");
  auto asset = load_gltf_from_memory(std::vector<std::uint8_t>(text.begin(), text.end()), "chain.gltf", ".",
                                     LoadLimits{}, diag);
  EXPECT_TRUE(asset.has_value()) << diag.all().size();
  if (!asset) return {};
  auto conversion = convert(std::move(*asset), ConvertOptions{}, diag);
  EXPECT_TRUE(conversion.has_value());
  if (!conversion) return {};
  std::vector<std::string> urdf_links, urdf_joints;
  for (const Link& link : conversion->robot.links) urdf_links.push_back("urdf_" + link.name);
  for (const Joint& joint : conversion->robot.joints) urdf_joints.push_back("urdf_" + joint.name);
  return robot_facts(conversion->robot, urdf_links, urdf_joints,
                     link_geometry_digests(conversion->asset, conversion->robot, test_digest));
}

std::string describe(const std::vector<ElementChange>& changes) {
  std::string out;
  for (const auto& c : changes) {
    out += std::string(to_string(c.element)) + " " + to_string(c.kind) + " " + c.name + " (" + c.urdf_name + ")";
    for (const auto& a : aspect_names(c.aspects)) out += " " + a;
    out += "; ";
  }
  return out;
}

std::vector<ElementChange> diff_after(const std::function<void(Chain&)>& edit) {
  Chain before;
  Chain after;
  edit(after);
  return diff_robots(facts_of(before), facts_of(after));
}

TEST(RobotDiff, TheSameContentHasNoChange) {
  const auto changes = diff_after([](Chain&) {});
  EXPECT_TRUE(changes.empty()) << describe(changes);
  const RobotFacts facts = facts_of(Chain());
  ASSERT_EQ(facts.links.size(), 3u);
  ASSERT_EQ(facts.joints.size(), 2u);
  // Three meshes of the same corners placed the same way in their link frames: one digest.
  EXPECT_EQ(facts.links[0].geometry, facts.links[1].geometry);
  EXPECT_FALSE(facts.links[0].geometry.empty());
}

TEST(RobotDiff, OneJointLimitNamesThatJointAndOnlyLimits) {
  const auto changes = diff_after([](Chain& c) { c.nodes[3]["extras"]["rdtf_upper"] = 1.5; });
  ASSERT_EQ(changes.size(), 1u) << describe(changes);
  EXPECT_EQ(changes[0].element, ElementChange::Element::kJoint);
  EXPECT_EQ(changes[0].kind, ElementChange::Kind::kChanged);
  EXPECT_EQ(changes[0].name, "joint_2");
  EXPECT_EQ(changes[0].urdf_name, "urdf_joint_2");
  EXPECT_EQ(changes[0].aspects, kAspectLimits);
  EXPECT_EQ(aspect_names(changes[0].aspects), std::vector<std::string>{"limits"});
}

TEST(RobotDiff, DynamicsAxisAndTypeAreTheirOwnAspects) {
  auto changes = diff_after([](Chain& c) { c.nodes[3]["extras"]["rdtf_damping"] = 0.5; });
  ASSERT_EQ(changes.size(), 1u) << describe(changes);
  EXPECT_EQ(changes[0].name, "joint_2");
  EXPECT_EQ(changes[0].aspects, kAspectDynamics);

  changes = diff_after([](Chain& c) { c.nodes[1]["extras"]["rdtf_axis"] = {0.0, 1.0, 0.0}; });
  ASSERT_EQ(changes.size(), 1u) << describe(changes);
  EXPECT_EQ(changes[0].name, "joint_1");
  EXPECT_EQ(changes[0].aspects, kAspectAxis);

  changes = diff_after([](Chain& c) { c.nodes[1]["extras"]["rdtf_joint"] = "continuous"; });
  ASSERT_EQ(changes.size(), 1u) << describe(changes);
  EXPECT_EQ(changes[0].name, "joint_1");
  EXPECT_EQ(changes[0].aspects, kAspectType);
}

TEST(RobotDiff, RenameIsRemovedPlusAdded) {
  const auto changes = diff_after([](Chain& c) { c.nodes[3]["name"] = "elbow"; });
  ASSERT_EQ(changes.size(), 3u) << describe(changes);
  // The child link's parent joint has a new name too.
  EXPECT_EQ(changes[0].element, ElementChange::Element::kLink);
  EXPECT_EQ(changes[0].kind, ElementChange::Kind::kChanged);
  EXPECT_EQ(changes[0].name, "link_2");
  EXPECT_EQ(changes[0].aspects, kAspectParent);
  EXPECT_EQ(changes[1].element, ElementChange::Element::kJoint);
  EXPECT_EQ(changes[1].kind, ElementChange::Kind::kRemoved);
  EXPECT_EQ(changes[1].name, "joint_2");
  EXPECT_EQ(changes[1].urdf_name, "urdf_joint_2");
  EXPECT_EQ(changes[2].kind, ElementChange::Kind::kAdded);
  EXPECT_EQ(changes[2].name, "elbow");
  EXPECT_EQ(changes[2].urdf_name, "urdf_elbow");
  EXPECT_EQ(changes[2].aspects, 0u);
}

TEST(RobotDiff, MovedVertexIsThatLinksGeometryAndInertial) {
  // Corner 7 (+x +y +z) of link_1's box pulled outwards: a different solid.
  const auto changes = diff_after([](Chain& c) { c.positions[1][7 * 3 + 0] = 0.08f; });
  ASSERT_EQ(changes.size(), 1u) << describe(changes);
  EXPECT_EQ(changes[0].element, ElementChange::Element::kLink);
  EXPECT_EQ(changes[0].name, "link_1");
  EXPECT_EQ(changes[0].urdf_name, "urdf_link_1");
  EXPECT_EQ(changes[0].aspects, kAspectGeometry | kAspectInertial);
}

TEST(RobotDiff, JointOriginMovesNothingDownstream) {
  // The child links move in the scene, but nothing in their own frames does.
  const auto changes = diff_after([](Chain& c) { c.nodes[1]["translation"] = {0.0, 0.3, 0.1}; });
  ASSERT_EQ(changes.size(), 1u) << describe(changes);
  EXPECT_EQ(changes[0].name, "joint_1");
  EXPECT_EQ(changes[0].aspects, kAspectOrigin);
}

TEST(RobotDiff, AddedAndRemovedLinks) {
  // link_2 and joint_2 gone; and back again from nothing.
  Chain full;
  Chain cut;
  cut.nodes[2].erase("children");
  cut.nodes.erase(4);
  cut.nodes.erase(3);
  auto changes = diff_robots(facts_of(full), facts_of(cut));
  ASSERT_EQ(changes.size(), 2u) << describe(changes);
  EXPECT_EQ(changes[0].element, ElementChange::Element::kLink);
  EXPECT_EQ(changes[0].kind, ElementChange::Kind::kRemoved);
  EXPECT_EQ(changes[0].name, "link_2");
  EXPECT_EQ(changes[1].element, ElementChange::Element::kJoint);
  EXPECT_EQ(changes[1].kind, ElementChange::Kind::kRemoved);
  EXPECT_EQ(changes[1].name, "joint_2");

  changes = diff_robots(RobotFacts{}, facts_of(full));
  ASSERT_EQ(changes.size(), 5u) << describe(changes);
  for (const auto& c : changes) EXPECT_EQ(c.kind, ElementChange::Kind::kAdded) << describe(changes);
}

TEST(RobotDiff, ReparentedJointNamesParentAndChild) {
  RobotFacts before = facts_of(Chain());
  RobotFacts after = before;
  after.joints[1].parent = "base";
  after.joints[0].child = "link_2";
  const auto changes = diff_robots(before, after);
  ASSERT_EQ(changes.size(), 2u) << describe(changes);
  EXPECT_EQ(changes[0].name, "joint_1");
  EXPECT_EQ(changes[0].aspects, kAspectChild);
  EXPECT_EQ(changes[1].name, "joint_2");
  EXPECT_EQ(changes[1].aspects, kAspectParent);
}

TEST(RobotDiff, RepeatedNamesMatchInOrder) {
  RobotFacts before = facts_of(Chain());
  before.links[1].name = "part";
  before.links[2].name = "part";
  RobotFacts after = before;
  after.links[2].mass += 1;  // The second "part".
  const auto changes = diff_robots(before, after);
  ASSERT_EQ(changes.size(), 1u) << describe(changes);
  EXPECT_EQ(changes[0].name, "part");
  EXPECT_EQ(changes[0].urdf_name, "urdf_link_2");
  EXPECT_EQ(changes[0].aspects, kAspectInertial);
}

}  // namespace
}  // namespace rdtf
