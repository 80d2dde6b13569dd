// The gate's verdict kept between saves of a model (daemon/verdict_memo.h): a conversion reuses it
// only when the robot, its geometry's bounds, the file and the settings are exactly those it was
// computed for; any change to one of them runs the check again.
#include "verdict_memo.h"

#include <gtest/gtest.h>

#include <cmath>

#include "conversion.h"
#include "daemon_loop.h"
#include "support/test_support.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;

std::string messages(const Diagnostics& diag) {
  std::string text;
  for (const Diagnostic& d : diag.all()) text += format(d) + "\n";
  return text;
}

// arm3 in a watched folder, converted with the dynamics check under the settings key "settings A".
struct Arm {
  testing::TempDir root;
  testing::TempDir out;
  Json document = Json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf"));
  Stepper stepper = Stepper::kAuto;

  Arm() {
    testing::write_file(root / "arm3.bin", testing::read_file(testing::data_dir() / "blender" / "arm3.bin"));
    document["materials"] = Json::array({{{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.5, 0.5, 1.0}}}}}});
    for (auto& mesh : document["meshes"]) {
      for (auto& primitive : mesh["primitives"]) primitive["material"] = 0;
    }
  }
  Json& node(const std::string& name) {
    for (auto& n : document["nodes"]) {
      if (n.value("name", "") == name) return n;
    }
    throw std::runtime_error("no node " + name);
  }
  ConversionJob job(const std::string& file = "arm3.gltf") {
    testing::write_file(root / file, document.dump(1));
    ConversionJob job;
    job.model_id = file;
    job.root = fs::canonical(root.path());
    job.source = job.root / file;
    job.output_dir = out.path();
    job.validation = ValidationOptions{};
    job.validation->duration = 0.5;
    job.validation->simulation.stepper = stepper;
    job.cache_key = "settings A";
    return job;
  }
  ConversionOutcome convert(ConversionJob job) {
    ConversionOutcome outcome = run_conversion(job);
    if (outcome.kind != ConversionOutcome::Kind::kConverted) {
      ADD_FAILURE() << messages(outcome.diagnostics);
    }
    return outcome;
  }
};

TEST(DaemonVerdictMemo, AnIdenticalRobotReusesTheVerdictAndAnyChangeRunsTheCheck) {
  Arm arm;
  const ConversionOutcome first = arm.convert(arm.job());
  ASSERT_TRUE(first.converted && first.converted->validation);
  EXPECT_FALSE(first.verdict_reused);
  ASSERT_TRUE(first.verdict) << "a verdict that ran is kept";
  EXPECT_TRUE(first.converted->validation->passed) << first.converted->validation->summary_line;
  EXPECT_GT(first.converted->validation->steps, 0u);
  EXPECT_EQ(first.verdict->verdict.summary_line, first.converted->validation->summary_line);

  // Only the copyright and a colour: other content, the same robot and bounds. (Not the generator:
  // Blender's is what makes custom-property vectors read in Blender's axes.)
  arm.document["asset"]["copyright"] = "another owner";
  arm.document["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"][0] = 0.25;
  ConversionJob visual = arm.job();
  visual.verdict = first.verdict;
  const ConversionOutcome repainted = arm.convert(visual);
  ASSERT_TRUE(repainted.converted && repainted.converted->validation);
  EXPECT_NE(repainted.content_hash, first.content_hash);
  EXPECT_TRUE(repainted.verdict_reused);
  EXPECT_FALSE(repainted.verdict) << "nothing new to keep: the check did not run";
  EXPECT_TRUE(repainted.converted->validation->passed);
  EXPECT_EQ(repainted.converted->validation->summary_line, first.converted->validation->summary_line);
  EXPECT_EQ(repainted.converted->validation->steps, first.converted->validation->steps);
  EXPECT_EQ(messages(repainted.converted->validation->diagnostics), messages(first.converted->validation->diagnostics));
  // The colour did reach the output: the conversion itself ran.
  EXPECT_NE(repainted.converted->rdtf_json.find("0.25"), std::string::npos);

  // The elbow's damping one last bit larger: another robot, the check runs.
  const double damping = arm.node("elbow")["extras"]["rdtf_damping"].get<double>();
  arm.node("elbow")["extras"]["rdtf_damping"] = std::nextafter(damping, 1.0);
  ConversionJob damped = arm.job();
  damped.verdict = first.verdict;
  const ConversionOutcome changed = arm.convert(damped);
  ASSERT_TRUE(changed.converted && changed.converted->validation);
  EXPECT_FALSE(changed.verdict_reused);
  ASSERT_TRUE(changed.verdict);
  EXPECT_NE(changed.verdict->digest, first.verdict->digest);
  EXPECT_GT(changed.converted->validation->steps, 0u);

  // The same robot and file under other settings (another settings_key): the check runs.
  arm.node("elbow")["extras"]["rdtf_damping"] = damping;
  ConversionJob resettled = arm.job();
  resettled.verdict = first.verdict;
  resettled.cache_key = "settings B";
  const ConversionOutcome other_settings = arm.convert(resettled);
  EXPECT_FALSE(other_settings.verdict_reused);
  EXPECT_TRUE(other_settings.verdict);

  // The same robot in another file (its diagnostics would name that file): the check runs.
  ConversionJob moved = arm.job("arm3_copy.gltf");
  moved.verdict = first.verdict;
  const ConversionOutcome other_file = arm.convert(moved);
  EXPECT_FALSE(other_file.verdict_reused);
  EXPECT_TRUE(other_file.verdict);

  // No settings key (nothing says what the verdict was computed under): nothing kept or reused.
  ConversionJob keyless = arm.job();
  keyless.cache_key.clear();
  keyless.verdict = first.verdict;
  const ConversionOutcome unkeyed = arm.convert(keyless);
  EXPECT_FALSE(unkeyed.verdict_reused);
  EXPECT_FALSE(unkeyed.verdict);
}

TEST(DaemonVerdictMemo, AFailedVerdictIsNeverReplacedByThePassOfAnotherRobot) {
  Arm arm;
  arm.stepper = Stepper::kQuickStep;  // whose run judges the mass ratio below
  const ConversionOutcome good = arm.convert(arm.job());
  ASSERT_TRUE(good.verdict && good.verdict->verdict.passed);

  // The forearm's solids at a millionth of the default density: the mass ratio across the elbow
  // (1e6, beyond the bound of 1e3) fails the check (JOINT_MASS_RATIO).
  const Json before = arm.document;
  bool set = false;
  for (auto& n : arm.document["nodes"]) {
    if (n.value("name", "") == "forearm_geom" || n.value("name", "") == "gripper") {
      n["extras"]["rdtf_density"] = 1e-3;
      set = true;
    }
  }
  ASSERT_TRUE(set);
  ConversionJob light = arm.job();
  light.verdict = good.verdict;
  const ConversionOutcome failed = run_conversion(light);
  ASSERT_TRUE(failed.converted && failed.converted->validation) << messages(failed.diagnostics);
  EXPECT_FALSE(failed.verdict_reused);
  EXPECT_FALSE(failed.converted->validation->passed) << failed.converted->validation->summary_line;
  EXPECT_TRUE(failed.converted->validation->diagnostics.contains("JOINT_MASS_RATIO"))
      << messages(failed.converted->validation->diagnostics);
  ASSERT_TRUE(failed.verdict);

  // The failing robot saved again with another copyright: its failed verdict is reused...
  arm.document["asset"]["copyright"] = "saved again";
  ConversionJob again = arm.job();
  again.verdict = failed.verdict;
  const ConversionOutcome still = run_conversion(again);
  ASSERT_TRUE(still.converted && still.converted->validation);
  EXPECT_TRUE(still.verdict_reused);
  EXPECT_FALSE(still.converted->validation->passed);

  // ...and the good verdict never applies to it.
  ConversionJob with_good = arm.job();
  with_good.verdict = good.verdict;
  const ConversionOutcome judged = run_conversion(with_good);
  ASSERT_TRUE(judged.converted && judged.converted->validation);
  EXPECT_FALSE(judged.verdict_reused);
  EXPECT_FALSE(judged.converted->validation->passed);

  // Back to the good robot: the good verdict applies again.
  arm.document = before;
  ConversionJob restored = arm.job();
  restored.verdict = good.verdict;
  const ConversionOutcome back = arm.convert(restored);
  EXPECT_TRUE(back.verdict_reused);
  EXPECT_TRUE(back.converted->validation->passed);
}

// The digest tells apart robots, bounds, files and settings that differ in any field by any bit.
bool same_robot(const Robot& a, const Robot& b) {
  return check_digest("m.gltf", "k", a, {}) == check_digest("m.gltf", "k", b, {});
}
bool same_bounds(const LinkBounds& a, const LinkBounds& b) {
  const Robot robot;
  return check_digest("m.gltf", "k", robot, a) == check_digest("m.gltf", "k", robot, b);
}

TEST(DaemonVerdictMemo, TheDigestTellsApartAnyBitOfWhatTheCheckReads) {
  Robot a;
  a.name = "r";
  a.links.resize(2);
  a.joints.resize(1);
  a.joints[0].damping = 0.0;
  a.root_links = {0};
  Robot b = a;
  EXPECT_TRUE(same_robot(a, b));
  b.joints[0].damping = -0.0;  // Equal as numbers, other bits.
  EXPECT_FALSE(same_robot(a, b));
  b = a;
  b.links[1].inertial.inertia(2, 1) = 1e-300;
  EXPECT_FALSE(same_robot(a, b));
  b = a;
  b.links[0].X_SL.translation().x() = 1e-17;
  EXPECT_FALSE(same_robot(a, b));
  b = a;
  b.joints[0].limits = JointLimits{};
  EXPECT_FALSE(same_robot(a, b));
  b = a;
  b.links[1].meshes.push_back(LinkMesh{});
  EXPECT_FALSE(same_robot(a, b));
  b = a;
  b.joints[0].axis.z() = std::nextafter(0.0, 1.0);
  EXPECT_FALSE(same_robot(a, b));
  b = a;
  b.links.pop_back();
  EXPECT_FALSE(same_robot(a, b));
  b = a;
  b.links[1].inertial_source = InertialSource::kAuthored;
  EXPECT_FALSE(same_robot(a, b));
  b = a;
  b.joints[0].kind = JointKind::kRevolute;
  EXPECT_FALSE(same_robot(a, b));
  // Characters moved between two names: each name is hashed after its length.
  a.links[0].name = "ab";
  a.links[1].name = "c";
  b = a;
  b.links[0].name = "a";
  b.links[1].name = "bc";
  EXPECT_FALSE(same_robot(a, b));
  // An index moved between two lists.
  b = a;
  a.links[0].child_joints = {1, 2};
  b.links[0].child_joints = {1};
  b.links[1].child_joints = {2};
  EXPECT_FALSE(same_robot(a, b));

  const LinkBounds box{Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1)), std::nullopt};
  LinkBounds other = box;
  EXPECT_TRUE(same_bounds(box, other));
  other[0]->max().y() = std::nextafter(1.0, 2.0);
  EXPECT_FALSE(same_bounds(box, other));
  other = box;
  other[1] = Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  EXPECT_FALSE(same_bounds(box, other));
  other = box;
  other.pop_back();
  EXPECT_FALSE(same_bounds(box, other));

  // The file and the settings, and where one ends and the other begins.
  EXPECT_NE(check_digest("a.gltf", "k", a, box), check_digest("b.gltf", "k", a, box));
  EXPECT_NE(check_digest("a.gltf", "k", a, box), check_digest("a.gltf", "k2", a, box));
  EXPECT_NE(check_digest("a.gltfk", "", a, box), check_digest("a.gltf", "k", a, box));
  EXPECT_EQ(check_digest("a.gltf", "k", a, box), check_digest("a.gltf", "k", Robot(a), LinkBounds(box)));
}

// The loop keeps each model's last verdict and hands it to the model's next conversion; nothing a
// reused verdict did not pass is published.
class DaemonVerdicts : public DaemonLoop {
 protected:
  void start_gated() {
    start([](DaemonConfig& config) {
      config.validate = true;
      config.validation_seconds = 0.5;
      config.stepper = Stepper::kQuickStep;  // whose run judges the mass ratio the failing robot has
    });
  }
  // Saves arm3.gltf and lets it settle: its conversion waits in the runner.
  const ConversionJob& save_arm(const Json& document) {
    save("arm3.gltf", document.dump(1));
    advance(std::chrono::milliseconds(60));
    EXPECT_EQ(runner_->waiting(), 1u);
    return runner_->next();
  }
};

TEST_F(DaemonVerdicts, EachConversionGetsTheModelsLastVerdictAndAFailureIsNeverPublished) {
  Arm arm;  // Its document; the files go to the watched folder.
  rdtf::testing::write_file(watch_ / "arm3.bin", fixture("arm3.bin"));
  start_gated();
  const std::string id = "arm3.gltf";

  EXPECT_FALSE(save_arm(arm.document).verdict) << "no verdict before the first check";
  convert();
  EXPECT_EQ(events(id), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA"}));

  // A colour: the first verdict goes with the job and applies.
  arm.document["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"][1] = 0.75;
  const auto first = save_arm(arm.document).verdict;
  ASSERT_TRUE(first);
  EXPECT_TRUE(first->verdict.passed);
  convert();
  EXPECT_EQ(events(id), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r2", "INERTIA"}));

  // A robot that fails: the passing verdict goes with the job but does not apply; nothing published.
  for (auto& n : arm.document["nodes"]) {
    if (n.value("name", "") == "forearm_geom" || n.value("name", "") == "gripper") n["extras"]["rdtf_density"] = 1e-3;
  }
  EXPECT_EQ(save_arm(arm.document).verdict, first) << "a reused verdict is kept as it was";
  convert();
  EXPECT_EQ(events(id), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r2", "INERTIA",
                                                  "ERROR live r2"}));

  // The failing robot saved again: its own (failed) verdict goes with the job, still nothing published.
  arm.document["asset"]["copyright"] = "saved again";
  const auto failed = save_arm(arm.document).verdict;
  ASSERT_TRUE(failed);
  EXPECT_NE(failed, first);
  EXPECT_FALSE(failed->verdict.passed);
  convert();
  EXPECT_EQ(events(id), (std::vector<std::string>{"DESCRIPTION r1", "INERTIA", "DESCRIPTION r2", "INERTIA",
                                                  "ERROR live r2", "ERROR live r2"}));

  // A model removed forgets its verdict: when it comes back, the check runs.
  std::filesystem::remove(watch_ / id);
  notify(Kind::kRemoved, watch_ / id);
  advance(std::chrono::milliseconds(60));
  convert();  // Finds the file gone: the model is dropped.
  EXPECT_EQ(events(id).back(), "REMOVED");
  EXPECT_FALSE(save_arm(arm.document).verdict);
}

}  // namespace
}  // namespace rdtf::daemon
