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

// An authored inertial in a frame other than the link's would be read in the wrong one.
TEST(RdtfEntries, AnInertialInAnotherFrameIsRefused) {
  json doc = arm();
  doc["extras"]["RDTF"] = {{"nodes",
                            {{{"node", 3},
                              {"type", "inertial"},
                              {"inertial", {{"mass", 1.0}, {"inertia", {0.01, 0, 0, 0.01, 0, 0.01}}, {"frame", "world"}}}}}}};
  const Diagnostic d = refused(doc, codes::RDTF_INVALID_VALUE);
  EXPECT_EQ(d.pointer, "/extras/RDTF/nodes/0/inertial/frame");
  EXPECT_NE(d.message.find("frame 'world' is not \"link\""), std::string::npos) << d.message;
}

// A refused entry is refused, not also compared with the node's rdtf_inertial as if it said
// "computed from the geometry".
TEST(RdtfEntries, ARefusedInertialIsNotComparedWithTheNodeExtras) {
  json doc = arm();
  doc["nodes"][3]["extras"]["rdtf_inertial"] = {{"mass", 1.0}, {"inertia", {0.01, 0, 0, 0.01, 0, 0.01}}};
  doc["extras"]["RDTF"] = {
      {"nodes", {{{"node", 3}, {"type", "inertial"}, {"inertial", {{"mass", -1.0}, {"inertia", {0.01, 0, 0, 0.01, 0, 0.01}}}}}}}};
  testing::TempDir dir;
  testing::write_file(dir / "arm.gltf", doc.dump());
  Diagnostics diag;
  EXPECT_FALSE(convert_file(dir / "arm.gltf", {}, diag).has_value());
  bool refused = false;
  for (const Diagnostic& d : diag.all()) {
    EXPECT_NE(d.code, codes::RDTF_NODE_EXTRAS_IGNORED) << format(d);
    refused = refused || (d.code == codes::RDTF_INVALID_VALUE && d.message.find("kg is negative: a mass is 0 or more") != std::string::npos);
  }
  EXPECT_TRUE(refused);
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

// rdtf's output re-packed by a tool that renumbers nodes (glTF-Transform prune, flatten, join)
// keeps its extras.RDTF: the error says why its entries point past the nodes, and how to recover
// (s90tools D5).
TEST(RdtfEntries, AnEntryPastTheNodesOfARepackedFileSaysWhy) {
  json doc = arm();
  doc["extras"]["RDTF"] = {{"nodes", {{{"node", 9}, {"type", "mesh"}}}}};
  const Diagnostic plain = refused(doc, codes::RDTF_INVALID_NODE_ENTRY);
  EXPECT_NE(plain.message.find("the index of an existing node (0 to 3); it has 9"), std::string::npos) << plain.message;
  EXPECT_EQ(plain.message.find("renumbers"), std::string::npos) << plain.message;
  doc["asset"]["generator"] = "glTF-Transform v4.5.1";
  const Diagnostic repacked = refused(doc, codes::RDTF_INVALID_NODE_ENTRY);
  EXPECT_NE(repacked.message.find("'glTF-Transform v4.5.1', which renumbers or removes nodes"), std::string::npos)
      << repacked.message;
  EXPECT_NE(repacked.message.find("remove extras.RDTF"), std::string::npos) << repacked.message;
}

// Another major version may give its keys other meanings: refused, not read as 1.0.
TEST(RdtfEntries, AVersionThatIsNotFormatOneIsRefused) {
  for (const json& version : {json("2.0"), json("0.9"), json(1.0), json("1"), json("v1.0"), json("1.0.0"),
                              json(".1"), json("1.x")}) {
    json doc = arm();
    doc["extras"]["RDTF"]["version"] = version;
    const Diagnostic d = refused(doc, codes::RDTF_INVALID_VALUE);
    EXPECT_EQ(d.pointer, "/extras/RDTF/version") << version;
    EXPECT_NE(d.message.find("extras.RDTF.version is " + (version.is_string() ? "'" + version.get<std::string>() + "'"
                                                                               : version.dump())),
              std::string::npos)
        << d.message;
  }
}

// A later 1.x converts as 1.0 does, with one warning, and keeps its version and keys.
TEST(RdtfEntries, ALaterMinorVersionIsReadAsOneZeroWithAWarning) {
  const auto convert_with = [](const json& rdtf, Diagnostics& diag) {
    json doc = arm();
    doc["extras"]["RDTF"] = rdtf;
    testing::TempDir dir;
    testing::write_file(dir / "arm.gltf", doc.dump());
    auto conversion = convert_file(dir / "arm.gltf", {}, diag);
    EXPECT_TRUE(conversion.has_value());
    return conversion;
  };
  Diagnostics plain_diag;
  const auto plain = convert_with({{"version", "1.0"}}, plain_diag);
  EXPECT_FALSE(plain_diag.contains(codes::RDTF_VERSION_NEWER));
  Diagnostics newer_diag;
  const auto newer = convert_with({{"version", "1.12"}, {"futureKey", {1, 2}}}, newer_diag);
  ASSERT_TRUE(plain && newer);
  int warnings = 0;
  for (const Diagnostic& d : newer_diag.all()) {
    if (d.code != codes::RDTF_VERSION_NEWER) continue;
    ++warnings;
    EXPECT_EQ(d.severity, Severity::kWarning);
    EXPECT_EQ(d.pointer, "/extras/RDTF/version");
    EXPECT_NE(d.message.find("'1.12', newer than the 1.0"), std::string::npos) << d.message;
  }
  EXPECT_EQ(warnings, 1);
  const auto& written = newer->asset.document["extras"]["RDTF"];
  EXPECT_EQ(written["version"], "1.12");
  EXPECT_EQ(written["futureKey"], Json({1, 2}));
  EXPECT_EQ(plain->asset.document["extras"]["RDTF"]["nodes"], written["nodes"]);
  ASSERT_EQ(plain->robot.links.size(), newer->robot.links.size());
  for (std::size_t i = 0; i < plain->robot.links.size(); ++i) {
    EXPECT_EQ(plain->robot.links[i].inertial.mass, newer->robot.links[i].inertial.mass);
  }
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

// A node outside the converted scene gets no type, however its author typed it: a second Blender
// scene holding a re-imported rdtf output types its nodes by rdtf_type, and a link typed there,
// which the robot (built from the scene) does not hold, crashed rdtf and rdtfd (s80spec D1).
TEST(RdtfEntries, NodesTypedOutsideTheSceneAreLeftOut) {
  for (const bool by_entry : {false, true}) {
    json doc = arm();
    doc["nodes"].push_back({{"name", "base.001"}, {"children", {5}}, {"extras", {{"rdtf_type", "link"}}}});  // 4
    doc["nodes"].push_back({{"name", "base.001_mesh"}, {"mesh", 0}, {"extras", {{"rdtf_type", "mesh"}}}});  // 5
    doc["scenes"].push_back({{"name", "Scene.001"}, {"nodes", {4}}});
    doc["scene"] = 0;
    if (by_entry) {
      doc["nodes"][4].erase("extras");
      doc["nodes"][5].erase("extras");
      doc["extras"]["RDTF"] = {{"nodes", {{{"node", 4}, {"type", "link"}}, {{"node", 5}, {"type", "link"}}}}};
    }
    testing::TempDir dir;
    testing::write_file(dir / "arm.gltf", doc.dump());
    Diagnostics diag;
    const auto conversion = convert_file(dir / "arm.gltf", {}, diag);
    ASSERT_TRUE(conversion.has_value()) << by_entry;
    ASSERT_EQ(conversion->robot.links.size(), 3u);
    for (const Link& link : conversion->robot.links) EXPECT_LT(link.node, 4) << link.name;
    for (const Json& entry : conversion->asset.document["extras"]["RDTF"]["nodes"]) {
      EXPECT_NE(entry["node"], 4) << entry;
      EXPECT_NE(entry["node"], 5) << entry;
    }
  }
}

}  // namespace
}  // namespace rdtf
