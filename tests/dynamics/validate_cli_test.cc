// `rdtf validate IN [--json]` as users and scripts run it: exit 0 on a good model, 2 with the
// diagnostic on a broken one, and a JSON report with the documented fields. The broken models are
// small glTF files written by the test: two boxes, the second on a joint described by node extras
// (docs/format.md).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "support/test_support.h"

namespace rdtf {
namespace {

using nlohmann::json;

std::string quoted(const std::filesystem::path& path) { return "'" + path.string() + "'"; }

testing::CommandResult validate(const std::string& arguments) {
  return testing::run_command("'" + testing::cli_path() + "' validate " + arguments);
}

std::string base64(const std::string& bytes) {
  static const char* const kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 2]);
    out += kTable[v >> 18 & 63];
    out += kTable[v >> 12 & 63];
    out += i + 1 < bytes.size() ? kTable[v >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? kTable[v & 63] : '=';
  }
  return out;
}

// A 0.1 m cube mesh (12 triangles wound outwards), embedded: mesh 0; mesh 1 is the same cube
// without its last face (open).
json cube_parts() {
  std::string bin;
  const auto put = [&](const auto value) { bin.append(reinterpret_cast<const char*>(&value), sizeof(value)); };
  for (int c = 0; c < 8; ++c) {
    put(c & 1 ? 0.05f : -0.05f);
    put(c & 2 ? 0.05f : -0.05f);
    put(c & 4 ? 0.05f : -0.05f);
  }
  const int quads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (const auto& q : quads) {
    for (int v : {q[0], q[1], q[2], q[0], q[2], q[3]}) put(static_cast<std::uint16_t>(v));
  }
  const auto mesh = [](int indices) {
    const json primitive = {{"attributes", {{"POSITION", 0}}}, {"indices", indices}};
    return json{{"primitives", json::array({primitive})}};
  };
  return {{"meshes", json::array({mesh(1), mesh(2)})},
          {"accessors",
           {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"},
             {"min", {-0.05, -0.05, -0.05}}, {"max", {0.05, 0.05, 0.05}}},
            {{"bufferView", 1}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}},
            {{"bufferView", 1}, {"componentType", 5123}, {"count", 30}, {"type", "SCALAR"}}}},
          {"bufferViews",
           {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}, {"target", 34962}},
            {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 72}, {"target", 34963}}}},
          {"buffers", {{{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}}}};
}

// Nodes: 0 "base" (cube, extras `base_extras`), its child 1 "arm" (cube, 0.3 m along +X, extras
// `arm_extras`: the joint between them, as Blender exports custom properties).
std::filesystem::path write_two_boxes(const testing::TempDir& folder, const json& base_extras, const json& arm_extras,
                                      int arm_mesh = 0) {
  json document = cube_parts();
  document["asset"] = {{"version", "2.0"}};
  document["scene"] = 0;
  document["scenes"] = {{{"nodes", {0}}}};
  json base = {{"name", "base"}, {"mesh", 0}, {"children", {1}}};
  if (!base_extras.empty()) base["extras"] = base_extras;
  json arm = {{"name", "arm"}, {"mesh", arm_mesh}, {"translation", {0.3, 0.0, 0.0}}};
  if (!arm_extras.empty()) arm["extras"] = arm_extras;
  document["nodes"] = {base, arm};
  const auto path = folder / "two_boxes.gltf";
  testing::write_file(path, document.dump(1));
  return path;
}

const json kHinge = {{"rdtf_joint", "revolute"}, {"rdtf_axis", {0.0, 0.0, 1.0}}};

TEST(ValidateCli, GoodFixturePassesWithExitZero) {
  const auto run = validate(quoted(testing::data_dir() / "blender" / "arm3.gltf"));
  EXPECT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("arm3.gltf: PASS: 3 s simulated in 3000 steps"), std::string::npos) << run.out;
}

TEST(ValidateCli, GeneratedGoodModelPasses) {
  testing::TempDir folder;
  const auto run = validate(quoted(write_two_boxes(folder, {}, kHinge)));
  EXPECT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find(": PASS:"), std::string::npos) << run.out;
}

// base at rdtf_mass 1e7 kg, arm 1 kg (0.1 m cube at 1000 kg/m^3), floating, stepped by QuickStep:
// the joint is named with both bodies. Held by the world (the default) the base is no body, and no
// ratio is judged; nor with the automatic stepper, whose dWorldStep holds the joint (2 bodies).
TEST(ValidateCli, MassRatioFailsWithExitTwoAndTheDiagnostic) {
  testing::TempDir folder;
  const auto path = write_two_boxes(folder, {{"rdtf_mass", 1e7}}, kHinge);
  const auto run = validate("--stepper quick_step --floating " + quoted(path));
  EXPECT_EQ(run.exit_code, 2) << run.out << run.err;
  EXPECT_NE(run.err.find("error JOINT_MASS_RATIO: joint 'base_arm_joint' (revolute): joins link 'base' (1e+07 kg) "
                         "and link 'arm' (1 kg): mass ratio 1e+07"),
            std::string::npos)
      << run.err;
  EXPECT_NE(run.out.find(": FAIL:"), std::string::npos) << run.out;
  // The bound is an option.
  EXPECT_EQ(validate("--stepper quick_step --floating " + quoted(path) + " --max-mass-ratio 1e8").exit_code, 0);
  EXPECT_EQ(validate(quoted(path)).exit_code, 0);
  const auto exact = validate("--floating " + quoted(path));
  EXPECT_EQ(exact.exit_code, 0) << exact.out << exact.err;
  EXPECT_EQ(exact.err.find("JOINT_MASS_RATIO"), std::string::npos) << exact.err;
}

// A massless arm on a hinge fails naming the options that simulate it; with them it passes, and
// --massless-links error keeps it an error. A tiny CPU budget gives its own verdict.
TEST(ValidateCli, BoundMassMasslessLinksAndCpuBudgetOptions) {
  testing::TempDir folder;
  // The arm without its mesh: a link (rdtf_type) with nothing to weigh.
  const auto path = write_two_boxes(folder, {}, {{"rdtf_joint", "revolute"}, {"rdtf_axis", {0.0, 0.0, 1.0}}, {"rdtf_type", "link"}});
  json document = json::parse(testing::read_file(path));
  document["nodes"][1].erase("mesh");
  testing::write_file(path, document.dump(1));
  const auto refused = validate(quoted(path));
  EXPECT_EQ(refused.exit_code, 2) << refused.out << refused.err;
  EXPECT_NE(refused.err.find("error LINK_MASS_ZERO: link 'arm'"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("--bound-mass KG --bound-inertia KGM2"), std::string::npos) << refused.err;
  const std::string bound = " --bound-mass 0.01 --bound-inertia 1e-5";
  const auto passed = validate(quoted(path) + bound);
  EXPECT_EQ(passed.exit_code, 0) << passed.out << passed.err;
  EXPECT_NE(passed.err.find("warning LINK_MASS_ZERO: link 'arm'"), std::string::npos) << passed.err;
  EXPECT_EQ(validate(quoted(path) + bound + " --massless-links error").exit_code, 2);
  const auto budget = validate(quoted(path) + bound + " --cpu-budget 1e-9");
  EXPECT_EQ(budget.exit_code, 2) << budget.out << budget.err;
  EXPECT_NE(budget.err.find("error SIM_BUDGET_EXCEEDED"), std::string::npos) << budget.err;
}

// Inverted limits and a zero axis are refused while the joint is read: the extras are named.
TEST(ValidateCli, JointErrorsInNodeExtrasFailWithExitTwo) {
  testing::TempDir folder;
  json inverted = kHinge;
  inverted["rdtf_lower"] = 1.0;
  inverted["rdtf_upper"] = -1.0;
  auto run = validate(quoted(write_two_boxes(folder, {}, inverted)));
  EXPECT_EQ(run.exit_code, 2) << run.out << run.err;
  EXPECT_NE(run.err.find("two_boxes.gltf:/nodes/1/extras: error JOINT_LIMITS_INVERTED"), std::string::npos) << run.err;
  json zero_axis = kHinge;
  zero_axis["rdtf_axis"] = {0.0, 0.0, 0.0};
  run = validate(quoted(write_two_boxes(folder, {}, zero_axis)));
  EXPECT_EQ(run.exit_code, 2) << run.out << run.err;
  EXPECT_NE(run.err.find("two_boxes.gltf:/nodes/1/extras/rdtf_axis: error JOINT_AXIS_ZERO"), std::string::npos)
      << run.err;
}

// An open mesh is named with its node (a warning: its volume, and so its mass, is unreliable; the
// converter still counts it, so the model still simulates). The link node 'arm' carries the mesh
// itself: the warning names that node of the input, not the node the output moves the mesh to.
TEST(ValidateCli, OpenMeshIsNamed) {
  testing::TempDir folder;
  const auto run = validate(quoted(write_two_boxes(folder, {}, kHinge, 1)));
  EXPECT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.err.find("two_boxes.gltf:/nodes/1: warning MESH_OPEN: mesh of 'arm' is not closed (4 boundary edges"),
            std::string::npos)
      << run.err;
}

void expect_report_fields(const json& report) {
  for (const char* key : {"passed", "simulated", "cancelled"}) EXPECT_TRUE(report.at(key).is_boolean()) << key;
  for (const char* key : {"simulatedTime", "timeStep", "energyDrift", "finalEnergyDrift", "worstJointError",
                          "worstJointMisalignment", "worstLimitViolation", "worstLimitRatio", "wallTime", "cpuTime"}) {
    EXPECT_TRUE(report.at(key).is_number()) << key;
  }
  for (const char* key : {"steps", "bodies"}) EXPECT_TRUE(report.at(key).is_number_integer()) << key;
  for (const char* key : {"stepper", "worstJoint", "worstLimitJoint"}) EXPECT_TRUE(report.at(key).is_string()) << key;
  EXPECT_TRUE(report.at("diagnostics").is_array());
  EXPECT_TRUE(report.at("conversionDiagnostics").is_array());
}

TEST(ValidateCli, JsonReportHasTheDocumentedFields) {
  const auto run = validate("--json " + quoted(testing::data_dir() / "blender" / "arm3.gltf"));
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const json report = json::parse(run.out);
  expect_report_fields(report);
  EXPECT_TRUE(report["passed"].get<bool>());
  EXPECT_EQ(report["steps"], 3000);
  EXPECT_EQ(report["bodies"], 2);  // the base is held by the world
  EXPECT_EQ(report["stepper"], "dWorldStep");
  EXPECT_EQ(report["timeStep"], 0.001);
  EXPECT_NEAR(report["simulatedTime"].get<double>(), 3.0, 1e-9);
  EXPECT_LE(report["energyDrift"].get<double>(), 0.01);
  EXPECT_GE(report["wallTime"].get<double>(), 0.0);
}

TEST(ValidateCli, JsonReportOfABrokenModelCarriesTheDiagnostic) {
  testing::TempDir folder;
  const auto run = validate("--json --stepper quick_step --floating " +
                            quoted(write_two_boxes(folder, {{"rdtf_mass", 1e7}}, kHinge)));
  EXPECT_EQ(run.exit_code, 2) << run.out << run.err;
  const json report = json::parse(run.out);
  expect_report_fields(report);
  EXPECT_FALSE(report["passed"].get<bool>());
  int found = 0;
  for (const json& d : report["diagnostics"]) {
    if (d["code"] != "JOINT_MASS_RATIO") continue;
    ++found;
    EXPECT_EQ(d["severity"], "error");
    EXPECT_NE(d["message"].get<std::string>().find("'base_arm_joint'"), std::string::npos);
    EXPECT_NE(d["file"].get<std::string>().find("two_boxes.gltf"), std::string::npos);
  }
  EXPECT_EQ(found, 1) << report.dump(1);
}

// Options reach the run: time step, duration, and gravity for Z-up content.
TEST(ValidateCli, OptionsChangeTheRun) {
  const auto run = validate("--json --seconds 0.5 --time-step 0.002 --gravity 0 0 -9.80665 " +
                            quoted(testing::data_dir() / "blender" / "arm3.gltf"));
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const json report = json::parse(run.out);
  EXPECT_EQ(report["steps"], 250);
  EXPECT_EQ(report["timeStep"], 0.002);
  EXPECT_EQ(report["startPose"], json::object());  // the rest pose
  EXPECT_EQ(report["stepper"], "dWorldStep");      // auto, 2 bodies

  // --stepper forces one, as rdtfd's setting does; a name it does not know is refused.
  const auto quick = validate("--json --seconds 0.1 --stepper quick_step " + quoted(testing::data_dir() / "blender" / "arm3.gltf"));
  ASSERT_EQ(quick.exit_code, 0) << quick.out << quick.err;
  EXPECT_EQ(json::parse(quick.out)["stepper"], "dWorldQuickStep");
  const auto bad = validate("--stepper rk4 " + quoted(testing::data_dir() / "blender" / "arm3.gltf"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE((bad.out + bad.err).find("rk4"), std::string::npos) << bad.out << bad.err;
}

// A time step longer than the run takes no step: it passed, "0 s simulated in 0 steps".
TEST(ValidateCli, ATimeStepLongerThanTheRunIsRefused) {
  const auto run = validate("--time-step 10 " + quoted(testing::data_dir() / "blender" / "arm3.gltf"));
  EXPECT_EQ(run.exit_code, 2) << run.out << run.err;
  EXPECT_NE(run.err.find("SIM_INVALID_OPTIONS"), std::string::npos) << run.out << run.err;
  EXPECT_NE(run.err.find("a time step of 10 s over a run of 3 s: give a positive time step no longer than the run"),
            std::string::npos)
      << run.err;
  // Up to twice the run it rounded to one step and passed; beyond any run's count of steps it
  // overflowed that count.
  for (const char* step : {"4", "1e-300"}) {
    const auto refused = validate(std::string("--time-step ") + step + " " + quoted(testing::data_dir() / "blender" / "arm3.gltf"));
    EXPECT_EQ(refused.exit_code, 2) << step << refused.out << refused.err;
    EXPECT_NE(refused.err.find("SIM_INVALID_OPTIONS"), std::string::npos) << step << refused.err;
  }
  EXPECT_EQ(run.out.find("PASS"), std::string::npos) << run.out;
  // --seconds 0 asks for the physical checks alone: no step, and no complaint about it.
  const auto checks_only = validate("--seconds 0 " + quoted(testing::data_dir() / "blender" / "arm3.gltf"));
  EXPECT_EQ(checks_only.exit_code, 0) << checks_only.out << checks_only.err;
}

// --start-offset bends every revolute joint without a named start (arm3: shoulder and elbow, whose
// limits allow +0.3 rad) and the report says where the run started.
TEST(ValidateCli, StartOffsetBendsTheRevoluteJoints) {
  const auto run = validate("--json --seconds 0.2 --start-offset 0.3 " + quoted(testing::data_dir() / "blender" / "arm3.gltf"));
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const json report = json::parse(run.out);
  EXPECT_EQ(report["startPose"], (json{{"shoulder", 0.3}, {"elbow", 0.3}})) << report.dump(1);
}

}  // namespace
}  // namespace rdtf
