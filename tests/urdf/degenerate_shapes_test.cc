// URDF import of shapes without volume (a cylinder of length 0 on a mount link, spheres of radius
// 0 on feet, a box with a side of 0): each is skipped with a warning that names the link, the
// element and its line, and the robot is imported whole (MuJoCo refuses such files; Drake and
// Gazebo load them). Negative sizes stay errors.
#include <gtest/gtest.h>

#include "rdtf/dynamics.h"
#include "rdtf/urdf.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

const char* const kRobot = R"(<robot name="degenerate">
<link name="base"><inertial><mass value="2"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
<visual><geometry><box size="0.2 0.2 0.2"/></geometry></visual></link>
<link name="mount"><visual><geometry><cylinder radius="0.05" length="0"/></geometry></visual></link>
<link name="foot"><inertial><mass value="0.5"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
<collision><geometry><sphere radius="0"/></geometry></collision></link>
<link name="plate"><inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
<visual><geometry><box size="0.1 0 0.1"/></geometry></visual></link>
<joint name="mount_joint" type="fixed"><parent link="base"/><child link="mount"/><origin xyz="0 0 0.1"/></joint>
<joint name="knee" type="revolute"><parent link="mount"/><child link="foot"/><origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>
<limit lower="-1" upper="1" effort="10" velocity="2"/></joint>
<joint name="plate_joint" type="fixed"><parent link="foot"/><child link="plate"/><origin xyz="0 0 0.05"/></joint>
<link name="toe"><inertial><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial>
<visual><geometry><sphere radius="0.0"/></geometry></visual>
<collision><geometry><sphere radius="0.02"/></geometry></collision></link>
<joint name="toe_joint" type="fixed"><parent link="foot"/><child link="toe"/><origin xyz="0 0 -0.05"/></joint>
</robot>
)";

TEST(UrdfDegenerateShapes, AreSkippedWithAWarningAndTheRobotIsKept) {
  const testing::TempDir dir;
  testing::write_file(dir / "robot.urdf", kRobot);
  Diagnostics diag;
  const auto conversion = import_urdf(dir / "robot.urdf", UrdfImportOptions{}, diag);
  std::string all;
  for (const Diagnostic& d : diag.all()) all += format(d) + "\n";
  ASSERT_TRUE(conversion) << all;
  EXPECT_FALSE(diag.has_errors()) << all;
  ASSERT_EQ(conversion->robot.links.size(), 5u);
  ASSERT_EQ(conversion->robot.joints.size(), 4u);
  struct Expected {
    const char* pointer;
    const char* says;
  };
  const Expected expected[] = {
      {"/robot/link[@name='mount']/visual[1]", "line 4: <cylinder> has length 0: it has no volume"},
      {"/robot/link[@name='foot']/collision[1]", "line 6: <sphere> has radius 0: it has no volume"},
      {"/robot/link[@name='plate']/visual[1]", "line 8: <box> has size \"0.1 0 0.1\", a side of 0: it has no volume"},
      // pybullet's laikago: a toe drawn as a sphere of radius 0 whose collision sphere is drawn
      // instead (it was only an info, saying import reads spheres).
      {"/robot/link[@name='toe']/visual[1]", "line 14: <sphere> has radius 0: it has no volume"},
  };
  std::vector<Diagnostic> degenerate;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == "URDF_SHAPE_DEGENERATE") degenerate.push_back(d);
  }
  ASSERT_EQ(degenerate.size(), 4u) << all;
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(degenerate[i].severity, Severity::kWarning);
    EXPECT_EQ(degenerate[i].pointer, expected[i].pointer);
    EXPECT_EQ(degenerate[i].message.rfind(expected[i].says, 0), 0u) << degenerate[i].message;
    EXPECT_NE(degenerate[i].message.find("skipped, the link is kept"), std::string::npos) << degenerate[i].message;
  }
  // The imported robot is whole and passes the gate (URDF is Z up: gravity along -Z once imported
  // as glTF's Y up, the default).
  const ValidationReport report = validate_dynamics(*conversion, ValidationOptions{});
  std::string report_text;
  for (const Diagnostic& d : report.diagnostics.all()) report_text += format(d) + "\n";
  EXPECT_TRUE(report.passed) << report_text;
}

}  // namespace
}  // namespace rdtf
