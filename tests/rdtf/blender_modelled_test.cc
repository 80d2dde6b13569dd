// Robots modelled in Blender the way modellers do (tests/data/blender/make_robots.py, exported by
// Blender's own glTF exporter) give the robot that was modelled: the pivots are the empties, the
// axes are as typed in Blender, the masses are the volumes Blender's bmesh computes times the
// densities (modelled.json, written by the same script). Blender's data is float32: pivots, axes
// and volumes agree with it to about 1e-7 relative, so 1e-6 is the bound.
#include <gtest/gtest.h>

#include "rdtf/completion.h"
#include "rdtf/convert.h"
#include "rdtf/urdf.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

constexpr double kFloat32Tolerance = 1e-6;

const Json& modelled(const std::string& model) {
  static const Json all =
      Json::parse(testing::read_file(testing::data_dir() / "blender" / "modelled.json"));
  return all.at(model);
}

Eigen::Vector3d vec(const Json& v) { return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()}; }

Conversion convert_blender(const std::string& file, Diagnostics& diag) {
  auto conversion = convert_file(testing::data_dir() / "blender" / file, ConvertOptions{}, diag);
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError) ADD_FAILURE() << format(d);
  }
  if (!conversion) throw std::runtime_error(file + " did not convert");
  return std::move(*conversion);
}

const Link& link_named(const Robot& robot, const std::string& name) {
  for (const Link& link : robot.links) {
    if (link.name == name) return link;
  }
  throw std::runtime_error("no link " + name);
}

// Links, joints (parent, child), pivots, axes and masses as Blender says they are.
void expect_as_modelled(const Robot& robot, const Json& expected) {
  ASSERT_EQ(robot.links.size(), expected["links"].size());
  for (const auto& [name, link] : expected["links"].items()) {
    const Link& got = link_named(robot, name);
    const double mass = link["mass"].get<double>();
    EXPECT_NEAR(got.inertial.mass, mass, kFloat32Tolerance * mass) << name;
    EXPECT_NEAR(got.inertial.volume, link["volume"].get<double>(),
                kFloat32Tolerance * link["volume"].get<double>())
        << name;
  }
  ASSERT_EQ(robot.joints.size(), expected["joints"].size());
  for (const Json& want : expected["joints"]) {
    const std::string name = want["name"].get<std::string>();
    const Joint* joint = nullptr;
    for (const Joint& j : robot.joints) {
      if (j.name == name) joint = &j;
    }
    ASSERT_NE(joint, nullptr) << "no joint " << name;
    EXPECT_EQ(robot.links[joint->parent_link].name, want["parent"].get<std::string>());
    EXPECT_EQ(robot.links[joint->child_link].name, want["child"].get<std::string>());
    EXPECT_EQ(joint->kind, JointKind::kRevolute) << name;
    // The joint frame in the scene: the parent link frame times X_PJ.
    const Eigen::Isometry3d X_SJ = robot.links[joint->parent_link].X_SL * joint->X_PJ;
    EXPECT_LE((X_SJ.translation() - vec(want["pivot_scene"])).norm(), kFloat32Tolerance)
        << name << " pivot at " << X_SJ.translation().transpose();
    EXPECT_LE((X_SJ.linear() * joint->axis - vec(want["axis_scene"])).norm(), kFloat32Tolerance)
        << name << " axis " << (X_SJ.linear() * joint->axis).transpose();
    // URDF keeps the joint frame and the child link frame one.
    EXPECT_TRUE(X_SJ.isApprox(robot.links[joint->child_link].X_SL, 1e-12)) << name;
  }
}

TEST(BlenderModelled, ArmPivotsAxesAndMassesAreTheModelled) {
  Diagnostics diag;
  const Conversion conversion = convert_blender("modelled_arm.gltf", diag);
  const Robot& robot = conversion.robot;
  std::vector<std::string> names;
  for (const Link& link : robot.links) names.push_back(link.name);
  EXPECT_EQ(names, (std::vector<std::string>{"base", "upper_arm", "forearm"}));
  expect_as_modelled(robot, modelled("modelled_arm"));
  EXPECT_FALSE(diag.contains("NO_RDTF_PROPERTIES"));
  EXPECT_FALSE(diag.contains("UNITS_IMPLAUSIBLE"));
  EXPECT_FALSE(diag.contains("MESH_OPEN"));
}

TEST(BlenderModelled, ArmLimitsEffortAndDamping) {
  Diagnostics diag;
  const Robot robot = convert_blender("modelled_arm.gltf", diag).robot;
  ASSERT_EQ(robot.joints.size(), 2u);
  const Joint& shoulder = robot.joints[0];
  ASSERT_TRUE(shoulder.limits.has_value());
  EXPECT_EQ(shoulder.limits->lower, -1.5);
  EXPECT_EQ(shoulder.limits->upper, 1.5);
  EXPECT_EQ(shoulder.limits->effort, 20.0);
  EXPECT_EQ(shoulder.limits->velocity, 2.0);
  const Joint& elbow = robot.joints[1];
  ASSERT_TRUE(elbow.limits.has_value());
  EXPECT_EQ(elbow.limits->effort, 0.0) << "not authored";
  EXPECT_EQ(elbow.damping, 0.1);
}

TEST(BlenderModelled, GlbGivesTheSameRobot) {
  Diagnostics diag;
  expect_as_modelled(convert_blender("modelled_arm.glb", diag).robot, modelled("modelled_arm"));
}

TEST(BlenderModelled, BonePropertiesMakeTheJointBetweenBoneLinks) {
  Diagnostics diag;
  const Robot robot = convert_blender("modelled_bones.gltf", diag).robot;
  // The armature object is a link too (massless, holding the root bone by a fixed joint).
  Json expected = modelled("modelled_bones");
  std::vector<std::string> names;
  for (const Link& link : robot.links) names.push_back(link.name);
  EXPECT_EQ(names, (std::vector<std::string>{"rig", "lower", "upper", "hand"}));
  Robot bones = robot;
  // Compare the bone links and their joint only.
  bones.links.erase(bones.links.begin());
  std::vector<Joint> joints;
  for (Joint joint : robot.joints) {
    if (robot.links[joint.parent_link].name == "rig") continue;
    joint.parent_link -= 1;
    joint.child_link -= 1;
    joints.push_back(joint);
  }
  bones.joints = joints;
  expect_as_modelled(bones, expected);
  ASSERT_TRUE(bones.joints[0].limits.has_value());
  EXPECT_EQ(bones.joints[0].limits->lower, -1.0);
}

TEST(BlenderModelled, NoCustomPropertiesWarnsWithTheFix) {
  Diagnostics diag;
  convert_blender("modelled_arm_no_extras.glb", diag);
  const Diagnostic* warning = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == "NO_RDTF_PROPERTIES") warning = &d;
  }
  ASSERT_NE(warning, nullptr);
  EXPECT_EQ(warning->severity, Severity::kWarning);
  EXPECT_NE(warning->message.find("'shoulder'"), std::string::npos) << warning->message;
  EXPECT_NE(warning->message.find("'elbow'"), std::string::npos) << warning->message;
  EXPECT_NE(warning->message.find("Include > Custom Properties"), std::string::npos);
  EXPECT_NE(warning->message.find("export_extras=True"), std::string::npos);
  EXPECT_NE(warning->message.find("not on the pose bone"), std::string::npos);
}

TEST(BlenderModelled, MillimetreModelWarnsNamingTheScale) {
  Diagnostics diag;
  convert_blender("modelled_arm_mm.glb", diag);
  const Diagnostic* warning = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == "UNITS_IMPLAUSIBLE") warning = &d;
  }
  ASSERT_NE(warning, nullptr);
  EXPECT_NE(warning->message.find("millimetres"), std::string::npos) << warning->message;
  EXPECT_NE(warning->message.find("0.001"), std::string::npos) << warning->message;
  EXPECT_NE(warning->message.find("'base'"), std::string::npos) << warning->message;
}

// A hand-written document (no meshes): base -> joint node -> child link, with joint extras.
Json one_joint(const Json& joint_extras) {
  return Json{{"asset", {{"version", "2.0"}}},
              {"scene", 0},
              {"scenes", {{{"nodes", {0}}}}},
              {"nodes",
               {{{"name", "base"}, {"children", {1, 3}}},
                {{"name", "elbow joint"}, {"translation", {0, 1, 0}}, {"children", {2}},
                 {"extras", joint_extras}},
                {{"name", "forearm"}, {"extras", {{"rdtf_type", "link"}}}},
                {{"name", "tip"}, {"extras", {{"rdtf_type", "link"}}}}}}};
}

std::vector<Diagnostic> convert_errors(const Json& document) {
  Diagnostics diag("model.gltf");
  GltfAsset asset;
  asset.path = "model.gltf";
  asset.document = document;
  convert(std::move(asset), ConvertOptions{}, diag);
  std::vector<Diagnostic> errors;
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError) errors.push_back(d);
  }
  return errors;
}

TEST(BlenderModelled, JointDiagnosticsNameTheNodeAndShowTheValue) {
  struct Case {
    Json extras;
    std::string code, pointer, message;
  };
  const std::vector<Case> cases = {
      {{{"rdtf_joint", "revolute"}, {"rdtf_axis", {0, 0, 0}}}, "JOINT_AXIS_ZERO",
       "/nodes/1/extras/rdtf_axis", "node 1 'elbow joint': the joint axis [0,0,0] is the zero vector"},
      {{{"rdtf_joint", "revolute"}, {"rdtf_axis", "up"}}, "RDTF_INVALID_VALUE",
       "/nodes/1/extras/rdtf_axis",
       "node 1 'elbow joint': rdtf_axis is 'up', not three finite numbers or one of \"x\", \"y\", "
       "\"z\", \"-x\", \"-y\", \"-z\""},
      {{{"rdtf_joint", "hinge"}}, "RDTF_INVALID_JOINT_TYPE", "/nodes/1/extras/rdtf_joint",
       "node 1 'elbow joint': joint type 'hinge' is not one of fixed, revolute, continuous, "
       "prismatic, floating, planar, ball"},
      {{{"rdtf_joint", "revolute"}, {"rdtf_damping", "0.4"}}, "RDTF_INVALID_VALUE",
       "/nodes/1/extras/rdtf_damping",
       "node 1 'elbow joint': rdtf_damping is '0.4', not a finite number; it is text: in Blender, make the custom "
       "property a number (Edit Property > Type: Float, or Float Array for an axis), not a String"},
      {{{"rdtf_joint", "revolute"}, {"rdtf_axis", "[0, 0, 1]"}}, "RDTF_INVALID_VALUE", "/nodes/1/extras/rdtf_axis",
       "node 1 'elbow joint': rdtf_axis is '[0, 0, 1]', not three finite numbers or one of \"x\", \"y\", \"z\", "
       "\"-x\", \"-y\", \"-z\"; it is text: in Blender, make the custom property a number (Edit Property > Type: "
       "Float, or Float Array for an axis), not a String"},
      {{{"rdtf_joint", "Revolute "}}, "RDTF_INVALID_JOINT_TYPE", "/nodes/1/extras/rdtf_joint",
       "node 1 'elbow joint': joint type 'Revolute ' is not one of fixed, revolute, continuous, prismatic, floating, "
       "planar, ball; did you mean 'revolute'? (types are lower case, without spaces)"},
      {{{"rdtf_joint", "revolute"}, {"rdtf_lower", 1.5}, {"rdtf_upper", -1.25}},
       "JOINT_LIMITS_INVERTED", "/nodes/1/extras",
       "node 1 'elbow joint': lower limit 1.5 is above upper limit -1.25"},
      {{{"rdtf_joint", "revolute"}, {"rdtf_axes", "z-up"}}, "RDTF_INVALID_VALUE",
       "/nodes/1/extras/rdtf_axes", "node 1 'elbow joint': rdtf_axes is 'z-up', not \"blender\" or \"gltf\""},
  };
  for (const Case& c : cases) {
    const auto errors = convert_errors(one_joint(c.extras));
    ASSERT_EQ(errors.size(), 1u) << c.extras.dump();
    EXPECT_EQ(errors[0].code, c.code);
    EXPECT_EQ(errors[0].pointer, c.pointer);
    EXPECT_EQ(errors[0].message, c.message);
    EXPECT_EQ(errors[0].file, "model.gltf");
  }
}

TEST(BlenderModelled, NamedAxesAndTheAxesRule) {
  // Not from Blender: vectors and names are in glTF's axes of the node.
  Json document = one_joint({{"rdtf_joint", "revolute"}, {"rdtf_axis", "-z"}});
  Diagnostics diag;
  GltfAsset asset;
  asset.document = document;
  auto conversion = convert(asset, ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  EXPECT_EQ(conversion->robot.joints[0].axis, Eigen::Vector3d(0, 0, -1));
  // From Blender's exporter: in Blender's axes, glTF (x, y, z) = Blender (x, z, -y).
  asset.document["asset"]["generator"] = "Khronos glTF Blender I/O v3.4.50";
  for (const auto& [axis, expected] : {std::pair{Json("z"), Eigen::Vector3d(0, 1, 0)},
                                       {Json("-y"), Eigen::Vector3d(0, 0, 1)},
                                       {Json({0, 0, 2}), Eigen::Vector3d(0, 1, 0)}}) {
    asset.document["nodes"][1]["extras"]["rdtf_axis"] = axis;
    conversion = convert(asset, ConvertOptions{}, diag);
    ASSERT_TRUE(conversion);
    EXPECT_TRUE(conversion->robot.joints[0].axis.isApprox(expected, 1e-15)) << axis.dump();
  }
  // rdtf_axes on the node overrides the generator.
  asset.document["nodes"][1]["extras"]["rdtf_axes"] = "gltf";
  conversion = convert(asset, ConvertOptions{}, diag);
  EXPECT_EQ(conversion->robot.joints[0].axis, Eigen::Vector3d(0, 0, 1));
}

// Only an axis's direction counts, whatever its length: one whose norm overflows a double
// ([1e300, 1e300, 0] was turned into the zero vector) or underflows it (1e-200) is the direction
// it points in.
TEST(BlenderModelled, AxesOfAnyLengthKeepTheirDirection) {
  const double r = std::sqrt(0.5);
  for (const auto& [axis, expected] :
       {std::pair{Json({1e300, 1e300, 0}), Eigen::Vector3d(r, r, 0)}, {Json({0, -1e-200, 0}), Eigen::Vector3d(0, -1, 0)},
        {Json({1.7e308, 0, -1.7e308}), Eigen::Vector3d(r, 0, -r)}, {Json({0, 0, 4.9e-324}), Eigen::Vector3d(0, 0, 1)}}) {
    SCOPED_TRACE(axis.dump());
    Diagnostics diag;
    GltfAsset asset;
    asset.document = one_joint({{"rdtf_joint", "revolute"}, {"rdtf_axis", axis}});
    const auto conversion = convert(asset, ConvertOptions{}, diag);
    ASSERT_TRUE(conversion);
    EXPECT_LE((conversion->robot.joints[0].axis - expected).norm(), 1e-15);
  }
}

// A TRS scale of 0 (valid glTF) flattens a mesh: its part of the link's mass vanishes, and the
// user hears of it (a scale of [0, 1, 1] on upper_arm's motor cut the link's mass without a word).
TEST(BlenderModelled, AMeshScaledToNothingIsAWarningAndAddsNoMass) {
  testing::TempDir dir;
  Json document = Json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf"));
  ASSERT_EQ(document["nodes"][5]["name"], "upper_arm_motor");
  std::filesystem::copy_file(testing::data_dir() / "blender" / "arm3.bin", dir / "arm3.bin");
  testing::write_file(dir / "arm3.gltf", document.dump());
  Diagnostics whole_diag;
  const auto whole = convert_file(dir / "arm3.gltf", ConvertOptions{}, whole_diag);
  ASSERT_TRUE(whole);
  document["nodes"][5]["scale"] = {0.0, 1.0, 1.0};
  testing::write_file(dir / "arm3.gltf", document.dump());
  Diagnostics diag;
  const auto flat = convert_file(dir / "arm3.gltf", ConvertOptions{}, diag);
  ASSERT_TRUE(flat);
  const Diagnostic* found = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == "MESH_SCALED_TO_NOTHING") found = &d;
  }
  ASSERT_NE(found, nullptr);
  EXPECT_EQ(found->severity, Severity::kWarning);
  EXPECT_EQ(found->pointer, "/nodes/5");
  EXPECT_NE(found->message.find("'upper_arm_motor'"), std::string::npos) << found->message;
  // The link keeps exactly the mass of its other mesh.
  double motor = 0;
  for (const LinkMesh& mesh : link_named(whole->robot, "upper_arm").meshes) {
    if (mesh.node == 5) motor = mesh.volume * mesh.density;
  }
  EXPECT_GT(motor, 0.0);
  const double before = link_named(whole->robot, "upper_arm").inertial.mass;
  EXPECT_NEAR(link_named(flat->robot, "upper_arm").inertial.mass, before - motor, 1e-12 * before);
  for (const Diagnostic& d : whole_diag.all()) EXPECT_NE(d.code, "MESH_SCALED_TO_NOTHING");
}

TEST(BlenderModelled, PivotIsTheJointEmptyNotTheChildOrigin) {
  // The forearm's node sits 0.25 above the elbow empty (Blender puts a cylinder's origin at its
  // centre): the joint and the forearm's link frame are at the empty, 1 above the base.
  Json document = one_joint({{"rdtf_joint", "revolute"}});
  document["nodes"][2]["translation"] = {0, 0.25, 0};
  GltfAsset asset;
  asset.document = document;
  Diagnostics diag;
  const auto conversion = convert(asset, ConvertOptions{}, diag);
  ASSERT_TRUE(conversion);
  const Robot& robot = conversion->robot;
  ASSERT_EQ(robot.joints.size(), 2u);
  EXPECT_EQ(robot.joints[0].name, "elbow joint");
  EXPECT_EQ(robot.joints[0].X_PJ.translation(), Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(link_named(robot, "forearm").X_SL.translation(), Eigen::Vector3d(0, 1, 0));
  // A link under a link (rdtf's inserted joint node, no transform): the child's own origin.
  EXPECT_EQ(robot.joints[1].name, "base_tip_joint");
  EXPECT_EQ(robot.joints[1].frame_node, robot.links[robot.joints[1].child_link].node);
}

// What a tool that keeps node extras only (Blender's importer) leaves of rdtf's output is enough:
// without extras.RDTF the output converts to the same robot, for models whose joints came from
// extras.RDTF (URDF import: authored inertials too) as for Blender's.
TEST(BlenderModelled, NodeExtrasAloneGiveTheSameRobot) {
  Diagnostics diag;
  std::vector<Conversion> firsts;
  firsts.push_back(convert_blender("modelled_arm.gltf", diag));
  UrdfImportOptions import_options;
  auto imported = import_urdf(testing::data_dir() / "urdf" / "urdf_tutorial" / "07-physics.urdf",
                              import_options, diag);
  ASSERT_TRUE(imported) << (diag.all().empty() ? "" : format(diag.all().back()));
  firsts.push_back(std::move(*imported));
  for (const Conversion& first : firsts) {
    SCOPED_TRACE(first.robot.name);
    GltfAsset stripped = first.asset;
    stripped.document["extras"].erase("RDTF");
    Diagnostics again_diag;
    const auto again = convert(std::move(stripped), ConvertOptions{}, again_diag);
    ASSERT_TRUE(again) << (again_diag.all().empty() ? "" : format(again_diag.all().back()));
    const Robot& a = first.robot;
    const Robot& b = again->robot;
    ASSERT_EQ(b.links.size(), a.links.size());
    for (std::size_t l = 0; l < a.links.size(); ++l) {
      EXPECT_EQ(b.links[l].name, a.links[l].name);
      EXPECT_EQ(b.links[l].inertial.mass, a.links[l].inertial.mass) << a.links[l].name;
      EXPECT_EQ(b.links[l].inertial.center_of_mass, a.links[l].inertial.center_of_mass) << a.links[l].name;
      EXPECT_TRUE(b.links[l].inertial.inertia.isApprox(a.links[l].inertial.inertia, 1e-12)) << a.links[l].name;
      EXPECT_TRUE(b.links[l].X_SL.isApprox(a.links[l].X_SL, 1e-15)) << a.links[l].name;
    }
    ASSERT_EQ(b.joints.size(), a.joints.size());
    for (std::size_t j = 0; j < a.joints.size(); ++j) {
      EXPECT_EQ(b.joints[j].name, a.joints[j].name);
      EXPECT_EQ(b.joints[j].kind, a.joints[j].kind) << a.joints[j].name;
      EXPECT_LE((b.joints[j].axis - a.joints[j].axis).norm(), 1e-15) << a.joints[j].name;
      EXPECT_EQ(b.joints[j].limits.has_value(), a.joints[j].limits.has_value()) << a.joints[j].name;
      if (a.joints[j].limits && b.joints[j].limits) {
        EXPECT_EQ(b.joints[j].limits->lower, a.joints[j].limits->lower);
        EXPECT_EQ(b.joints[j].limits->upper, a.joints[j].limits->upper);
        EXPECT_EQ(b.joints[j].limits->effort, a.joints[j].limits->effort);
        EXPECT_EQ(b.joints[j].limits->velocity, a.joints[j].limits->velocity);
      }
      EXPECT_EQ(b.joints[j].damping, a.joints[j].damping);
      EXPECT_EQ(b.joints[j].friction, a.joints[j].friction);
    }
  }
}

// A joint without authored effort and velocity: the URDF's required <limit> attributes get the
// documented values that never bind, not 0 ("cannot move").
TEST(BlenderModelled, UrdfLimitWithoutEffortOrVelocityGetsTheDocumentedDefaults) {
  Diagnostics diag;
  const Conversion conversion = convert_blender("modelled_arm.gltf", diag);
  Diagnostics urdf_diag;
  const auto urdf = export_urdf(conversion, UrdfOptions{}, urdf_diag);
  ASSERT_TRUE(urdf);
  // The shoulder authored both, the elbow neither.
  EXPECT_NE(urdf->text.find("effort=\"20\""), std::string::npos) << urdf->text;
  EXPECT_NE(urdf->text.find("velocity=\"2\""), std::string::npos) << urdf->text;
  EXPECT_NE(urdf->text.find("effort=\"1e+06\""), std::string::npos) << urdf->text;
  EXPECT_NE(urdf->text.find("velocity=\"1000\""), std::string::npos) << urdf->text;
  EXPECT_EQ(urdf->text.find("effort=\"0\""), std::string::npos) << urdf->text;
  ASSERT_EQ(urdf_diag.all().size(), 1u);
  EXPECT_EQ(urdf_diag.all()[0].code, "URDF_LIMIT_DEFAULTED");
  EXPECT_EQ(urdf_diag.all()[0].message,
            "joint 'elbow' has no rdtf_effort or rdtf_velocity: the URDF's <limit> (which requires "
            "both) says effort 1e+06 and velocity 1000, which never bind; set them to the real limits");
}

}  // namespace
}  // namespace rdtf
