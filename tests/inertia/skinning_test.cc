// Skinned meshes: each bone's parts and their mass (docs/format.md, "Mass properties").
#include <cmath>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

std::map<std::string, double> link_masses(const Conversion& conversion) {
  std::map<std::string, double> masses;
  for (const Link& link : conversion.robot.links) masses[link.name] = link.inertial.mass;
  return masses;
}

// Rigid parts that only touch (the same corner coordinates on the shared face, as CAD parts of an
// arm have) stay each with its own bone: welded by position alone they were one part, which went
// whole to `lower` (80 kg) and left the moving `upper` massless (s100xform D2).
TEST(Skinning, TouchingRigidPartsStayWithTheirOwnBones) {
  Diagnostics diag;
  const auto conversion = convert_file(testing::data_dir() / "skin/skin_touch.gltf", {}, diag);
  ASSERT_TRUE(conversion.has_value());
  const double w = static_cast<double>(0.2f);  // the boxes' width as stored (float32)
  const double expected = 1000.0 * w * w * 1.0;
  const auto masses = link_masses(*conversion);
  EXPECT_NEAR(masses.at("lower"), expected, 1e-9 * expected);
  EXPECT_NEAR(masses.at("upper"), expected, 1e-9 * expected);
  for (const Diagnostic& d : diag.all()) {
    EXPECT_NE(d.code, codes::SKIN_PART_SHARED) << d.message;
    EXPECT_NE(d.code, codes::LINK_NO_VOLUME) << d.message;
  }
}

// The skinned mesh node's rdtf_mass is the whole mesh's, shared by its bones as their volumes are
// (it was ignored: 2,196 kg at the default density, without a word; s100xform D3).
TEST(Skinning, TheMeshNodesMassIsSharedByItsBones) {
  Diagnostics diag;
  const auto conversion = convert_file(testing::data_dir() / "skin/skin_rdtfmass.gltf", {}, diag);
  ASSERT_TRUE(conversion.has_value());
  double total = 0, volume = 0;
  for (const Link& link : conversion->robot.links) {
    total += link.inertial.mass;
    volume += link.inertial.volume;
  }
  EXPECT_NEAR(total, 10.0, 1e-12 * 10.0);
  for (const Link& link : conversion->robot.links) {
    const double share = 10.0 * link.inertial.volume / volume;
    EXPECT_NEAR(link.inertial.mass, share, 1e-12 * 10.0) << link.name;
  }
  // The two parts are equal up to their float32 coordinates: about 5 kg each.
  const auto masses = link_masses(*conversion);
  EXPECT_NEAR(masses.at("b0"), 5.0, 1e-6 * 5.0);
  EXPECT_NEAR(masses.at("b1"), 5.0, 1e-6 * 5.0);
}

// A part weighted 0.75 / 0.25 to two bones, the skeleton posed away from its bind pose, weighs as
// it is drawn (glTF 2.0 3.7.3.3: each vertex at sum w_j S_j v): rigid under its heaviest bone it
// was 53% heavier (1,098 kg; s100xform D1). The expected masses are the sweep's numpy integrals of
// the drawn hexahedra (d_skin_blend.py), not rdtf's.
TEST(Skinning, APartSharedByBonesWeighsAsDrawn) {
  Diagnostics diag;
  const auto conversion = convert_file(testing::data_dir() / "skin/skin_blend.gltf", {}, diag);
  ASSERT_TRUE(conversion.has_value());
  const auto masses = link_masses(*conversion);
  EXPECT_NEAR(masses.at("b0"), 1098.1666741656757, 1e-9 * 1098.1666741656757);
  EXPECT_NEAR(masses.at("b1"), 718.0320434258927, 1e-9 * 718.0320434258927);
  bool said = false;
  for (const Diagnostic& d : diag.all()) {
    if (d.code != codes::SKIN_PART_SHARED) continue;
    said = true;
    EXPECT_NE(d.message.find("weighs as drawn"), std::string::npos) << d.message;
    EXPECT_NE(d.message.find("'b1', which carries 75% of its weight"), std::string::npos) << d.message;
  }
  EXPECT_TRUE(said);
}

}  // namespace
}  // namespace rdtf
