// Bad URDF input: each gets one clear error naming the file, the element and what is wrong; the
// CLI exits 2 and writes nothing.
#include <cctype>

#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using namespace urdf_test;
namespace fs = std::filesystem;

struct BadUrdf {
  const char* label;
  const char* text;
  const char* code;
  const char* pointer;  // The element the error points at.
  const char* says;     // A piece of the message.
};

const BadUrdf kBadUrdfs[] = {
    {"missing mesh",
     "<robot name=\"r\">\n<link name=\"a\">\n<visual><geometry><mesh filename=\"meshes/gone.stl\"/></geometry></visual>\n"
     "</link>\n</robot>\n",
     "URDF_MESH_NOT_FOUND", "/robot/link[@name='a']/visual[1]", "line 3: mesh file 'meshes/gone.stl' not found"},
    {"not an stl",
     "<robot name=\"r\">\n<link name=\"a\">\n<visual><geometry><mesh filename=\"junk.stl\"/></geometry></visual>\n"
     "</link>\n</robot>\n",
     "URDF_MESH_INVALID", "/robot/link[@name='a']/visual[1]", "junk.stl"},
    {"malformed xml", "<robot name=\"r\">\n<link name=\"a\">\n</robot>\n", "URDF_MALFORMED_XML", "", "malformed XML"},
    {"not a robot", "<sdf version=\"1.6\"/>\n", "URDF_NOT_A_ROBOT", "", "<sdf>"},
    {"loop",
     "<robot name=\"r\">\n<link name=\"root\"/>\n<link name=\"b\"/>\n<link name=\"c\"/>\n"
     "<joint name=\"root_b\" type=\"fixed\"><parent link=\"root\"/><child link=\"b\"/></joint>\n"
     "<joint name=\"b_c\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>\n"
     "<joint name=\"c_b\" type=\"fixed\"><parent link=\"c\"/><child link=\"b\"/></joint>\n</robot>\n",
     "URDF_LINK_TWO_PARENTS", "/robot/joint[@name='c_b']", "link 'b' is the child of joint 'c_b' and of joint 'root_b'"},
    {"loop without a second parent",
     "<robot name=\"r\">\n<link name=\"root\"/>\n<link name=\"b\"/>\n<link name=\"c\"/>\n"
     "<joint name=\"b_c\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>\n"
     "<joint name=\"c_b\" type=\"fixed\"><parent link=\"c\"/><child link=\"b\"/></joint>\n</robot>\n",
     "URDF_JOINT_LOOP", "/robot/joint[@name='", "form a loop"},
    {"unknown joint kind",
     "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n"
     "<joint name=\"j\" type=\"hinge\"><parent link=\"a\"/><child link=\"b\"/></joint>\n</robot>\n",
     "URDF_UNKNOWN_JOINT_TYPE", "/robot/joint[@name='j']", "line 4: joint 'j' has type 'hinge'"},
    {"missing parent link",
     "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n"
     "<joint name=\"j\" type=\"fixed\"><parent link=\"ghost\"/><child link=\"b\"/></joint>\n</robot>\n",
     "URDF_UNKNOWN_LINK", "/robot/joint[@name='j']", "names parent link 'ghost', which no <link> defines"},
    {"duplicate link names", "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"a\"/>\n</robot>\n",
     "URDF_DUPLICATE_NAME", "/robot/link[@name='a']", "line 3: a second link is named 'a'"},
    {"negative mass",
     "<robot name=\"r\">\n<link name=\"a\">\n<inertial><mass value=\"-2\"/>"
     "<inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial>\n</link>\n</robot>\n",
     "URDF_INVALID_INERTIAL", "/robot/link[@name='a']/inertial", "mass -2"},
};

class UrdfImportErrors : public ::testing::TestWithParam<BadUrdf> {};

TEST_P(UrdfImportErrors, ClearErrorAndNoOutput) {
  const BadUrdf& bad = GetParam();
  TempDir dir;
  const fs::path urdf = dir / "robot.urdf";
  testing::write_file(urdf, bad.text);
  testing::write_file(dir / "junk.stl", "this is no STL file");

  Diagnostics diag;
  EXPECT_FALSE(import_urdf(urdf, UrdfImportOptions{}, diag));
  const Diagnostic* found = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == bad.code) found = &d;
  }
  ASSERT_NE(found, nullptr) << "no " << bad.code;
  EXPECT_EQ(found->severity, Severity::kError);
  EXPECT_EQ(found->file, urdf.string());
  EXPECT_EQ(found->pointer.rfind(bad.pointer, 0), 0u) << found->pointer;
  EXPECT_NE(found->message.find(bad.says), std::string::npos) << found->message;

  // The CLI: exit code 2, the error on stderr with the file and element, no output file.
  const fs::path out = dir / "out.gltf";
  const testing::CommandResult run =
      testing::run_command("'" + testing::cli_path() + "' import '" + urdf.string() + "' -o '" + out.string() + "'");
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find(urdf.string() + ":" + found->pointer), std::string::npos) << run.err;
  EXPECT_NE(run.err.find(bad.code), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(dir / "out.bin"));
}

INSTANTIATE_TEST_SUITE_P(BadInput, UrdfImportErrors, ::testing::ValuesIn(kBadUrdfs),
                         [](const ::testing::TestParamInfo<BadUrdf>& param_info) {
                           std::string name = param_info.param.label;
                           for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return name;
                         });

TEST(UrdfImportErrorsCli, MissingInputFileIsExitTwoNamingIt) {
  TempDir dir;
  const testing::CommandResult run = testing::run_command("'" + testing::cli_path() + "' import '" +
                                                          (dir / "nope.urdf").string() + "' -o '" +
                                                          (dir / "out.gltf").string() + "'");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find((dir / "nope.urdf").string()), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(dir / "out.gltf"));
}

}  // namespace
}  // namespace rdtf
