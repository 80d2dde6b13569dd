// extras.RDTF of the wrong shape is refused, naming the place, rather than dropped or copied into
// the output as it is (the output would then not be valid RDTF, or another robot). The model is
// tests/data/khr/arm_extras.gltf: base, arm, slider and arm's inertial node (3).
#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

using nlohmann::json;

json arm() { return json::parse(testing::read_file(testing::data_dir() / "khr" / "arm_extras.gltf")); }

// Converts; the error of `code`, which must be there, and the conversion must fail.
Diagnostic refused(const json& doc, const std::string& code) {
  testing::TempDir dir;
  testing::write_file(dir / "arm.gltf", doc.dump());
  Diagnostics diag;
  EXPECT_FALSE(convert_file(dir / "arm.gltf", {}, diag).has_value());
  for (const Diagnostic& d : diag.all()) {
    if (d.code == code && d.severity == Severity::kError) return d;
  }
  ADD_FAILURE() << "no " << code;
  return {};
}

TEST(RdtfEntries, RdtfThatIsNoObjectIsRefused) {
  json doc = arm();
  doc["extras"]["RDTF"] = 5;
  const Diagnostic d = refused(doc, codes::RDTF_INVALID_VALUE);
  EXPECT_EQ(d.pointer, "/extras/RDTF");
  EXPECT_NE(d.message.find("extras.RDTF is 5, not an object"), std::string::npos) << d.message;
}

TEST(RdtfEntries, NodesThatAreNoArrayAreRefused) {
  json doc = arm();
  doc["extras"]["RDTF"] = {{"nodes", "x"}};
  const Diagnostic d = refused(doc, codes::RDTF_INVALID_VALUE);
  EXPECT_EQ(d.pointer, "/extras/RDTF/nodes");
  EXPECT_NE(d.message.find("'x', not an array"), std::string::npos) << d.message;
}

TEST(RdtfEntries, AJointOrInertialThatIsNoObjectIsRefused) {
  for (const char* key : {"joint", "inertial"}) {
    json doc = arm();
    doc["extras"]["RDTF"] = {{"nodes", {{{"node", 1}, {key, "revolute"}}}}};
    const Diagnostic d = refused(doc, codes::RDTF_INVALID_VALUE);
    EXPECT_EQ(d.pointer, std::string("/extras/RDTF/nodes/0/") + key);
    EXPECT_NE(d.message.find("entry for node 1 'arm': " + std::string(key) + " is 'revolute', not an object"),
              std::string::npos)
        << d.message;
  }
}

// Listed twice, a node's type and properties would be whichever entry a reader takes.
TEST(RdtfEntries, ANodeListedTwiceIsRefused) {
  json doc = arm();
  doc["extras"]["RDTF"] = {{"nodes", {{{"node", 2}, {"type", "link"}}, {{"node", 2}, {"type", "mesh"}}}}};
  const Diagnostic d = refused(doc, codes::RDTF_INVALID_NODE_ENTRY);
  EXPECT_EQ(d.pointer, "/extras/RDTF/nodes/1/node");
  EXPECT_NE(d.message.find("node 2 'slider' is listed again (first at /extras/RDTF/nodes/0)"), std::string::npos)
      << d.message;
}

// The base link (a 0.016 m^3 box of 5 kg by rdtf_mass) typed joint by its author: its mass is
// lost, and a warning says so.
TEST(RdtfEntries, AMeshTypedJointIsNamed) {
  json doc = arm();
  doc["extras"]["RDTF"] = {{"nodes", {{{"node", 2}, {"type", "joint"}}}}};
  testing::TempDir dir;
  testing::write_file(dir / "arm.gltf", doc.dump());
  Diagnostics diag;
  ASSERT_TRUE(convert_file(dir / "arm.gltf", {}, diag).has_value());
  bool named = false;
  for (const Diagnostic& d : diag.all()) {
    named |= d.code == codes::MESH_WITHOUT_LINK && d.pointer == "/nodes/2" &&
             d.message.find("node 2 'slider' has a mesh but is typed joint") != std::string::npos;
  }
  EXPECT_TRUE(named);
}

}  // namespace
}  // namespace rdtf
