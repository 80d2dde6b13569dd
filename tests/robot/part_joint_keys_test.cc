// Joint keys on a part (the child link node) below a joint empty whose keys are read are not read
// at all (core/robot/robot.cc: the joint node nearest the part that has any is the source). A
// modeller who types a limit on the part, or types it wrong, is told so; keys that say the same
// as the empty's are no news. On tests/data/blender/arm3.gltf: node 7 'shoulder' (revolute, z,
// [-1.57, 1.57]) above node 6 'upper_arm'.
#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

using nlohmann::json;

std::vector<Diagnostic> ignored_keys(const json& part_extras, Robot* robot = nullptr) {
  json doc = json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf"));
  doc["nodes"][6]["extras"] = part_extras;
  testing::TempDir dir;
  testing::write_file(dir / "arm3.gltf", doc.dump());
  std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin", dir / "arm3.bin");
  Diagnostics diag;
  auto conversion = convert_file(dir / "arm3.gltf", {}, diag);
  EXPECT_TRUE(conversion.has_value());
  if (conversion && robot) *robot = conversion->robot;
  std::vector<Diagnostic> found;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == codes::RDTF_NODE_EXTRAS_IGNORED) found.push_back(d);
  }
  return found;
}

TEST(PartJointKeys, AnInvalidOrDifferentKeyOnThePartIsNamedAsNotRead) {
  Robot robot;
  auto found = ignored_keys({{"rdtf_lower", "abc"}}, &robot);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].severity, Severity::kWarning);
  EXPECT_EQ(found[0].pointer, "/nodes/6/extras");
  EXPECT_NE(found[0].message.find("node 6 'upper_arm': joint '"), std::string::npos) << found[0].message;
  EXPECT_NE(found[0].message.find("rdtf_lower 'abc' (-1.57 there) is not read: the joint's properties are those of "
                                  "node 7 'shoulder'"),
            std::string::npos)
      << found[0].message;
  // The empty's limits stand.
  ASSERT_EQ(robot.joints.size(), 2u);
  for (const Joint& joint : robot.joints) {
    if (joint.child_link >= 0 && robot.links[joint.child_link].name == "upper_arm") {
      ASSERT_TRUE(joint.limits);
      EXPECT_EQ(joint.limits->lower, -1.57);
    }
  }
  found = ignored_keys({{"rdtf_effort", 5.0}, {"rdtf_upper", 2.0}});
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NE(found[0].message.find("rdtf_upper 2.0 (1.57 there), rdtf_effort 5.0 (not there) are not read"), std::string::npos)
      << found[0].message;
}

TEST(PartJointKeys, KeysThatSayWhatTheEmptySaysAreNoNews) {
  EXPECT_TRUE(ignored_keys({{"rdtf_joint", "revolute"}, {"rdtf_lower", -1.57}, {"rdtf_upper", 1.57}}).empty());
  EXPECT_TRUE(ignored_keys({{"rdtf_density", 2700.0}}).empty());  // no joint key at all
}

}  // namespace
}  // namespace rdtf
