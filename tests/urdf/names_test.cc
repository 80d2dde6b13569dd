// urdf_names (rdtf/urdf_names.h): the URDF names of links and joints, which rdtfd's states and
// inertia tables carry too. Written out by hand here from docs/urdf.md's rule (other characters
// become '_', empty names the kind's name, a name valid as it is kept, a taken one "_2", "_3", ...),
// and checked to be the names urdfdom reads in the exported URDF.
#include "rdtf/urdf_names.h"

#include <algorithm>

#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using namespace urdf_test;

Robot named(const std::vector<std::string>& links, const std::vector<std::string>& joints) {
  Robot robot;
  for (std::size_t i = 0; i < links.size(); ++i) {
    Link link;
    link.name = links[i];
    link.node = static_cast<int>(i);
    robot.links.push_back(link);
  }
  for (std::size_t j = 0; j < joints.size(); ++j) {
    Joint joint;
    joint.name = joints[j];
    joint.node = static_cast<int>(100 + j);
    robot.joints.push_back(joint);
  }
  return robot;
}

TEST(UrdfNames, ValidNamesAreKept) {
  const Robot robot = named({"base_link", "arm-1.2", "X9"}, {"shoulder_joint"});
  Diagnostics diag;
  const UrdfNames names = urdf_names(robot, &diag);
  EXPECT_EQ(names.links, (std::vector<std::string>{"base_link", "arm-1.2", "X9"}));
  EXPECT_EQ(names.joints, (std::vector<std::string>{"shoulder_joint"}));
  EXPECT_TRUE(diag.all().empty());
}

TEST(UrdfNames, SpacesAndOtherCharactersBecomeUnderscores) {
  // A character is one '_' however many bytes UTF-8 gives it: "ä" two, "手" three, "🦾" four.
  const Robot robot = named({"upper arm", "base/link", "Gelenk\xc3\xa4", "a:b<c>", "\xe6\x89\x8b\xe9\xa6\x96",
                             "arm\xf0\x9f\xa6\xbe"},
                            {"elbow joint"});
  const UrdfNames names = urdf_names(robot);
  EXPECT_EQ(names.links,
            (std::vector<std::string>{"upper_arm", "base_link", "Gelenk_", "a_b_c_", "__", "arm_"}));
  EXPECT_EQ(names.joints, (std::vector<std::string>{"elbow_joint"}));
}

// Many links of one name, among them names that are its suffixed forms already: each renamed one
// takes the next suffix nobody has, counting on from the last one given (not from 2 again, which
// cost n^2 / 2 tries: 40,000 links of one name did not export in 90 s).
TEST(UrdfNames, ManyEqualNamesTakeConsecutiveFreeSuffixes) {
  std::vector<std::string> links(3000, "a");
  links[1000] = "a_5";
  links[2000] = "a_2500";
  const UrdfNames names = urdf_names(named(links, {}));
  ASSERT_EQ(names.links.size(), links.size());
  EXPECT_EQ(names.links[0], "a");
  EXPECT_EQ(names.links[1000], "a_5");
  EXPECT_EQ(names.links[2000], "a_2500");
  int suffix = 1;
  for (std::size_t i = 1; i < links.size(); ++i) {
    if (i == 1000 || i == 2000) continue;
    ++suffix;
    if (suffix == 5 || suffix == 2500) ++suffix;
    EXPECT_EQ(names.links[i], "a_" + std::to_string(suffix)) << i;
  }
}

TEST(UrdfNames, ValidNamesKeepThemselvesAndTheOthersTakeTheFirstFreeSuffix) {
  // "arm link" and "arm_link" are one URDF name: "arm_link", valid as it is, keeps it though it
  // comes second (a controller or an SRDF that names "arm_link" means it), as do "arm_link_2" and
  // "arm.link"; the renamed ones take the first suffix nobody has. Of two equal valid names the
  // first keeps it.
  const Robot robot = named({"arm link", "arm_link", "arm_link_2", "arm.link", "arm link"},
                            {"j", "j", "j "});
  Diagnostics diag;
  const UrdfNames names = urdf_names(robot, &diag);
  EXPECT_EQ(names.links,
            (std::vector<std::string>{"arm_link_3", "arm_link", "arm_link_2", "arm.link", "arm_link_4"}));
  EXPECT_EQ(names.joints, (std::vector<std::string>{"j", "j_2", "j_"}));
  // One warning per changed name, pointing at its node and naming both names.
  std::vector<std::string> pointers;
  for (const Diagnostic& d : diag.all()) {
    EXPECT_EQ(d.code, "URDF_NAME_CHANGED");
    EXPECT_EQ(d.severity, Severity::kWarning);
    pointers.push_back(d.pointer);
  }
  EXPECT_EQ(pointers, (std::vector<std::string>{"/nodes/0", "/nodes/4", "/nodes/101", "/nodes/102"}));
  EXPECT_NE(diag.all()[0].message.find("link 'arm link' is named 'arm_link_3'"), std::string::npos)
      << diag.all()[0].message;
  EXPECT_NE(diag.all()[3].message.find("joint 'j ' is named 'j_'"), std::string::npos) << diag.all()[3].message;
}

TEST(UrdfNames, EmptyNamesGetTheKindsNameAndLinksAndJointsAreSeparate) {
  // A link and a joint may share a name (URDF keeps them apart); an empty name takes "link" or
  // "joint", after any link authored with that name.
  const Robot robot = named({"link", "", "", "shared"}, {"", "shared", "joint"});
  const UrdfNames names = urdf_names(robot);
  EXPECT_EQ(names.links, (std::vector<std::string>{"link", "link_2", "link_3", "shared"}));
  // The joint authored as "joint" keeps it, though an empty name comes first.
  EXPECT_EQ(names.joints, (std::vector<std::string>{"joint_2", "shared", "joint"}));
}

TEST(UrdfNames, AreTheNamesTheExportedUrdfHas) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(0.1f, 0.1f, 0.1f));
  const int base = b.node("base link", -1, Json{{"mesh", mesh}});
  const Json hinge{{"rdtf_joint", "revolute"}, {"rdtf_lower", -1.0}, {"rdtf_upper", 1.0}};
  const int elbow = b.node("elbow joint", base, Json{{"extras", hinge}, {"translation", {0.0, 0.2, 0.0}}});
  b.link_with_mesh("arm link", elbow, mesh);
  const int elbow2 = b.node("elbow_joint", base, Json{{"extras", hinge}, {"translation", {0.0, 0.4, 0.0}}});
  b.link_with_mesh("arm_link", elbow2, mesh);
  Diagnostics diag;
  const Conversion conversion = b.convert(diag);
  const UrdfNames names = urdf_names(conversion.robot);
  Diagnostics export_diag;
  const auto exported = export_urdf(conversion, UrdfOptions{}, export_diag);
  ASSERT_TRUE(exported) << format(export_diag.all().front());
  EXPECT_EQ(exported->link_names, names.links);
  EXPECT_EQ(exported->joint_names, names.joints);
  ASSERT_EQ(conversion.robot.joints.size(), 2u);
  EXPECT_EQ(conversion.robot.joints[0].name, "elbow joint");
  // "elbow_joint" keeps its name; "elbow joint", first in the robot, takes the suffix.
  EXPECT_EQ(names.joints, (std::vector<std::string>{"elbow_joint_2", "elbow_joint"}));
  // urdfdom reads exactly these names back, with each joint between the links it joins.
  const auto model = parse_with_urdfdom(exported->text);
  ASSERT_TRUE(model);
  EXPECT_EQ(model->links_.size(), names.links.size());
  for (const std::string& link : names.links) EXPECT_TRUE(model->getLink(link)) << link;
  for (std::size_t j = 0; j < names.joints.size(); ++j) {
    const auto joint = model->getJoint(names.joints[j]);
    ASSERT_TRUE(joint) << names.joints[j];
    EXPECT_EQ(joint->parent_link_name, names.links[conversion.robot.joints[j].parent_link]);
    EXPECT_EQ(joint->child_link_name, names.links[conversion.robot.joints[j].child_link]);
  }
}

}  // namespace
}  // namespace rdtf
