// rdtf_mass on a link scales every mesh it owns alike (docs/format.md, "Node extras"). A mesh's
// own rdtf_mass under it is then scaled too: a warning gives the mass it ends with, and the
// meshes' densities are those that give the link's mass. The model is tests/data/khr/arm_extras.gltf
// (base: rdtf_mass 5 kg, its mesh a box of 0.016 m^3) with the base's box moved to a mesh node
// under it ("shell"), and a copy of it 1 m above with rdtf_mass 2 kg ("ballast"): the base is then
// an empty whose meshes are its parts, as Blender users parent parts to an empty.
#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

TEST(LinkMass, ALinksMassScalesAMeshsOwnMassWithAWarningThatSaysWhatItBecomes) {
  Json doc = Json::parse(testing::read_file(testing::data_dir() / "khr" / "arm_extras.gltf"));
  const std::size_t extra = doc["nodes"].size();
  doc["nodes"].push_back({{"name", "ballast"}, {"mesh", 0}, {"translation", {0, 0, 1}}, {"extras", {{"rdtf_mass", 2.0}}}});
  doc["nodes"].push_back({{"name", "shell"}, {"mesh", 0}});
  doc["nodes"][0].erase("mesh");
  doc["nodes"][0]["children"].push_back(extra);
  doc["nodes"][0]["children"].push_back(extra + 1);
  testing::TempDir dir;
  testing::write_file(dir / "arm.gltf", doc.dump());
  Diagnostics diag;
  const auto conversion = convert_file(dir / "arm.gltf", {}, diag);
  ASSERT_TRUE(conversion.has_value());
  const Link& base = conversion->robot.links[0];
  ASSERT_EQ(base.name, "base");
  EXPECT_EQ(base.inertial.mass, 5.0);
  // Before the link's mass: the shell at 1000 kg/m^3 (0.016 m^3 as float positions give it, about
  // 16 kg) and the ballast's 2 kg; both scaled by 5 kg over their sum.
  ASSERT_EQ(base.meshes.size(), 2u);
  const double shell_volume = base.meshes[0].node == static_cast<int>(extra) ? base.meshes[1].volume : base.meshes[0].volume;
  EXPECT_NEAR(shell_volume, 0.016, 1e-9);
  const double factor = 5.0 / (2.0 + 1000.0 * shell_volume);
  double mass = 0;
  for (const LinkMesh& mesh : base.meshes) mass += mesh.density * mesh.volume;
  EXPECT_NEAR(mass, 5.0, 5.0 * 1e-12);
  for (const LinkMesh& mesh : base.meshes) {
    const double expected = mesh.node == static_cast<int>(extra) ? 2.0 * factor : 1000.0 * shell_volume * factor;
    EXPECT_NEAR(mesh.density * mesh.volume, expected, expected * 1e-9) << "mesh of node " << mesh.node;
  }
  int warnings = 0;
  for (const Diagnostic& d : diag.all()) {
    if (d.code != codes::RDTF_MASS_OVERRIDDEN) continue;
    ++warnings;
    EXPECT_EQ(d.severity, Severity::kWarning);
    EXPECT_EQ(d.pointer, "/nodes/" + std::to_string(extra) + "/extras/rdtf_mass");
    EXPECT_EQ(d.message, "node " + std::to_string(extra) +
                             " 'ballast' sets rdtf_mass 2 kg, but link 'base' sets rdtf_mass 5 kg for all its meshes, "
                             "which scales this one to 0.555556 kg; set the mass on the link or on its meshes, not both");
  }
  EXPECT_EQ(warnings, 1);
}

// Without a mesh of its own mass nothing is overridden: no warning.
TEST(LinkMass, ALinksMassAloneIsNoWarning) {
  Diagnostics diag;
  ASSERT_TRUE(convert_file(testing::data_dir() / "khr" / "arm_extras.gltf", {}, diag).has_value());
  EXPECT_FALSE(diag.contains(codes::RDTF_MASS_OVERRIDDEN));
}

}  // namespace
}  // namespace rdtf
