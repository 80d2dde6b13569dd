// rdtf's output opened in Blender and exported again (Blender's importer keeps node extras only,
// not the document's extras.RDTF) is the same robot: links, joints, frames, axes and masses.
// Blender is a requirement of the tests (scripts/install-deps.sh): without it this test fails.
// One Blender process does every file (it starts in a second or two).
//
// Not here, because Blender's importer changes them (docs/blender.md): armatures (it rebuilds
// every bone's orientation from its "Bone Dir" heuristic, so bone frames and the bind pose move)
// and nodes with negative or sheared scale (the `transforms` fixture: it decomposes them again,
// turning the mirrored wheel's frame by 1.4 degrees).
#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/write.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

// Blender keeps positions and transforms as float32: a vertex or a translation comes back within
// one float32 rounding (relative 6e-8) of what it was, and a volume within a few of them.
constexpr double kFloat32Tolerance = 1e-6;

// Links and joints are matched by name: Blender's exporter may write a node's children in
// another order (the rover's imu and wheel_axle, both on the body mesh, come back swapped).
template <typename Item>
const Item* named(const std::vector<Item>& items, const std::string& name) {
  for (const Item& item : items) {
    if (item.name == name) return &item;
  }
  return nullptr;
}

void expect_same_robot(const Robot& before, const Robot& after, const std::string& model) {
  SCOPED_TRACE(model);
  ASSERT_EQ(after.links.size(), before.links.size());
  for (std::size_t l = 0; l < before.links.size(); ++l) {
    const Link& a = before.links[l];
    const Link* found = named(after.links, a.name);
    ASSERT_NE(found, nullptr) << "no link " << a.name;
    const Link& b = *found;
    EXPECT_NEAR(b.inertial.mass, a.inertial.mass, kFloat32Tolerance * std::max(1.0, a.inertial.mass)) << a.name;
    EXPECT_LE((b.X_SL.translation() - a.X_SL.translation()).norm(), kFloat32Tolerance) << a.name;
    EXPECT_LE((b.X_SL.linear() - a.X_SL.linear()).norm(), kFloat32Tolerance) << a.name;
    EXPECT_LE((b.X_SL * b.inertial.center_of_mass - a.X_SL * a.inertial.center_of_mass).norm(),
              kFloat32Tolerance)
        << a.name;
  }
  ASSERT_EQ(after.joints.size(), before.joints.size());
  for (std::size_t j = 0; j < before.joints.size(); ++j) {
    const Joint& a = before.joints[j];
    const Joint* found = named(after.joints, a.name);
    ASSERT_NE(found, nullptr) << "no joint " << a.name;
    const Joint& b = *found;
    EXPECT_EQ(b.kind, a.kind) << a.name;
    EXPECT_EQ(after.links[b.parent_link].name, before.links[a.parent_link].name) << a.name;
    EXPECT_EQ(after.links[b.child_link].name, before.links[a.child_link].name) << a.name;
    EXPECT_LE((b.X_PJ.translation() - a.X_PJ.translation()).norm(), kFloat32Tolerance) << a.name;
    EXPECT_LE((b.axis - a.axis).norm(), kFloat32Tolerance) << a.name;
    EXPECT_EQ(b.limits.has_value(), a.limits.has_value()) << a.name;
    if (a.limits && b.limits) {
      EXPECT_EQ(b.limits->lower, a.limits->lower) << a.name;
      EXPECT_EQ(b.limits->upper, a.limits->upper) << a.name;
      EXPECT_EQ(b.limits->effort, a.limits->effort) << a.name;
    }
    EXPECT_EQ(b.damping, a.damping) << a.name;
  }
}

TEST(BlenderRoundTrip, ImportAndExportInBlenderKeepsTheRobot) {
  const testing::TempDir dir;
  const std::vector<std::string> models = {"modelled_arm.gltf", "arm3.gltf", "two_cylinder.gltf", "modelled_groups.glb"};
  std::vector<Robot> before;
  std::string args;
  for (const std::string& model : models) {
    Diagnostics diag;
    const auto conversion = convert_file(testing::data_dir() / "blender" / model, ConvertOptions{}, diag);
    ASSERT_TRUE(conversion) << model;
    const std::string stem = model.substr(0, model.find('.'));
    WriteOptions options;
    options.format = OutputFormat::kGlb;
    ASSERT_TRUE(write_rdtf(conversion->asset, dir / (stem + ".rdtf.glb"), options, diag)) << model;
    // The node extras rdtf adds keep the file valid glTF.
    const auto report = testing::khronos_report(dir / (stem + ".rdtf.glb"));
    EXPECT_EQ(report["issues"]["numErrors"].get<int>(), 0) << model << ": " << report.dump();
    before.push_back(conversion->robot);
    args += " '" + (dir / (stem + ".rdtf.glb")).string() + "' '" + (dir / (stem + ".glb")).string() + "'";
  }
  const auto script = testing::data_dir() / "blender" / "roundtrip.py";
  const auto result = testing::run_command("blender -b --factory-startup --python '" + script.string() +
                                           "' --python-exit-code 1 --" + args);
  ASSERT_EQ(result.exit_code, 0) << "Blender (Debian package blender) must run for this test:\n"
                                 << result.out << result.err;
  for (std::size_t m = 0; m < models.size(); ++m) {
    const std::string stem = models[m].substr(0, models[m].find('.'));
    Diagnostics diag;
    const auto again = convert_file(dir / (stem + ".glb"), ConvertOptions{}, diag);
    ASSERT_TRUE(again) << models[m];
    for (const Diagnostic& d : diag.all()) {
      EXPECT_NE(d.severity, Severity::kError) << format(d);
    }
    // Blender wrote the file again.
    EXPECT_EQ(again->asset.document["asset"]["generator"], "Khronos glTF Blender I/O v3.4.50");
    expect_same_robot(before[m], again->robot, models[m]);
  }
}

}  // namespace
}  // namespace rdtf
