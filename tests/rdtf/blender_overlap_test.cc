// Overlapping parts as a modeller makes them in Blender (tests/data/blender/make_overlap.py): a post
// joined into the base with Ctrl+J, a motor parented to the arm (a link of its own on a fixed
// joint) sunk into it, and a skinned part joined from two boxes that cross. The mass is the sum of the meshes' integrals, as Blender's own
// bmesh.calc_volume gives it, and the region counted twice is named with its size, checked against
// Blender's Boolean union (the Exact solver) of the same parts.
#include <cmath>
#include <regex>
#include <string>
#include <vector>

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

// How far the sample may be from the exact region (winding_sample.h), seen along one direction:
// each grid cell the region's outline (perimeter `outline` in that view) passes through may be
// misjudged, by at most the region's longest chord along the rays; cells of hb by hc, about 4,096
// of them, as near square as the body's bounds across the rays (`extent_b` by `extent_c`) allow;
// `edges`: the outline's corners, each a cell more. The sample takes one of the three directions,
// so the bound is the largest of theirs; then the message's two significant digits.
struct View {
  double outline, chord, extent_b, extent_c, edges;
};
double grid_error(const View& v) {
  const double nb = std::round(std::sqrt(4096 * v.extent_b / v.extent_c));
  const double nc = std::round(4096 / nb);
  const double hb = v.extent_b / nb, hc = v.extent_c / nc;
  return (v.outline / hb + v.outline / hc + v.edges) * hb * hc * v.chord;
}
double allowed(double exact, const std::vector<View>& views) {
  double grid = 0;
  for (const View& v : views) grid = std::max(grid, grid_error(v));
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
  // The post (32-gon of radius 0.05 along glTF y) inside the cube from y = -0.05 to 0.1; the
  // base's bounds 0.2 (x) by 0.35 (y) by 0.2 (z). Along x: a 0.15 by 0.1 rectangle (y, z), chords
  // up to 0.1; along y: the 32-gon (z, x), chords 0.15; along z: a 0.1 by 0.15 rectangle (x, y).
  const double post_exact = base - united["base"].get<double>();
  const double post_gon = 2 * 32 * 0.05 * std::sin(3.14159265358979323846 / 32);
  EXPECT_NEAR(volume_in(post.message), post_exact,
              allowed(post_exact, {{0.5, 0.1, 0.35, 0.2, 4}, {post_gon, 0.15, 0.2, 0.2, 64}, {0.5, 0.1, 0.2, 0.35, 4}}))
      << post.message;

  const Diagnostic& motor = *overlaps[1];
  EXPECT_EQ(motor.pointer, "/nodes/1");
  EXPECT_NE(motor.message.find("links 'arm' and 'arm_motor' (one body: fixed joints join them): the meshes of node 1 "
                               "'arm' and node 0 'arm_motor' overlap"),
            std::string::npos)
      << motor.message;
  // The motor (32-gon of radius 0.04 along x) through the bar 0.1 thick; the body's bounds 0.12 (x,
  // the motor's length) by 0.4 (y) by 0.1 (z). Along x: the 32-gon (y, z), every chord 0.1; along y:
  // a 0.08 by 0.1 rectangle (z, x), chords 0.08; along z: a 0.1 by 0.08 rectangle (x, y), chords 0.08.
  const double motor_exact = arm - united["arm"].get<double>();
  const double motor_gon = 2 * 32 * 0.04 * std::sin(3.14159265358979323846 / 32);
  EXPECT_NEAR(volume_in(motor.message), motor_exact,
              allowed(motor_exact, {{motor_gon, 0.1, 0.4, 0.1, 64}, {0.36, 0.08, 0.1, 0.12, 4}, {0.36, 0.08, 0.12, 0.4, 4}}))
      << motor.message;
}

// A skinned mesh: the lower bone's part is two boxes joined where they cross (the post 0.2 x 0.2 x
// 0.3, the bar 0.3 x 0.1 x 0.1 through it), the whole mesh bound by weights. The bone is a link,
// and its part overlaps itself as any link's can.
TEST(BlenderOverlap, ASkinnedPartOverlappingItselfIsNamed) {
  Diagnostics diag;
  const auto conversion = convert_file(testing::data_dir() / "blender" / "overlap_skinned.glb", {}, diag);
  ASSERT_TRUE(conversion.has_value());
  const double joined = blender_says()["skinned_joined"]["lower"].get<double>();
  EXPECT_NEAR(link_volume(conversion->robot, "lower"), joined, kFloat32Tolerance * joined);
  std::vector<const Diagnostic*> overlaps;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == codes::LINK_PARTS_OVERLAP) overlaps.push_back(&d);
  }
  ASSERT_EQ(overlaps.size(), 1u);
  EXPECT_NE(overlaps[0]->message.find("link 'lower': the mesh of node 2 'body' overlaps itself"), std::string::npos)
      << overlaps[0]->message;
  // The common box 0.2 (x) by 0.1 (y) by 0.1 (z), in the lower bone's frame (glTF's axes: the bone
  // points up, unrolled); the part's bounds 0.3 by 0.3 by 0.2.
  const double exact = joined - blender_says()["skinned_union"]["lower"].get<double>();
  EXPECT_NEAR(volume_in(overlaps[0]->message), exact,
              allowed(exact, {{0.4, 0.2, 0.3, 0.2, 4}, {0.6, 0.1, 0.2, 0.3, 4}, {0.6, 0.1, 0.3, 0.3, 4}}))
      << overlaps[0]->message;
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
