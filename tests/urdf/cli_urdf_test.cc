// `rdtf urdf IN -o DIR` and `rdtf import robot.urdf -o robot.gltf` as a user runs them.
#include <algorithm>

#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using namespace urdf_test;
namespace fs = std::filesystem;

testing::CommandResult rdtf_cli(const std::string& arguments) {
  return testing::run_command("'" + testing::cli_path() + "' " + arguments);
}

std::string quoted(const fs::path& path) { return "'" + path.string() + "'"; }

TEST(UrdfCli, ExportWritesRobotUrdfAndMeshesThatCheckUrdfAccepts) {
  TempDir dir;
  const auto run = rdtf_cli("urdf " + quoted(testing::data_dir() / "blender/arm3.gltf") + " -o " + quoted(dir / "arm3"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("wrote " + (dir / "arm3/robot.urdf").string()), std::string::npos) << run.err;
  for (const char* link : {"base_link", "upper_arm", "forearm"}) {
    EXPECT_TRUE(fs::is_regular_file(dir / "arm3/meshes" / (std::string(link) + ".stl"))) << link;
  }
  expect_check_urdf_passes(dir / "arm3/robot.urdf");
  // The elbow's missing limits are reported (a warning, printed without --verbose).
  EXPECT_NE(run.err.find("URDF_REVOLUTE_WITHOUT_LIMITS"), std::string::npos) << run.err;

  // And back: the URDF imports to a glTF the Khronos validator accepts.
  const auto back = rdtf_cli("import " + quoted(dir / "arm3/robot.urdf") + " -o " + quoted(dir / "arm3.gltf"));
  ASSERT_EQ(back.exit_code, 0) << back.err;
  const auto report = testing::khronos_report(dir / "arm3.gltf");
  EXPECT_EQ(report["issues"]["numErrors"].get<int>(), 0) << report["issues"].dump(1);
  const auto glb = rdtf_cli("import " + quoted(dir / "arm3/robot.urdf") + " -o " + quoted(dir / "arm3.glb"));
  ASSERT_EQ(glb.exit_code, 0) << glb.err;
  EXPECT_EQ(testing::khronos_report(dir / "arm3.glb")["issues"]["numErrors"].get<int>(), 0);
}

TEST(UrdfCli, OptionsForRosAndYUp) {
  TempDir dir;
  const auto run = rdtf_cli("urdf " + quoted(testing::data_dir() / "blender/two_cylinder.gltf") + " -o " +
                            quoted(dir.path()) + " --y-up --no-mujoco --mesh-prefix package://my_robot/urdf/");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string text = testing::read_file(dir / "robot.urdf");
  EXPECT_EQ(text.find("<mujoco"), std::string::npos);
  EXPECT_NE(text.find(R"(filename="package://my_robot/urdf/meshes/arm.stl")"), std::string::npos) << text;
  const auto model = parse_with_urdfdom(text);
  // Y kept up: the arm sits along +y of the base.
  const auto& origin = model->getJoint("base_arm_joint")->parent_to_joint_origin_transform.position;
  EXPECT_EQ(origin.z, 0.0);
  EXPECT_GT(origin.y, 0.3);
}

TEST(UrdfCli, ModelUrdfCannotSayIsExitTwoAndWritesNothing) {
  GltfBuilder b;
  const int mesh = b.box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.2f));
  const int base = b.node("base", -1, Json{{"mesh", mesh}});
  const int joint = b.node("hip", base, Json{{"extras", {{"rdtf_joint", "ball"}}}});
  b.link_with_mesh("leg", joint, mesh);
  TempDir dir;
  const auto glb = b.glb();
  testing::write_file(dir / "ball.glb", std::string(glb.begin(), glb.end()));
  const auto run = rdtf_cli("urdf " + quoted(dir / "ball.glb") + " -o " + quoted(dir / "out"));
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find((dir / "ball.glb").string() + ":/nodes/" + std::to_string(joint) + ": error URDF_BALL_JOINT"),
            std::string::npos)
      << run.err;
  EXPECT_FALSE(fs::exists(dir / "out/robot.urdf"));
}

// Every path below `dir`, relative, sorted: what a command left behind.
std::vector<std::string> contents(const fs::path& dir) {
  std::vector<std::string> found;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) found.push_back(fs::relative(entry.path(), dir).string());
  std::sort(found.begin(), found.end());
  return found;
}

const char* const kBoxUrdf =
    "<robot name=\"r\"><link name=\"a\"><visual><geometry><box size=\"0.1 0.2 0.3\"/></geometry></visual>"
    "</link></robot>\n";

// -o into folders that do not exist yet: created, as `rdtf convert` creates them (import used to
// fail with exit 1 for a .glb there).
TEST(UrdfCli, ImportCreatesTheOutputFolder) {
  TempDir dir;
  testing::write_file(dir / "t.urdf", kBoxUrdf);
  for (const char* output : {"new/dir/x.glb", "other/dir/x.gltf"}) {
    const auto run = rdtf_cli("import " + quoted(dir / "t.urdf") + " -o " + quoted(dir / output));
    EXPECT_EQ(run.exit_code, 0) << output << "\n" << run.err;
    EXPECT_TRUE(fs::is_regular_file(dir / output)) << output;
  }
  EXPECT_TRUE(fs::is_regular_file(dir / "other/dir/x.bin"));
}

// A folder as the output (ending in '/', or an existing one): exit 2 naming it, and nothing
// written (a stray '.bin' was left there and the exit code was 1).
TEST(UrdfCli, ImportOntoAFolderIsExitTwoAndWritesNothing) {
  TempDir dir;
  testing::write_file(dir / "t.urdf", kBoxUrdf);
  fs::create_directory(dir / "imp");
  testing::write_file(dir / "afile", "");
  const std::vector<std::string> before = contents(dir.path());
  const std::pair<std::string, std::string> cases[] = {
      {(dir / "imp/").string(), "is a folder, not a file: give the file to write, e.g. " + (dir / "imp/robot.gltf").string()},
      {(dir / "imp").string(), "is a folder, not a file: give the file to write, e.g. " + (dir / "imp/robot.gltf").string()},
      {(dir / "new/").string(), "names a folder (it ends in '/'), not a file: give the file to write, e.g. " +
                                    (dir / "new/robot.gltf").string()},
      {(dir / "afile/x.gltf").string(), (dir / "afile").string() + " is a file, not a folder"},
  };
  for (const auto& [output, says] : cases) {
    const auto run = rdtf_cli("import " + quoted(dir / "t.urdf") + " -o '" + output + "'");
    EXPECT_EQ(run.exit_code, 2) << output << "\n" << run.err;
    EXPECT_NE(run.err.find(output + ": error OUTPUT_PATH_INVALID: " + says), std::string::npos) << run.err;
    EXPECT_EQ(contents(dir.path()), before) << output;
  }
}

// `rdtf urdf` onto places where robot.urdf or the meshes cannot go: refused before any mesh is
// written (meshes/*.stl used to stay behind when robot.urdf was a folder).
TEST(UrdfCli, ExportOntoUnwritablePlacesIsExitTwoAndWritesNothing) {
  const fs::path model = testing::data_dir() / "blender/arm3.gltf";
  TempDir dir;
  fs::create_directories(dir / "urdf_is_folder/robot.urdf");
  fs::create_directories(dir / "meshes_is_file");
  testing::write_file(dir / "meshes_is_file/meshes", "");
  fs::create_directories(dir / "mesh_is_folder/meshes/forearm.stl");
  testing::write_file(dir / "afile", "");
  const std::vector<std::string> before = contents(dir.path());
  const std::pair<fs::path, std::string> cases[] = {
      {dir / "urdf_is_folder", "the output " + (dir / "urdf_is_folder/robot.urdf").string() + " is a folder"},
      {dir / "meshes_is_file", (dir / "meshes_is_file/meshes").string() + " is a file, not a folder"},
      {dir / "mesh_is_folder", "the output " + (dir / "mesh_is_folder/meshes/forearm.stl").string() + " is a folder"},
      {dir / "afile", "is a file, not a folder: give the folder to write into"},
      {dir / "afile/sub", (dir / "afile").string() + " is a file, not a folder"},
  };
  for (const auto& [output, says] : cases) {
    const auto run = rdtf_cli("urdf " + quoted(model) + " -o " + quoted(output));
    EXPECT_EQ(run.exit_code, 2) << output << "\n" << run.err;
    EXPECT_NE(run.err.find(output.string() + ": error OUTPUT_PATH_INVALID: " + says), std::string::npos) << run.err;
    EXPECT_EQ(contents(dir.path()), before) << output;
  }
  // And a folder that does not exist yet is made, with its parents.
  const auto run = rdtf_cli("urdf " + quoted(model) + " -o " + quoted(dir / "new/nested/"));
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(fs::is_regular_file(dir / "new/nested/robot.urdf"));
  EXPECT_TRUE(fs::is_regular_file(dir / "new/nested/meshes/forearm.stl"));
}

}  // namespace
}  // namespace rdtf
