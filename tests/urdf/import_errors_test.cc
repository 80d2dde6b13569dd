// Bad URDF input: each gets one clear error naming the file, the element and what is wrong; the
// CLI exits 2 and writes nothing.
#include <grp.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>

#include <cctype>
#include <cstdint>
#include <functional>
#include <regex>

#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using namespace urdf_test;
namespace fs = std::filesystem;

struct BadUrdf {
  std::string label;
  std::string text;
  std::string code;
  std::string pointer;  // The element (or attribute) the error points at: the pointer starts with it.
  std::string says;     // A piece of the message.
};

// gtest names each case by its label, not by the bytes of the struct.
void PrintTo(const BadUrdf& bad, std::ostream* out) { *out << bad.label; }

// A robot of one link 'a' whose <link> holds `elements` on line 3.
std::string link_urdf(const std::string& elements) {
  return "<robot name=\"r\">\n<link name=\"a\">\n" + elements + "\n</link>\n</robot>\n";
}

// Links 'a' and 'b' joined by joint 'j' of `type`, whose <joint> holds `elements` on line 5.
std::string joint_urdf(const std::string& elements, const std::string& type = "revolute") {
  return "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n<joint name=\"j\" type=\"" + type +
         "\"><parent link=\"a\"/><child link=\"b\"/>\n" + elements + "\n</joint>\n</robot>\n";
}

const std::string kLimit = "<limit lower=\"-1\" upper=\"1\" effort=\"10\" velocity=\"2\"/>";
const std::string kInertia = "<inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/>";

std::string inertial(const std::string& mass, const std::string& inertia = kInertia) {
  return "<inertial><mass value=\"" + mass + "\"/>" + inertia + "</inertial>";
}

std::string visual(const std::string& shape) { return "<visual><geometry>" + shape + "</geometry></visual>"; }

// A robot whose link 'a' (line 2) is followed by `levels` nested <x> elements, one a line from
// line 3: the robot is depth 1, so the element past depth 256 is on line 258.
std::string nested(int levels) {
  std::string text = "<robot name=\"r\">\n<link name=\"a\"/>\n";
  for (int i = 0; i < levels; ++i) text += "<x>\n";
  for (int i = 0; i < levels; ++i) text += "</x>";
  return text + "\n</robot>\n";
}

const BadUrdf kBadUrdfs[] = {
    // 50,000 levels overflowed TinyXML's stack (SIGSEGV); refused before it parses.
    {"nested_too_deep", nested(50000), "URDF_MALFORMED_XML", "", "line 258: elements nest more than 256 deep"},
    {"nested_one_too_deep", nested(256), "URDF_MALFORMED_XML", "", "line 258: elements nest more than 256 deep"},
    // TinyXML ends a declaration or a processing instruction at its first '>' and parses what
    // follows as elements: nesting hidden in a DOCTYPE's subset or after '<?pi >' is counted.
    {"nested_after_a_doctype_subset", "<!DOCTYPE robot [\n" + nested(300) + "]>\n", "URDF_MALFORMED_XML", "",
     "elements nest more than 256 deep"},
    {"nested_after_a_processing_instruction", "<?pi >\n" + nested(300) + "?>\n", "URDF_MALFORMED_XML", "",
     "elements nest more than 256 deep"},
    // Sizes whose volume overflows double failed inside the glTF the import builds.
    {"box_beyond_any_robot", link_urdf(visual("<box size=\"1e200 1e200 1e200\"/>")), "URDF_INVALID_NUMBER",
     "/robot/link[@name='a']/visual[1]/geometry/box/@size", "'1e200' is over 1e9 m"},
    {"mesh_scale_beyond_any_robot",
     link_urdf(visual("<mesh filename=\"junk.stl\" scale=\"1 1e300 1\"/>")), "URDF_INVALID_NUMBER",
     "/robot/link[@name='a']/visual[1]/geometry/mesh/@scale", "'1e300' is over 1e9"},
    // A xacro file given as a URDF: the macro's link would be lost without a word.
    {"xacro_file",
     "<robot name=\"r\" xmlns:xacro=\"http://www.ros.org/wiki/xacro\">\n<link name=\"a\"/>\n"
     "<xacro:macro name=\"m\"><link name=\"b\"/></xacro:macro>\n<xacro:m/>\n</robot>\n",
     "URDF_INVALID", "", "line 3: <xacro:macro>: this is a xacro file, not a URDF"},
    // A xacro file's text saved as .urdf with no xacro element left, only its substitutions:
    // counting the pieces of "$(optenv X 0) 0 0" said "3 numbers expected, 5 found".
    // A model given to import instead of convert: "line 0: column 0: malformed XML: Error
    // document empty", and for a GLB "byte 0xF0 is not UTF-8".
    {"gltf_given_as_urdf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": []}\n", "URDF_NOT_A_ROBOT", "",
     "this is a glTF file (JSON), not a URDF (an XML <robot> element): rdtf convert reads it"},
    {"glb_given_as_urdf", std::string("glTF\x02\x00\x00\x00\x14\x00\x00\x00\xf0\x00\x00\x00", 16),
     "URDF_NOT_A_ROBOT", "", "this is a GLB (binary glTF) file, not a URDF"},
    // A mesh or a text that is no XML at all: TinyXML said "line 0: Error document empty".
    {"ascii_stl_given_as_urdf", "solid cube\nfacet normal 0 0 1\n", "URDF_NOT_A_ROBOT", "",
     "this is an STL mesh (ASCII), not a URDF (an XML <robot> element): a URDF names its meshes in <mesh filename="},
    {"binary_stl_given_as_urdf", std::string(80, 'x') + std::string("\x01\x00\x00\x00", 4) + std::string(50, '\0'),
     "URDF_NOT_A_ROBOT", "", "this is a binary STL mesh, not a URDF"},
    {"not_xml", "\xEF\xBB\xBF\n  robot: r\n", "URDF_NOT_A_ROBOT", "",
     "this is not XML: it starts with 'robot: r' where a URDF (an XML <robot> element) starts with '<'"},
    {"not_xml_binary", std::string("\x01\xDD \x00", 4), "URDF_NOT_A_ROBOT", "",
     "this is not XML: it starts with the bytes 0x01 0xDD 0x20 0x00 where"},
    // XML in UTF-16 is XML: the UTF-8 check names it, not "not XML".
    {"utf16_little_endian", std::string("\xFF\xFE<\0r\0", 6), "URDF_NOT_UTF8", "",
     "the file is XML in UTF-16 (little-endian), which is not UTF-8"},
    {"utf16_big_endian_without_a_mark", std::string("\0<\0r", 4), "URDF_NOT_UTF8", "", "XML in UTF-16 (big-endian)"},
    // One of each where URDF has one: urdfdom reads the first and drops the rest without a word.
    {"two_inertials", link_urdf(inertial("1") + "\n" + inertial("50")), "URDF_INVALID",
     "/robot/link[@name='a']/inertial[2]",
     "line 4: <link> has a second <inertial> (the first is on line 3): URDF allows one"},
    {"two_parents", joint_urdf("<parent link=\"b\"/>\n" + kLimit), "URDF_INVALID", "/robot/joint[@name='j']/parent[2]",
     "line 5: <joint> has a second <parent> (the first is on line 4)"},
    {"two_masses", link_urdf("<inertial><mass value=\"1\"/>\n<mass value=\"2\"/>" + kInertia + "</inertial>"),
     "URDF_INVALID", "/robot/link[@name='a']/inertial/mass[2]", "line 4: <inertial> has a second <mass>"},
    {"second_robot", "<robot name=\"r\"><link name=\"a\"/></robot>\n<robot name=\"s\"><link name=\"b\"/></robot>\n",
     "URDF_MALFORMED_XML", "", "line 2: a second root element <robot> after </robot>"},
    {"text_after_the_robot", "<robot name=\"r\"><link name=\"a\"/></robot>\n<!-- fine -->\ntrailing <junk>\n",
     "URDF_MALFORMED_XML", "", "line 3: text after </robot> ('trailing <junk>"},
    // urdfdom refuses it too, but named the line of the last one.
    {"material_named_twice",
     "<robot name=\"r\">\n<material name=\"m\"/>\n<material name=\"m\"/>\n<link name=\"a\"/>\n</robot>\n",
     "URDF_DUPLICATE_NAME", "/robot/material[@name='m']", "line 3: a second material is named 'm' (the first is on line 2)"},
    {"text_after_the_robot_without_a_tag", "<robot name=\"r\"><link name=\"a\"/></robot>\njunk\n",
     "URDF_MALFORMED_XML", "", "line 2: text after </robot> ('junk')"},
    {"xacro_argument_in_a_number", joint_urdf("<origin xyz=\"$(optenv X 0) 0 0\"/>\n" + kLimit),
     "URDF_INVALID_NUMBER", "/robot/joint[@name='j']/origin/@xyz",
     "line 5: <origin xyz=\"$(optenv X 0) 0 0\">: '$(optenv X 0)' is a xacro expression, not a number: expand the file "
     "with xacro first"},
    {"xacro_property_in_a_number", joint_urdf("<origin rpy=\"0 0 ${pi/2}\"/>\n" + kLimit), "URDF_INVALID_NUMBER",
     "/robot/joint[@name='j']/origin/@rpy", "'${pi/2}' is a xacro expression, not a number"},
    {"xacro_find_in_a_mesh", link_urdf(visual("<mesh filename=\"$(find my_pkg)/meshes/base.stl\"/>")),
     "URDF_MESH_NOT_FOUND", "/robot/link[@name='a']/visual[1]",
     "line 3: mesh file '$(find my_pkg)/meshes/base.stl' holds a xacro expression: expand the file with xacro first"},
    {"missing mesh",
     "<robot name=\"r\">\n<link name=\"a\">\n<visual><geometry><mesh filename=\"meshes/gone.stl\"/></geometry></visual>\n"
     "</link>\n</robot>\n",
     "URDF_MESH_NOT_FOUND", "/robot/link[@name='a']/visual[1]", "line 3: mesh file 'meshes/gone.stl' not found"},
    // There, but no file: a FIFO would block the read for ever, a folder has no bytes.
    {"mesh that is a fifo", link_urdf(visual("<mesh filename=\"pipe.stl\"/>")), "URDF_MESH_NOT_FOUND",
     "/robot/link[@name='a']/visual[1]", "pipe.stl is a FIFO (named pipe), not a file rdtf reads"},
    {"mesh that is a folder", link_urdf(visual("<mesh filename=\"folder.stl\"/>")), "URDF_MESH_NOT_FOUND",
     "/robot/link[@name='a']/visual[1]", "line 3: mesh file 'folder.stl': "},
    {"not an stl",
     "<robot name=\"r\">\n<link name=\"a\">\n<visual><geometry><mesh filename=\"junk.stl\"/></geometry></visual>\n"
     "</link>\n</robot>\n",
     "URDF_MESH_INVALID", "/robot/link[@name='a']/visual[1]", "junk.stl"},
    {"malformed xml", "<robot name=\"r\">\n<link name=\"a\">\n</robot>\n", "URDF_MALFORMED_XML", "", "malformed XML"},
    // Not TinyXML's "line 0: column 0: ... Error document empty".
    {"empty file", "", "URDF_MALFORMED_XML", "", "the file is empty (0 bytes): a URDF is one <robot> element"},
    {"only whitespace", "\n \t\r\n", "URDF_MALFORMED_XML", "", "the file holds only whitespace (5 bytes)"},
    {"only a byte order mark", "\xEF\xBB\xBF\r\n", "URDF_MALFORMED_XML", "",
     "the file holds only a byte order mark and whitespace (5 bytes)"},
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
    // Numbers urdfdom reads leniently (a mass of "abc" became 0, a box with "abc" vanished): each
    // is read from the XML and refused at its attribute, with its line.
    {"negative mass", link_urdf(inertial("-2")), "URDF_INVALID_INERTIAL", "/robot/link[@name='a']/inertial/mass/@value",
     "line 3: <mass value=\"-2\">: '-2' is negative: a mass is 0 or more"},
    {"mass not a number", link_urdf(inertial("abc")), "URDF_INVALID_INERTIAL",
     "/robot/link[@name='a']/inertial/mass/@value", "line 3: <mass value=\"abc\">: 'abc' is not a number"},
    {"mass nan", link_urdf(inertial("nan")), "URDF_INVALID_INERTIAL", "/robot/link[@name='a']/inertial/mass/@value",
     "line 3: <mass value=\"nan\">: 'nan' is not a finite number"},
    {"mass inf", link_urdf(inertial("inf")), "URDF_INVALID_INERTIAL", "/robot/link[@name='a']/inertial/mass/@value",
     "'inf' is not a finite number"},
    {"mass beyond double", link_urdf(inertial("1e999")), "URDF_INVALID_INERTIAL",
     "/robot/link[@name='a']/inertial/mass/@value", "'1e999' is beyond the range of a double"},
    {"mass with trailing garbage", link_urdf(inertial("2kg")), "URDF_INVALID_INERTIAL",
     "/robot/link[@name='a']/inertial/mass/@value", "'2kg' is not a number"},
    {"inertia not finite",
     link_urdf(inertial("1", "<inertia ixx=\"inf\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/>")),
     "URDF_INVALID_INERTIAL", "/robot/link[@name='a']/inertial/inertia/@ixx", "line 3: <inertia ixx=\"inf\">"},
    // No body has a negative moment; a product of inertia may be negative (s100err D7).
    {"negative moment of inertia",
     link_urdf(inertial("1", "<inertia ixx=\"-0.5\" ixy=\"-0.1\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/>")),
     "URDF_INVALID_INERTIAL", "/robot/link[@name='a']/inertial/inertia/@ixx",
     "line 3: <inertia ixx=\"-0.5\">: '-0.5' is negative: a moment of inertia is 0 or more"},
    {"negative moment beyond rounding only",
     link_urdf(inertial("1", "<inertia ixx=\"1e-30\" ixy=\"0\" ixz=\"0\" iyy=\"-2e-3\" iyz=\"0\" izz=\"1\"/>")),
     "URDF_INVALID_INERTIAL", "/robot/link[@name='a']/inertial/inertia/@iyy", "'-2e-3' is negative"},
    {"inertia term missing", link_urdf(inertial("1", "<inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\"/>")),
     "URDF_INVALID_INERTIAL", "/robot/link[@name='a']/inertial/inertia", "<inertia> has no izz attribute"},
    {"inertial without mass", link_urdf("<inertial>" + kInertia + "</inertial>"), "URDF_INVALID_INERTIAL",
     "/robot/link[@name='a']/inertial", "line 3: <inertial> has no <mass"},
    {"inertial origin not finite",
     link_urdf("<inertial><origin xyz=\"0 nan 0\"/><mass value=\"1\"/>" + kInertia + "</inertial>"),
     "URDF_INVALID_INERTIAL", "/robot/link[@name='a']/inertial/origin/@xyz", "'nan' is not a finite number"},
    {"box size not a number", link_urdf(visual("<box size=\"0.1 abc 0.1\"/>")), "URDF_INVALID_NUMBER",
     "/robot/link[@name='a']/visual[1]/geometry/box/@size", "line 3: <box size=\"0.1 abc 0.1\">: 'abc' is not a number"},
    {"box size of two numbers", link_urdf(visual("<box size=\"0.1 0.1\"/>")), "URDF_INVALID_NUMBER",
     "/robot/link[@name='a']/visual[1]/geometry/box/@size", "3 numbers separated by spaces expected, 2 found"},
    {"box size negative", link_urdf(visual("<box size=\"0.1 -1 0.1\"/>")), "URDF_INVALID_NUMBER",
     "/robot/link[@name='a']/visual[1]/geometry/box/@size", "'-1' is negative: a box size is 0 or more"},
    {"box without size", link_urdf(visual("<box/>")), "URDF_INVALID",
     "/robot/link[@name='a']/visual[1]/geometry/box", "<box> has no size attribute"},
    {"cylinder radius negative", link_urdf(visual("<cylinder radius=\"-0.1\" length=\"1\"/>")),
     "URDF_INVALID_NUMBER", "/robot/link[@name='a']/visual[1]/geometry/cylinder/@radius", "'-0.1' is negative"},
    {"sphere radius nan", link_urdf(visual("<sphere radius=\"nan\"/>")), "URDF_INVALID_NUMBER",
     "/robot/link[@name='a']/visual[1]/geometry/sphere/@radius", "'nan' is not a finite number"},
    {"mesh scale zero", link_urdf(visual("<mesh filename=\"junk.stl\" scale=\"1 0 1\"/>")), "URDF_INVALID_NUMBER",
     "/robot/link[@name='a']/visual[1]/geometry/mesh/@scale", "'0' is zero"},
    {"second collision bad",
     link_urdf("<collision><geometry><box size=\"1 1 1\"/></geometry></collision>"
               "<collision><origin rpy=\"0 abc 0\"/><geometry><box size=\"1 1 1\"/></geometry></collision>"),
     "URDF_INVALID_NUMBER", "/robot/link[@name='a']/collision[2]/origin/@rpy", "'abc' is not a number"},
    {"unknown shape", link_urdf(visual("<capsule radius=\"1\" length=\"1\"/>")), "URDF_INVALID",
     "/robot/link[@name='a']/visual[1]/geometry/capsule", "<capsule> is no URDF shape"},
    {"empty geometry", link_urdf(visual("")), "URDF_INVALID", "/robot/link[@name='a']/visual[1]/geometry",
     "<geometry> holds no shape"},
    {"colour out of range",
     link_urdf("<visual><geometry><box size=\"1 1 1\"/></geometry><material name=\"m\"><color rgba=\"2 0 0 1\"/>"
               "</material></visual>"),
     "URDF_INVALID_NUMBER", "/robot/link[@name='a']/visual[1]/material/color/@rgba", "'2' is outside 0..1"},
    {"top-level colour of three numbers",
     "<robot name=\"r\">\n<material name=\"red\"><color rgba=\"1 0 0\"/></material>\n<link name=\"a\"/>\n</robot>\n",
     "URDF_INVALID_NUMBER", "/robot/material[@name='red']/color/@rgba", "line 2: <color rgba=\"1 0 0\">"},
    // Joints (urdfdom refused these with a message pointing at /robot and no line).
    {"joint origin nan", joint_urdf("<origin xyz=\"nan 0 0\"/>" + kLimit), "URDF_INVALID_NUMBER",
     "/robot/joint[@name='j']/origin/@xyz", "line 5: <origin xyz=\"nan 0 0\">: 'nan' is not a finite number"},
    {"axis nan", joint_urdf("<axis xyz=\"0 0 nan\"/>" + kLimit), "URDF_INVALID_NUMBER",
     "/robot/joint[@name='j']/axis/@xyz", "line 5: <axis xyz=\"0 0 nan\">: 'nan' is not a finite number"},
    {"axis zero", joint_urdf("<axis xyz=\"0 0 0\"/>" + kLimit), "URDF_INVALID_NUMBER",
     "/robot/joint[@name='j']/axis/@xyz", "line 5: <axis xyz=\"0 0 0\">: the zero vector is no direction"},
    {"axis without xyz", joint_urdf("<axis/>", "continuous"), "URDF_INVALID", "/robot/joint[@name='j']/axis",
     "<axis> has no xyz attribute"},
    {"lower not a number",
     joint_urdf("<limit lower=\"abc\" upper=\"1\" effort=\"1\" velocity=\"1\"/>"), "URDF_INVALID_NUMBER",
     "/robot/joint[@name='j']/limit/@lower", "line 5: <limit lower=\"abc\">: 'abc' is not a number"},
    {"effort negative", joint_urdf("<limit lower=\"-1\" upper=\"1\" effort=\"-5\" velocity=\"1\"/>"),
     "URDF_INVALID_NUMBER", "/robot/joint[@name='j']/limit/@effort", "'-5' is negative: an effort limit is 0 or more"},
    {"velocity infinite", joint_urdf("<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"inf\"/>"),
     "URDF_INVALID_NUMBER", "/robot/joint[@name='j']/limit/@velocity", "'inf' is not a finite number"},
    {"limits inverted", joint_urdf("<limit lower=\"1\" upper=\"-1\" effort=\"1\" velocity=\"1\"/>"),
     "URDF_INVALID_NUMBER", "/robot/joint[@name='j']/limit",
     "line 5: <limit>: lower 1 is above upper -1 (pybullet reads that as no limits; URDF has no such convention: "
     "make it type=\"continuous\" if it turns freely)"},
    {"prismatic limits inverted",
     joint_urdf("<axis xyz=\"1 0 0\"/><limit lower=\"1\" upper=\"-1\" effort=\"1\" velocity=\"1\"/>", "prismatic"),
     "URDF_INVALID_NUMBER", "/robot/joint[@name='j']/limit",
     "lower 1 is above upper -1 (pybullet reads that as no limits; URDF has no such convention: give its range of "
     "travel (URDF requires one))"},
    {"limit without effort", joint_urdf("<limit lower=\"-1\" upper=\"1\" velocity=\"1\"/>"), "URDF_INVALID",
     "/robot/joint[@name='j']/limit", "line 5: <limit> has no effort attribute"},
    {"revolute without limit", joint_urdf("<axis xyz=\"0 0 1\"/>"), "URDF_INVALID", "/robot/joint[@name='j']",
     "line 4: joint 'j' is revolute and has no <limit"},
    {"negative damping", joint_urdf(kLimit + "<dynamics damping=\"-1\"/>"), "URDF_INVALID_NUMBER",
     "/robot/joint[@name='j']/dynamics/@damping", "'-1' is negative: damping is 0 or more"},
    {"negative friction", joint_urdf("<dynamics friction=\"-0.5\"/>", "continuous"), "URDF_INVALID_NUMBER",
     "/robot/joint[@name='j']/dynamics/@friction", "'-0.5' is negative: friction is 0 or more"},
    {"mimic multiplier not a number", joint_urdf(kLimit + "<mimic joint=\"j\" multiplier=\"x\"/>"),
     "URDF_INVALID_NUMBER", "/robot/joint[@name='j']/mimic/@multiplier", "'x' is not a number"},
    // What urdfdom alone refuses: its message, at the element it names, with the line.
    {"robot without a name", "<robot>\n<link name=\"a\"/>\n</robot>\n", "URDF_PARSE_FAILED", "/robot",
     "line 1: urdfdom cannot read it: No name given for the robot"},
    // Names become glTF names, which JSON needs in UTF-8 (found by fuzzing: a crash, then an
    // internal error).
    {"name_not_utf8", "<robot name=\"r\">\n<link name=\"a\x92"
                      "b\"/>\n</robot>\n", "URDF_NOT_UTF8", "",
     "line 2, column 14 (byte 31): byte 0x92 is not UTF-8"},
    {"truncated_utf8_sequence", "<robot name=\"r\">\n<link name=\"caf\xC3\"/>\n</robot>\n", "URDF_NOT_UTF8", "",
     "line 2, column 16 (byte 33): byte 0xC3 is not UTF-8"},
    {"surrogate_character_reference", "<robot name=\"r\">\n<link name=\"a&#xD800;\"/>\n</robot>\n", "URDF_NOT_UTF8",
     "", "line 2, column 14 (byte 31): the character reference '&#xD800;' is not a Unicode character"},
    {"character_reference_beyond_unicode", "<robot name=\"r\">\n<link name=\"a&#1114112;\"/>\n</robot>\n",
     "URDF_NOT_UTF8", "", "the character reference '&#1114112;' is not a Unicode character"},
};

class UrdfImportErrors : public ::testing::TestWithParam<BadUrdf> {};

TEST_P(UrdfImportErrors, ClearErrorAndNoOutput) {
  const BadUrdf& bad = GetParam();
  TempDir dir;
  const fs::path urdf = dir / "robot.urdf";
  testing::write_file(urdf, bad.text);
  testing::write_file(dir / "junk.stl", "this is no STL file");
  ASSERT_EQ(::mkfifo((dir / "pipe.stl").c_str(), 0644), 0);
  fs::create_directory(dir / "folder.stl");

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
  // Exactly the attribute where one is named (the table gives whole attribute pointers).
  if (bad.pointer.find("/@") != std::string::npos) {
    EXPECT_EQ(found->pointer, bad.pointer);
  }
  EXPECT_NE(found->message.find(bad.says), std::string::npos) << found->message;
  // The element's line is a field of its own (JSON "line", LCM diagnostic_t.line) whenever the
  // message names it as "line N: ".
  std::smatch line;
  if (std::regex_search(found->message, line, std::regex("^line ([0-9]+): "))) {
    EXPECT_EQ(found->line, std::stoi(line[1].str())) << found->message;
  } else {
    EXPECT_EQ(found->line, 0) << found->message;
  }

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

// A published robot without its mesh package, or with a mesh that is no STL: where the link's
// mass is its <inertial>, the mesh is a warning naming it, and the robot is imported with that mass
// (it used to stop the import). Without an <inertial> it stays the error above: the mass would
// come from the mesh.
void expect_unusable_mesh_is_a_warning(const std::string& code, const std::function<void(const fs::path&)>& make_mesh) {
  TempDir dir;
  const fs::path urdf = dir / "robot.urdf";
  make_mesh(dir.path());
  testing::write_file(urdf, link_urdf(inertial("2.5") + "\n<visual><geometry><mesh filename=\"package://arm/meshes/base.STL\"/></geometry></visual>"));
  Diagnostics diag;
  const auto conversion = import_urdf(urdf, UrdfImportOptions{}, diag);
  ASSERT_TRUE(conversion);
  const Diagnostic* found = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == code) found = &d;
  }
  ASSERT_NE(found, nullptr);
  EXPECT_EQ(found->severity, Severity::kWarning);
  EXPECT_EQ(found->pointer, "/robot/link[@name='a']/visual[1]");
  EXPECT_NE(found->message.find("base.STL"), std::string::npos) << found->message;
  EXPECT_NE(found->message.find("the link's mass is its <inertial>"), std::string::npos) << found->message;
  ASSERT_EQ(conversion->robot.links.size(), 1u);
  EXPECT_EQ(conversion->robot.links[0].inertial.mass, 2.5);

  const testing::CommandResult run = testing::run_command("'" + testing::cli_path() + "' import '" + urdf.string() +
                                                          "' -o '" + (dir / "out.gltf").string() + "'");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("warning " + code), std::string::npos) << run.err;
  EXPECT_TRUE(fs::exists(dir / "out.gltf"));
}

// A moment a rounding below 0 (an exporter's -1e-30 for a thin rod's own axis) is no error.
TEST(UrdfImportErrors, AMomentARoundingBelowZeroIsAccepted) {
  TempDir dir;
  const fs::path urdf = dir / "robot.urdf";
  testing::write_file(urdf, link_urdf(inertial("1", "<inertia ixx=\"-1e-30\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/>")));
  Diagnostics diag;
  import_urdf(urdf, UrdfImportOptions{}, diag);
  for (const Diagnostic& d : diag.all()) EXPECT_NE(d.code, "URDF_INVALID_INERTIAL") << d.message;
}

// A sensor frame whose exporter wrote zero as noise (Unitree's z1: ixx="-1e-30" beside moments of
// 1e-30) is judged against the robot's inertias, not its own noise: accepted. A moment below 0 by
// more than a rounding of the robot's largest term is still refused.
TEST(UrdfImportErrors, ANoiseTensorOfAFrameIsJudgedAgainstTheRobot) {
  const auto urdf_with_frame = [](const std::string& frame_ixx) {
    return "<robot name=\"r\">\n"
           "<link name=\"base\"><inertial><mass value=\"2\"/>"
           "<inertia ixx=\"0.02\" ixy=\"0\" ixz=\"0\" iyy=\"0.03\" iyz=\"0\" izz=\"0.04\"/></inertial></link>\n"
           "<link name=\"camera_frame\"><inertial><mass value=\"1e-6\"/>"
           "<inertia ixx=\"" + frame_ixx + "\" ixy=\"0\" ixz=\"0\" iyy=\"1e-30\" iyz=\"0\" izz=\"1e-30\"/>"
           "</inertial></link>\n"
           "<joint name=\"camera_joint\" type=\"fixed\"><parent link=\"base\"/><child link=\"camera_frame\"/></joint>\n"
           "</robot>\n";
  };
  TempDir dir;
  const fs::path urdf = dir / "robot.urdf";
  testing::write_file(urdf, urdf_with_frame("-1e-30"));
  Diagnostics noise;
  EXPECT_TRUE(import_urdf(urdf, UrdfImportOptions{}, noise).has_value());
  for (const Diagnostic& d : noise.all()) EXPECT_NE(d.code, "URDF_INVALID_INERTIAL") << d.message;

  // 16 eps of the robot's largest term (0.04) is 1.4e-16, 1e-9 of the link's own 1e-10 less:
  // -1e-10 is a sign error, not noise.
  testing::write_file(urdf, urdf_with_frame("-1e-10"));
  Diagnostics negative;
  import_urdf(urdf, UrdfImportOptions{}, negative);
  bool refused = false;
  for (const Diagnostic& d : negative.all()) {
    if (d.code != "URDF_INVALID_INERTIAL") continue;
    refused = true;
    EXPECT_EQ(d.pointer, "/robot/link[@name='camera_frame']/inertial/inertia/@ixx");
    EXPECT_NE(d.message.find("'-1e-10' is negative"), std::string::npos) << d.message;
  }
  EXPECT_TRUE(refused) << "a moment of -1e-10 beside a largest term of 0.04 is no rounding";
  // Nor is -1e-8 on a sensor beside a 100 kg base's 16 kg m^2 (a heavy link licenses no sign error).
  const std::string heavy = "<robot name=\"r\">\n"
                            "<link name=\"base\"><inertial><mass value=\"100\"/>"
                            "<inertia ixx=\"16\" ixy=\"0\" ixz=\"0\" iyy=\"16\" iyz=\"0\" izz=\"16\"/></inertial></link>\n"
                            "<link name=\"sensor\"><inertial><mass value=\"0.01\"/>"
                            "<inertia ixx=\"-1e-8\" ixy=\"0\" ixz=\"0\" iyy=\"1e-8\" iyz=\"0\" izz=\"1e-8\"/>"
                            "</inertial></link>\n"
                            "<joint name=\"sensor_joint\" type=\"fixed\"><parent link=\"base\"/><child link=\"sensor\"/></joint>\n"
                            "</robot>\n";
  testing::write_file(urdf, heavy);
  Diagnostics sign_error;
  EXPECT_FALSE(import_urdf(urdf, UrdfImportOptions{}, sign_error).has_value());
  EXPECT_TRUE(sign_error.contains("URDF_INVALID_INERTIAL"));
}

TEST(UrdfImportErrors, MissingMeshOfALinkWithAnInertialIsAWarning) {
  expect_unusable_mesh_is_a_warning("URDF_MESH_NOT_FOUND", [](const fs::path&) {});
}

// A mesh that is there and readable but cannot be read now (the process is out of descriptors:
// strace makes its open fail with EMFILE) fails the import, exit 2 and no output, even on a link
// with an <inertial>: it was "not found", a warning, and the model went out without its geometry.
TEST(UrdfImportErrors, AMeshThatIsThereButCannotBeReadNowFailsTheImport) {
  TempDir dir;
  // One triangle, binary STL: 80-byte header, count, then normal, three corners and attribute.
  std::string stl(80, '\0');
  const auto put_u32 = [&](std::uint32_t v) { stl.append(reinterpret_cast<const char*>(&v), 4); };
  const auto put_f32 = [&](float v) { stl.append(reinterpret_cast<const char*>(&v), 4); };
  put_u32(1);
  for (const float v : {0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put_f32(v);
  stl.append(2, '\0');
  testing::write_file(dir / "tri.stl", stl);
  testing::write_file(dir / "robot.urdf", link_urdf(inertial("2.5") + visual("<mesh filename=\"tri.stl\"/>")));
  const auto run_import = [&](const std::string& prefix, const std::string& out) {
    return testing::run_command("cd '" + dir.path().string() + "' && " + prefix + "'" + testing::cli_path() +
                                "' import robot.urdf -o " + out);
  };
  testing::CommandResult run = run_import("", "plain.gltf");  // untraced, as the control
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // strace -P matches the path as rdtf passes it to openat: beside a relative URDF, ./tri.stl.
  run = run_import("ASAN_OPTIONS=\"${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0\" strace -f -qq -o /dev/null "
                   "-P ./tri.stl -e trace=openat -e inject=openat:error=EMFILE ",
                   "out.gltf");
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find("error URDF_READ_FAILED"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("too many open files"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("/robot/link[@name='a']/visual[1]"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(dir / "out.gltf"));
  EXPECT_FALSE(fs::exists(dir / "out.bin"));
}

TEST(UrdfImportErrors, MeshThatIsNoStlOfALinkWithAnInertialIsAWarning) {
  expect_unusable_mesh_is_a_warning("URDF_MESH_INVALID", [](const fs::path& dir) {
    fs::create_directories(dir / "arm" / "meshes");
    testing::write_file(dir / "arm" / "meshes" / "base.STL", "this is no STL file");
  });
}

// A camera frame without <inertial> on a fixed joint is massless, as URDF reads it: its missing
// mesh is only its look, a warning, not the error of a link whose mass would come from it (which
// contradicted the info beside it, "it is massless").
TEST(UrdfImportErrors, MissingMeshOfAMasslessFixedLinkIsAWarning) {
  TempDir dir;
  const fs::path urdf = dir / "robot.urdf";
  testing::write_file(urdf, "<robot name=\"r\">\n<link name=\"a\">" + inertial("2.5") + visual("<box size=\"0.1 0.1 0.1\"/>") +
                                "</link>\n<link name=\"camera\">" +
                                visual("<mesh filename=\"package://cam/meshes/camera.stl\"/>") +
                                "</link>\n<joint name=\"cam_joint\" type=\"fixed\"><parent link=\"a\"/><child "
                                "link=\"camera\"/></joint>\n</robot>\n");
  Diagnostics diag;
  const auto conversion = import_urdf(urdf, UrdfImportOptions{}, diag);
  ASSERT_TRUE(conversion) << (diag.all().empty() ? std::string() : format(diag.all().front()));
  const Diagnostic* found = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == "URDF_MESH_NOT_FOUND") found = &d;
  }
  ASSERT_NE(found, nullptr);
  EXPECT_EQ(found->severity, Severity::kWarning);
  EXPECT_EQ(found->pointer, "/robot/link[@name='camera']/visual[1]");
  EXPECT_NE(found->message.find("massless on its fixed joint"), std::string::npos) << found->message;
  // Every place looked in, whole (it said "looked for ./cam/meshes/camera.stl and 1 other places").
  EXPECT_NE(found->message.find("(looked for " + fs::absolute(dir / "cam" / "meshes" / "camera.stl").lexically_normal().string()),
            std::string::npos)
      << found->message;
  EXPECT_EQ(found->message.find("other places"), std::string::npos) << found->message;
}

// UR, Fetch and TIAGo descriptions give COLLADA visuals and STL collision meshes. A link whose
// mass comes from its geometry takes its <collision> where a <visual> cannot be read (it came out
// massless, and the gate refused the robot); one with an <inertial> shows its <collision> where no
// <visual> can be read (it showed nothing).
TEST(UrdfImportErrors, UnreadableVisualsGiveWayToTheCollisionGeometry) {
  TempDir dir;
  const fs::path urdf = dir / "robot.urdf";
  const std::string collision = "<collision><geometry><box size=\"0.1 0.2 0.3\"/></geometry></collision>";
  testing::write_file(urdf, "<robot name=\"r\">\n<link name=\"a\">" + inertial("2.5") +
                                visual("<mesh filename=\"package://arm/meshes/base.dae\"/>") + collision +
                                "</link>\n<link name=\"b\">" + visual("<mesh filename=\"package://arm/meshes/upper.dae\"/>") +
                                collision + "</link>\n<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child "
                                "link=\"b\"/>" + kLimit + "</joint>\n</robot>\n");
  Diagnostics diag;
  const auto conversion = import_urdf(urdf, UrdfImportOptions{}, diag);
  ASSERT_TRUE(conversion) << (diag.all().empty() ? std::string() : format(diag.all().front()));
  std::vector<const Diagnostic*> found;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == "URDF_COLLISION_AS_VISUAL") found.push_back(&d);
    EXPECT_NE(d.code, "URDF_MESH_FORMAT_UNSUPPORTED") << d.message;
  }
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0]->pointer, "/robot/link[@name='a']");
  EXPECT_NE(found[0]->message.find("<visual> 1 ('package://arm/meshes/base.dae')"), std::string::npos) << found[0]->message;
  EXPECT_NE(found[0]->message.find("nor any other <visual>"), std::string::npos) << found[0]->message;
  EXPECT_EQ(found[1]->pointer, "/robot/link[@name='b']");
  EXPECT_NE(found[1]->message.find("the link's mass comes from its geometry"), std::string::npos) << found[1]->message;
  const Robot& robot = conversion->robot;
  ASSERT_EQ(robot.links.size(), 2u);
  EXPECT_EQ(robot.links[0].inertial.mass, 2.5);  // Its <inertial>: the box only shows it.
  EXPECT_EQ(conversion->asset.document["meshes"].size(), 2u);
  // The box at the default 1000 kg/m^3: 6 kg, to the float32 rounding of its three edges (each
  // within 2^-24 relative, so the volume within 3 * 2^-24 < 2e-7).
  EXPECT_NEAR(robot.links[1].inertial.mass, 6.0, 6.0 * 2e-7);
}

// What may follow the root: white space, comments (one holding "</robot>" too), processing
// instructions; and an end tag written "</robot  >". Each imports.
TEST(UrdfImportErrors, CommentsAndInstructionsAfterTheRobotAreFine) {
  for (const std::string& text : {std::string("<robot name=\"r\"><link name=\"a\"/></robot>\n<!-- ended with </robot> -->\n"),
                                 std::string("<robot name=\"r\"><!-- </robot> --><link name=\"a\"/></robot  >\n"),
                                 std::string("<robot name=\"r\"><link name=\"a\"/></robot>\n<?xml-stylesheet href=\"x\"?>\n")}) {
    TempDir dir;
    testing::write_file(dir / "robot.urdf", text);
    Diagnostics diag;
    EXPECT_TRUE(import_urdf(dir / "robot.urdf", UrdfImportOptions{}, diag))
        << text << (diag.all().empty() ? std::string() : format(diag.all().front()));
  }
}

// A COLLADA visual and a collision STL, neither there: the link shows nothing, and the missing
// collision mesh, which would have stood in, went unmentioned (z1's gripper).
TEST(UrdfImportErrors, AMissingCollisionMeshThatWouldStandInIsNamed) {
  TempDir dir;
  const fs::path urdf = dir / "robot.urdf";
  testing::write_file(urdf, "<robot name=\"r\">\n<link name=\"a\">" + inertial("2.5") +
                                visual("<mesh filename=\"meshes/a.dae\"/>") +
                                "\n<collision><geometry><mesh filename=\"meshes/a_collision.STL\"/></geometry></collision>"
                                "</link>\n</robot>\n");
  Diagnostics diag;
  ASSERT_TRUE(import_urdf(urdf, UrdfImportOptions{}, diag));
  // Both meshes are named as missing: the visual's (it is only the link's look) and the collision
  // mesh that would have stood in.
  const Diagnostic* found = nullptr;
  const Diagnostic* visual_missing = nullptr;
  for (const Diagnostic& d : diag.all()) {
    if (d.code != "URDF_MESH_NOT_FOUND") continue;
    (d.pointer == "/robot/link[@name='a']/collision[1]" ? found : visual_missing) = &d;
  }
  ASSERT_NE(visual_missing, nullptr);
  EXPECT_EQ(visual_missing->pointer, "/robot/link[@name='a']/visual[1]");
  EXPECT_NE(visual_missing->message.find("mesh file 'meshes/a.dae' not found"), std::string::npos) << visual_missing->message;
  ASSERT_NE(found, nullptr);
  EXPECT_EQ(found->severity, Severity::kWarning);
  EXPECT_EQ(found->line, 3);
  EXPECT_NE(found->message.find("its <collision> mesh 'meshes/a_collision.STL', which would stand in, cannot be read: "
                                "mesh file 'meshes/a_collision.STL' not found"),
            std::string::npos)
      << found->message;
}

// Why the URDF cannot be read, in the user's terms: missing, a folder, unreadable (it used to say
// "not a regular file" for all of them).
void expect_read_failure(const fs::path& urdf, const std::string& why) {
  Diagnostics diag;
  EXPECT_FALSE(import_urdf(urdf, UrdfImportOptions{}, diag));
  ASSERT_EQ(diag.all().size(), 1u);
  EXPECT_EQ(diag.all()[0].code, "URDF_READ_FAILED");
  EXPECT_EQ(diag.all()[0].message, "cannot read " + urdf.string() + ": " + why);

  TempDir out;
  const testing::CommandResult run = testing::run_command("'" + testing::cli_path() + "' import '" + urdf.string() +
                                                          "' -o '" + (out / "out.gltf").string() + "'");
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find(urdf.string() + ": error URDF_READ_FAILED: cannot read " + urdf.string() + ": " + why),
            std::string::npos)
      << run.err;
  EXPECT_TRUE(fs::is_empty(out.path()));
}

TEST(UrdfImportErrorsCli, MissingInputFileIsNoSuchFile) {
  TempDir dir;
  expect_read_failure(dir / "nope.urdf", "no such file");
}

TEST(UrdfImportErrorsCli, DanglingSymbolicLinkIsNoSuchFile) {
  TempDir dir;
  fs::create_symlink(dir / "gone.urdf", dir / "robot.urdf");
  expect_read_failure(dir / "robot.urdf", "no such file (a symbolic link to nothing)");
}

TEST(UrdfImportErrorsCli, FolderIsNotAFile) {
  TempDir dir;
  fs::create_directory(dir / "robot.urdf");
  expect_read_failure(dir / "robot.urdf", "it is a folder, not a file");
}

TEST(UrdfImportErrorsCli, FifoIsRefusedWithoutBlocking) {
  TempDir dir;
  ASSERT_EQ(::mkfifo((dir / "robot.urdf").c_str(), 0600), 0);
  expect_read_failure(dir / "robot.urdf", "it is a FIFO, not a regular file");
}

TEST(UrdfImportErrorsCli, UnreadableFileSaysPermissionDenied) {
  TempDir dir;
  testing::write_file(dir / "robot.urdf", "<robot name=\"r\"><link name=\"a\"/></robot>\n");
  fs::permissions(dir / "robot.urdf", fs::perms::none);
  if (::geteuid() != 0) {
    expect_read_failure(dir / "robot.urdf", "permission denied");
    return;
  }
  // root reads any file (CI runs as root): the check runs in a child that has become the user
  // nobody, its failures printed there and reported here through its exit status.
  fs::permissions(dir.path(), fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                                  fs::perms::others_read | fs::perms::others_exec);
  std::fflush(nullptr);
  const pid_t child = ::fork();
  ASSERT_NE(child, -1);
  if (child == 0) {
    constexpr uid_t kNobody = 65534;
    if (::setgroups(0, nullptr) != 0 || ::setgid(kNobody) != 0 || ::setuid(kNobody) != 0) ::_exit(3);
    expect_read_failure(dir / "robot.urdf", "permission denied");
    std::fflush(nullptr);
    ::_exit(::testing::Test::HasFailure() ? 1 : 0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "the check as user nobody failed (3: could not become nobody)";
}

// What a file is instead is told from its first bytes, before it is read whole: a GLB over the size
// limit is named as a GLB (not FILE_TOO_LARGE after reading it), and 300 MB of a mesh are not read.
TEST(UrdfImportErrors, AFileThatIsNoUrdfIsToldFromItsFirstBytes) {
  TempDir dir;
  testing::write_file(dir / "robot.urdf", std::string("glTF\x02\x00\x00\x00", 8) + std::string(4096, '\0'));
  UrdfImportOptions options;
  options.convert.limits.max_file_bytes = 1024;
  Diagnostics diag;
  EXPECT_FALSE(import_urdf(dir / "robot.urdf", options, diag));
  ASSERT_EQ(diag.all().size(), 1u);
  EXPECT_EQ(diag.all()[0].code, "URDF_NOT_A_ROBOT");
  EXPECT_EQ(diag.all()[0].message,
            "this is a GLB (binary glTF) file, not a URDF (an XML <robot> element): rdtf convert reads it");
  // A URDF over the limit is still refused for its size.
  testing::write_file(dir / "big.urdf", "<robot name=\"r\">" + std::string(2048, ' ') + "</robot>\n");
  Diagnostics big;
  EXPECT_FALSE(import_urdf(dir / "big.urdf", options, big));
  ASSERT_EQ(big.all().size(), 1u);
  EXPECT_EQ(big.all()[0].code, "FILE_TOO_LARGE");
}

// Every bad number is reported, not only the first, each at its own attribute and line.
TEST(UrdfImportErrors, EveryBadNumberIsReported) {
  TempDir dir;
  testing::write_file(dir / "robot.urdf", joint_urdf("<axis xyz=\"0 0 0\"/>\n<limit lower=\"x\" upper=\"1\" effort=\"-1\" "
                                                     "velocity=\"1\"/>\n<dynamics damping=\"-2\" friction=\"nan\"/>"));
  Diagnostics diag;
  EXPECT_FALSE(import_urdf(dir / "robot.urdf", UrdfImportOptions{}, diag));
  std::vector<std::string> places;
  for (const Diagnostic& d : diag.all()) places.push_back(d.code + " " + d.pointer + " " + d.message.substr(0, 7));
  const std::vector<std::string> expected{
      "URDF_INVALID_NUMBER /robot/joint[@name='j']/axis/@xyz line 5:",
      "URDF_INVALID_NUMBER /robot/joint[@name='j']/limit/@lower line 6:",
      "URDF_INVALID_NUMBER /robot/joint[@name='j']/limit/@effort line 6:",
      "URDF_INVALID_NUMBER /robot/joint[@name='j']/dynamics/@damping line 7:",
      "URDF_INVALID_NUMBER /robot/joint[@name='j']/dynamics/@friction line 7:",
  };
  EXPECT_EQ(places, expected);
}

}  // namespace
}  // namespace rdtf
