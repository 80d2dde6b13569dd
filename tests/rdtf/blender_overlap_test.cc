// Overlapping parts as a modeller makes them in Blender (tests/data/blender/make_overlap.py): a post
// joined into the base with Ctrl+J, and a motor parented to the arm (a link of its own on a fixed
// joint) sunk into it. The mass is the sum of the meshes' integrals, as Blender's own
// bmesh.calc_volume gives it, and the region counted twice is named with its size, checked against
// Blender's Boolean union (the Exact solver) of the same parts.
#include <cmath>
#include <regex>
#include <string>

#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

constexpr double kFloat32Tolerance = 1e-6;  // float32 positions, as blender_fixtures_test.cc

const Json& blender_says() {
  static const Json record = Json::parse(testing::read_file(testing::data_dir() / "blender" / "overlap.json"));
  return record;
}

double link_volume(const Robot& robot, const std::string& name) {
  for (const Link& link : robot.links) {
    if (link.name == name) return link.inertial.volume;
  }
  ADD_FAILURE() << "no link " << name;
  return 0;
}

// The volume a warning gives ("about 0.0012 m^3").
double volume_in(const std::string& message) {
  std::smatch m;
  if (!std::regex_search(message, m, std::regex("about ([0-9.e+-]+) m\\^3"))) {
    ADD_FAILURE() << message;
    return 0;
  }
  return std::stod(m[1]);
}

// How far the sample may be from the exact region (winding_sample.h): each grid cell the region's
// outline (perimeter `outline`, seen along x) passes through may be misjudged, by at most the
// region's longest chord along x; cells of hy by hz, about 16,384 of them, as near square as the
// body's (y, z) bounds `extent_y` by `extent_z` allow. Then the message's two significant digits.
double allowed(double exact, double outline, double chord, double extent_y, double extent_z) {
  const double ny = std::round(std::sqrt(16384 * extent_y / extent_z));
  const double nz = std::round(16384 / ny);
  const double hy = extent_y / ny, hz = extent_z / nz;
  const double grid = (outline / hy + outline / hz + 64 + 4) * hy * hz * chord;  // 64: the 32-gon's edges, twice
  return grid + 0.05 * (exact + grid);
}

TEST(BlenderOverlap, JoinedAndParentedPartsAreNamedWithTheVolumeCountedTwice) {
  Diagnostics diag;
  const auto conversion = convert_file(testing::data_dir() / "blender" / "overlap_joined.glb", {}, diag);
  ASSERT_TRUE(conversion.has_value()) << diag.all().size();
  const Json& joined = blender_says()["joined"];
  const Json& united = blender_says()["union"];
  // The mass is what the paper's integral gives, the shared region twice, as Blender's own sum.
  const double base = joined["base"].get<double>(), arm = joined["arm"].get<double>();
  EXPECT_NEAR(link_volume(conversion->robot, "base"), base, kFloat32Tolerance * base);
  EXPECT_NEAR(link_volume(conversion->robot, "arm") + link_volume(conversion->robot, "arm_motor"), arm,
              kFloat32Tolerance * arm);

  std::vector<const Diagnostic*> overlaps;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == codes::LINK_PARTS_OVERLAP) overlaps.push_back(&d);
    EXPECT_NE(d.code, codes::MESH_SHELL_INSIDE_OUT) << format(d);
  }
  ASSERT_EQ(overlaps.size(), 2u);
  const Diagnostic& post = *overlaps[0];
  EXPECT_EQ(post.severity, Severity::kWarning);
  EXPECT_EQ(post.pointer, "/nodes/3");
  EXPECT_NE(post.message.find("link 'base': the mesh of node 3 'base' overlaps itself (parts joined into one object"),
            std::string::npos)
      << post.message;
  // The post (32-gon of radius 0.05 along glTF y) inside the cube from y = -0.05 to 0.1, seen along
  // x: a 0.15 by 0.1 rectangle, chords up to 0.1; the base's bounds 0.35 (y) by 0.2 (z).
  const double post_exact = base - united["base"].get<double>();
  EXPECT_NEAR(volume_in(post.message), post_exact, allowed(post_exact, 0.5, 0.1, 0.35, 0.2)) << post.message;

  const Diagnostic& motor = *overlaps[1];
  EXPECT_EQ(motor.pointer, "/nodes/1");
  EXPECT_NE(motor.message.find("links 'arm' and 'arm_motor' (one body: fixed joints join them): the meshes of node 1 "
                               "'arm' and node 0 'arm_motor' overlap"),
            std::string::npos)
      << motor.message;
  // The motor (32-gon of radius 0.04 along x) through the bar 0.1 thick: its outline is the 32-gon's
  // perimeter, every chord 0.1; the arm's bounds 0.4 (y) by 0.1 (z).
  const double motor_exact = arm - united["arm"].get<double>();
  const double perimeter = 2 * 32 * 0.04 * std::sin(3.14159265358979323846 / 32);
  EXPECT_NEAR(volume_in(motor.message), motor_exact, allowed(motor_exact, perimeter, 0.1, 0.4, 0.1)) << motor.message;
}

TEST(BlenderOverlap, PartsUnitedWithABooleanModifierAreExactAndSilent) {
  Diagnostics diag;
  const auto conversion = convert_file(testing::data_dir() / "blender" / "overlap_union.glb", {}, diag);
  ASSERT_TRUE(conversion.has_value());
  EXPECT_FALSE(diag.contains(codes::LINK_PARTS_OVERLAP));
  EXPECT_FALSE(diag.contains(codes::MESH_SHELL_INSIDE_OUT));
  for (const char* link : {"base", "arm"}) {
    const double expected = blender_says()["union"][link].get<double>();
    EXPECT_NEAR(link_volume(conversion->robot, link), expected, kFloat32Tolerance * expected) << link;
  }
}

}  // namespace
}  // namespace rdtf
