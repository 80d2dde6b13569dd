// Published robot descriptions (tests/data/robots, sources and licences in its README.md) through
// `rdtf import` and `rdtf validate`, as a user runs them. Each robot is labelled sound or broken by
// checks that are not rdtf's (independent_robot_checks.h: the authored inertials through urdfdom and
// Eigen, and MuJoCo compiling and simulating the URDF); the test first proves the recorded label is
// what those checks find, then that rdtf agrees: a sound robot imports and validates (exit 0), a
// welded one too with a warning naming every culprit link, a broken one fails with an error
// diagnostic naming every culprit link.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <sstream>
#include <nlohmann/json.hpp>

#include "dynamics/independent_robot_checks.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

using nlohmann::json;

// Simulated time in MuJoCo: long enough for every joint to swing through its range under gravity,
// short enough for ASan (~1 s wall for the whole corpus in Release).
constexpr double kMujocoSeconds = 1.0;

// sound: both independent checks find nothing. broken: the inertia check finds culprits and
// MuJoCo refuses the file or runs it unstably. welded: the inertia check finds culprits that are
// welded (fixed joints) into bodies whose combined inertia is sound, and MuJoCo, which fuses them
// (fusestatic, its URDF default), loads and runs the file stably.
enum class Label { kSound, kWelded, kBroken };

struct RealRobot {
  const char* file;                  // in tests/data/robots
  const char* kind;
  Label label;
  std::vector<std::string> culprits;  // the links with impossible inertia
};

const char* label_name(Label label) {
  return label == Label::kSound ? "sound" : label == Label::kWelded ? "welded" : "broken";
}

std::ostream& operator<<(std::ostream& out, const RealRobot& robot) { return out << robot.file; }

const std::vector<RealRobot>& corpus() {
  static const std::vector<RealRobot> robots = {
      {"ur5.urdf", "industrial arm, +-2 pi joint ranges", Label::kSound, {}},
      {"kuka_iiwa.urdf", "7-joint arm, massless root welded to the world", Label::kSound, {}},
      {"panda.urdf", "collaborative arm and gripper, joint 6 beyond pi, massless frames with inertia", Label::kSound, {}},
      {"a1.urdf", "quadruped, IMU and feet on fixed joints, thighs beyond pi", Label::kSound, {}},
      {"simple_humanoid.urdf", "humanoid, 29 joints", Label::kSound, {}},
      {"r2d2.urdf", "wheeled base with a gripper, primitive shapes", Label::kSound, {}},
      {"cartpole.urdf", "cart-pole, massless rail welded to the world", Label::kSound, {}},
      {"double_pendulum.urdf", "double pendulum", Label::kSound, {}},
      {"ur5_damped_spindle.urdf", "industrial arm, a 0.1 kg spindle damped 0.4 N m s (c h / I = 9.6)", Label::kSound, {}},
      {"ur5_five_finger_hand.urdf", "arm with a five-finger hand, one island of 29 bodies (QuickStep fails it)", Label::kSound, {}},
      {"arm_dexterous_hand_41.urdf", "arm with a 24-joint hand, one island of 41 bodies (QuickStep fails it)", Label::kSound, {}},
      {"allegro_right_hand.urdf", "hand, 16 joints (published inertias impossible)", Label::kBroken,
       {"link_3.0", "link_7.0", "link_11.0", "link_15.0"}},
      {"finger_edu.urdf", "finger (manipulator), a thin-rod link with its fingertip welded on (published)",
       Label::kWelded, {"finger_lower_link"}},
      {"ur5_broken_triangle.urdf", "industrial arm, one link made impossible", Label::kBroken, {"forearm_link"}},
      {"panda_broken_not_pd.urdf", "collaborative arm, one link made impossible", Label::kBroken, {"panda_link4"}},
      {"double_pendulum_broken_zero_inertia.urdf", "pendulum, zero inertia on a moving link", Label::kBroken, {"link2"}},
  };
  return robots;
}

std::filesystem::path robot_path(const RealRobot& robot) { return testing::data_dir() / "robots" / robot.file; }

std::string shell_quoted(const std::filesystem::path& path) { return "'" + path.string() + "'"; }

// Every error diagnostic of the import's output and of `rdtf validate --json`.
struct RdtfVerdict {
  int import_exit = -1, validate_exit = -1;
  std::vector<json> errors, warnings;
  std::string output;  // for failure messages
};

RdtfVerdict run_rdtf(const RealRobot& robot) {
  RdtfVerdict verdict;
  testing::TempDir dir;
  const auto imported = testing::run_command(shell_quoted(testing::cli_path()) + " import " + shell_quoted(robot_path(robot)) +
                                             " -o " + shell_quoted(dir / "robot.gltf"));
  verdict.import_exit = imported.exit_code;
  verdict.output = imported.out + imported.err;
  if (imported.exit_code != 0) {
    // The import's diagnostics are text: keep the error lines as messages.
    std::istringstream lines(verdict.output);
    for (std::string line; std::getline(lines, line);) {
      if (line.find(" error ") != std::string::npos) verdict.errors.push_back({{"message", line}});
    }
    return verdict;
  }
  const auto validated =
      testing::run_command(shell_quoted(testing::cli_path()) + " validate --json " + shell_quoted(dir / "robot.gltf"));
  verdict.validate_exit = validated.exit_code;
  verdict.output += validated.out + validated.err;
  const json report = json::parse(validated.out, nullptr, false);
  if (report.is_discarded()) return verdict;
  for (const char* list : {"conversionDiagnostics", "diagnostics"}) {
    for (const json& d : report.value(list, json::array())) {
      if (d.value("severity", "") == "error") verdict.errors.push_back(d);
      if (d.value("severity", "") == "warning") verdict.warnings.push_back(d);
    }
  }
  return verdict;
}

std::string codes(const RdtfVerdict& verdict) {
  std::string out;
  for (const json& e : verdict.errors) {
    out += (out.empty() ? "" : ", ") + e.value("code", std::string("?")) + " (" + e.value("message", std::string()) + ")";
  }
  return out.empty() ? "none" : out;
}

class RealRobots : public ::testing::TestWithParam<RealRobot> {};

TEST_P(RealRobots, IndependentChecksGiveTheLabelAndRdtfAgrees) {
  const RealRobot& robot = GetParam();
  const std::filesystem::path path = robot_path(robot);
  std::printf("robot %s (%s), label %s\n", robot.file, robot.kind, label_name(robot.label));

  // 1. The authored inertials, parsed by urdfdom.
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(testing::read_file(path));
  ASSERT_TRUE(model) << path << ": urdfdom cannot parse it";
  const robots::InertiaReport inertia = robots::check_inertials(*model);
  std::vector<std::string> found;
  for (const robots::Finding& f : inertia.findings) {
    std::printf("  inertia check: link '%s': %s\n", f.link.c_str(), f.problem.c_str());
    if (std::find(found.begin(), found.end(), f.link) == found.end()) found.push_back(f.link);
  }
  std::printf("  inertia check: %d links with inertials, %d moving bodies, %zu findings\n",
              inertia.links_with_inertial, inertia.moving_bodies, inertia.findings.size());

  // 2. MuJoCo compiles and simulates it.
  const robots::MujocoRun mujoco = robots::run_in_mujoco(path, kMujocoSeconds);
  const bool mujoco_stable = mujoco.loaded && mujoco.finite && mujoco.bad_qacc_warnings == 0 &&
                             mujoco.worst_energy_rise <= robots::kEnergyRiseBound * mujoco.energy_scale;
  if (mujoco.loaded) {
    std::printf("  MuJoCo: %d bodies (fused), %d dofs, %.3g s simulated, finite %d, bad-qacc warnings %d, "
                "worst energy rise %.3g J = %.3g of m g L (%.3g J)\n",
                mujoco.bodies, mujoco.dofs, mujoco.seconds, mujoco.finite, mujoco.bad_qacc_warnings,
                mujoco.worst_energy_rise, mujoco.worst_energy_rise / mujoco.energy_scale, mujoco.energy_scale);
  } else {
    std::printf("  MuJoCo refuses it: %s\n", mujoco.error.c_str());
  }

  // The label is what the independent checks say: sound when both find nothing; welded when the
  // inertia check's culprits are fused by MuJoCo into bodies it runs stably (finger_edu: the rod
  // with its fingertip); broken otherwise.
  if (robot.label == Label::kSound) {
    EXPECT_TRUE(inertia.findings.empty()) << path << " is labelled sound";
    EXPECT_TRUE(mujoco_stable) << path << " is labelled sound; MuJoCo: " << mujoco.error;
  } else {
    std::vector<std::string> expected = robot.culprits;
    std::sort(expected.begin(), expected.end());
    std::sort(found.begin(), found.end());
    EXPECT_EQ(found, expected) << path << ": the inertia check's culprits";
    if (robot.label == Label::kWelded) {
      EXPECT_TRUE(mujoco_stable) << path << " is labelled welded; MuJoCo: " << mujoco.error;
    } else {
      EXPECT_FALSE(mujoco_stable) << path << " is labelled broken but MuJoCo runs it stably";
    }
  }

  // 3. rdtf, as a user runs it.
  const RdtfVerdict rdtf = run_rdtf(robot);
  std::printf("  rdtf: import exit %d, validate exit %d, errors: %s\n", rdtf.import_exit, rdtf.validate_exit,
              codes(rdtf).c_str());
  if (robot.label == Label::kSound) {
    EXPECT_EQ(rdtf.import_exit, 0) << rdtf.output;
    EXPECT_EQ(rdtf.validate_exit, 0) << path << " is sound but rdtf validate refuses it: " << codes(rdtf);
  } else if (robot.label == Label::kWelded) {
    // It runs, and rdtf says which authored links no real part could have.
    EXPECT_EQ(rdtf.import_exit, 0) << rdtf.output;
    EXPECT_EQ(rdtf.validate_exit, 0) << path << " is labelled welded but rdtf validate refuses it: " << codes(rdtf);
    for (const std::string& link : robot.culprits) {
      const bool named = std::any_of(rdtf.warnings.begin(), rdtf.warnings.end(), [&](const json& w) {
        return w.value("message", std::string()).find("'" + link + "'") != std::string::npos;
      });
      EXPECT_TRUE(named) << path << ": no warning names the culprit link '" << link << "'";
    }
  } else {
    EXPECT_TRUE(rdtf.import_exit != 0 || rdtf.validate_exit != 0) << path << " is broken but rdtf passes it";
    for (const std::string& link : robot.culprits) {
      const bool named = std::any_of(rdtf.errors.begin(), rdtf.errors.end(), [&](const json& e) {
        return e.value("message", std::string()).find("'" + link + "'") != std::string::npos;
      });
      EXPECT_TRUE(named) << path << ": no error names the culprit link '" << link << "': " << codes(rdtf);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Corpus, RealRobots, ::testing::ValuesIn(corpus()),
                         [](const ::testing::TestParamInfo<RealRobot>& param_info) {
                           std::string name = std::filesystem::path(param_info.param.file).stem().string();
                           for (char& c : name) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return name;
                         });

}  // namespace
}  // namespace rdtf
