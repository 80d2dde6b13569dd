// What rdtf's output says about the robot, read as a third party reads it (s101fmt): extras.RDTF
// holds every link's inertial and joints' axes as unit vectors, and the node extras describe the
// same robot, so that converting the output again gives it unchanged.
#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"
#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using urdf_test::GltfBuilder;

std::size_t node_named(const Json& doc, const std::string& name) {
  for (std::size_t i = 0; i < doc["nodes"].size(); ++i) {
    if (doc["nodes"][i].value("name", "") == name) return i;
  }
  ADD_FAILURE() << "no node " << name;
  return 0;
}

const Json* entry_of(const Json& doc, std::size_t node) {
  for (const Json& entry : doc["extras"]["RDTF"]["nodes"]) {
    if (entry["node"] == node) return &entry;
  }
  return nullptr;
}

Conversion convert_again(const Conversion& first, Diagnostics& diag, double default_density = 1000.0) {
  ConvertOptions options;
  options.default_density = default_density;
  auto again = convert(first.asset, options, diag);
  if (!again) throw std::runtime_error("the output did not convert again");
  return std::move(*again);
}

void expect_same_inertials(const Robot& a, const Robot& b) {
  ASSERT_EQ(a.links.size(), b.links.size());
  for (std::size_t l = 0; l < a.links.size(); ++l) {
    SCOPED_TRACE(a.links[l].name);
    const MassProperties &x = a.links[l].inertial, &y = b.links[l].inertial;
    EXPECT_NEAR(y.mass, x.mass, 1e-12 * x.mass);
    EXPECT_LE((y.center_of_mass - x.center_of_mass).norm(), 1e-12);
    EXPECT_LE((y.inertia - x.inertia).cwiseAbs().maxCoeff(), 1e-12 * x.inertia.cwiseAbs().maxCoeff());
  }
}

// A 0.2 x 0.1 x 0.2 m box link weighed to 3 kg by its rdtf_mass, with a 0.1 m cube of 4000 kg/m^3
// beside it (0.2 m along x): both weigh 4 kg before the link's mass scales them alike, so the
// centre of mass is at x = 0.1. The output wrote the box's scaled density (375) beside the cube's
// authored 4000, and read again the centre of mass moved to 0.145 (s101fmt D1).
TEST(OutputExtras, ALinkMassOverAMeshDensityConvertsAgainUnchanged) {
  GltfBuilder b;
  const int base = b.node("base", -1, Json{{"mesh", b.box_mesh({0.2f, 0.1f, 0.2f})}, {"extras", {{"rdtf_mass", 3.0}}}});
  b.node("cube", base,
         Json{{"mesh", b.box_mesh({0.1f, 0.1f, 0.1f})},
              {"translation", {0.2, 0, 0}},
              {"extras", {{"rdtf_type", "mesh"}, {"rdtf_density", 4000}}}});
  Diagnostics diag;
  const Conversion first = b.convert(diag);
  ASSERT_EQ(first.robot.links.size(), 1u);
  EXPECT_NEAR(first.robot.links[0].inertial.mass, 3.0, 1e-12);
  EXPECT_NEAR(first.robot.links[0].inertial.center_of_mass.x(), 0.1, 1e-7);  // float32 corners
  const Json& out = first.asset.document;
  EXPECT_EQ(out["nodes"][node_named(out, "cube")]["extras"]["rdtf_density"], 4000);
  // The box's density as it was before the link's mass scaled it: the default's, so that read
  // again with another default (--density) its ratio to the cube's stays (s102rev D3).
  EXPECT_NEAR(out["nodes"][node_named(out, "base_mesh")]["extras"]["rdtf_density"].get<double>(), 1000.0, 1e-9);
  for (const double density : {1000.0, 500.0}) {
    Diagnostics again_diag;
    expect_same_inertials(first.robot, convert_again(first, again_diag, density).robot);
    EXPECT_FALSE(again_diag.contains(codes::KHR_PHYSICS_IGNORED));
  }
}

// An inertial authored in node extras (arm_extras.gltf's arm) or KHR motion (arm_khr.gltf's base
// and arm) is in the output's extras.RDTF too, without a source (it reads back as authored): a
// reader of extras.RDTF found entries with no inertial and weighed the geometry (16 kg for 5).
TEST(OutputExtras, AuthoredInertialsAreInExtrasRdtf) {
  for (const std::string& name : {std::string("arm_extras.gltf"), std::string("arm_khr.gltf")}) {
    SCOPED_TRACE(name);
    Diagnostics diag;
    const auto first = convert_file(testing::data_dir() / "khr" / name, {}, diag);
    ASSERT_TRUE(first);
    int authored = 0;
    for (const Link& link : first->robot.links) {
      if (link.inertial_source != InertialSource::kAuthored) continue;
      ++authored;
      const Json* entry = entry_of(first->asset.document, static_cast<std::size_t>(link.inertial_node));
      ASSERT_NE(entry, nullptr) << link.name;
      ASSERT_TRUE(entry->contains("inertial")) << entry->dump();
      EXPECT_EQ((*entry)["inertial"]["mass"].get<double>(), link.inertial.mass);
      EXPECT_FALSE((*entry)["inertial"].contains("source"));
    }
    EXPECT_GT(authored, 0);
    Diagnostics again_diag;
    const Conversion again = convert_again(*first, again_diag);
    expect_same_inertials(first->robot, again.robot);
    EXPECT_FALSE(again_diag.contains(codes::KHR_PHYSICS_IGNORED));
    EXPECT_FALSE(again_diag.contains(codes::RDTF_NODE_EXTRAS_IGNORED));
    for (std::size_t l = 0; l < again.robot.links.size(); ++l) {
      EXPECT_EQ(again.robot.links[l].inertial_source, first->robot.links[l].inertial_source) << again.robot.links[l].name;
    }
  }
}

// A 0.2 x 0.1 x 0.2 m box link whose inertial node carries `rdtf_inertial` in its extras.
Conversion box_with_inertial_extras(const Json& rdtf_inertial) {
  GltfBuilder b;
  const int base = b.node("base", -1, Json{{"mesh", b.box_mesh({0.2f, 0.1f, 0.2f})}});
  b.node("base_inertial", base, Json{{"extras", {{"rdtf_type", "inertial"}, {"rdtf_inertial", rdtf_inertial}}}});
  Diagnostics diag;
  return b.convert(diag);
}

// An rdtf_inertial whose source is not a string is no computed one left by an output: read as
// authored, as before, and the conversion goes on (the stale check threw a JSON type error, s102rev D4).
TEST(OutputExtras, AnInertialSourceOfAnyTypeConverts) {
  for (const Json& source : {Json(1), Json(nullptr), Json(true), Json::object()}) {
    SCOPED_TRACE(source.dump());
    const Conversion c = box_with_inertial_extras(
        {{"mass", 3.0}, {"gravityCenter", {0, 0, 0}}, {"inertia", {1, 0, 0, 1, 0, 1}}, {"source", source}});
    ASSERT_EQ(c.robot.links.size(), 1u);
    EXPECT_EQ(c.robot.links[0].inertial.mass, 3.0);
  }
}

// A computed rdtf_inertial left by an earlier output (a part rescaled since, in Blender) is written
// again: it stayed, telling a reader of node extras 99 kg where extras.RDTF said 4 (s101fmt D6).
TEST(OutputExtras, AStaleComputedInertialInNodeExtrasIsRewritten) {
  const Conversion first = box_with_inertial_extras({{"mass", 99.0}, {"gravityCenter", {0, 0.5, 0}},
                                                     {"inertia", {1, 0, 0, 1, 0, 1}}, {"frame", "link"},
                                                     {"source", "computed"}});
  ASSERT_EQ(first.robot.links.size(), 1u);
  EXPECT_EQ(first.robot.links[0].inertial_source, InertialSource::kComputed);
  const Json& out = first.asset.document;
  const std::size_t inertial = node_named(out, "base_inertial");
  const Json& written = out["nodes"][inertial]["extras"]["rdtf_inertial"];
  EXPECT_EQ(written, (*entry_of(out, inertial))["inertial"]);
  EXPECT_NEAR(written["mass"].get<double>(), 4.0, 1e-6);
}

// A vector axis authored in extras.RDTF goes out as the unit vector rdtf read it as ([0, 2, 0]
// read back as q * axis doubled the slide, s101fmt D9); a named axis is kept as written.
TEST(OutputExtras, AnAuthoredAxisGoesOutAsAUnitVector) {
  // Components beyond 1e154 or below 1e-154 square out of range: normalised all the same (s102rev D2).
  for (const Json& axis : {Json::array({0, 2, 0}), Json("y"), Json::array({0, 1e200, 0}), Json::array({0, 1e-200, 0})}) {
    SCOPED_TRACE(axis.dump());
    GltfBuilder b;
    const int base = b.node("base", -1, Json{{"mesh", b.box_mesh({0.2f, 0.1f, 0.2f})}});
    const int slide = b.node("slide", base, Json{{"translation", {0, 0.1, 0}}});
    b.link_with_mesh("carriage", slide, b.box_mesh({0.1f, 0.1f, 0.1f}));
    b.rdtf_entry(Json{{"node", slide},
                      {"type", "joint"},
                      {"joint", {{"type", "prismatic"}, {"axis", axis}, {"lower", 0}, {"upper", 0.5}}}});
    Diagnostics diag;
    const Conversion first = b.convert(diag);
    ASSERT_EQ(first.robot.joints.size(), 1u);
    EXPECT_TRUE(first.robot.joints[0].axis.isApprox(Eigen::Vector3d::UnitY(), 1e-15));
    const Json* entry = entry_of(first.asset.document, static_cast<std::size_t>(slide));
    ASSERT_NE(entry, nullptr);
    EXPECT_EQ((*entry)["joint"]["axis"], axis.is_string() ? axis : Json::array({0.0, 1.0, 0.0}));
  }
}

}  // namespace
}  // namespace rdtf
