// COLLADA and OBJ meshes of a URDF, read as RViz and MoveIt read them (docs/urdf.md, "COLLADA and
// OBJ meshes"): node transforms applied, <unit meter> applied exactly, <up_axis> ignored, each
// part in its file's colour or else the <visual>'s. The files are written here, so every expected
// value is a box's closed form.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

#include "rdtf/write.h"

#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using namespace urdf_test;
namespace fs = std::filesystem;

// The shortest decimal that reads back as the same double.
std::string exact_text(double value) { return Json(value).dump(); }

// Writes the import as .gltf and runs the Khronos validator on it: no errors.
void expect_no_validator_errors(const Conversion& conversion, const fs::path& path) {
  Diagnostics diag;
  ASSERT_TRUE(write_rdtf(conversion.asset, path, OutputFormat::kGltf, diag));
  const auto report = testing::khronos_report(path);
  EXPECT_EQ(report["issues"]["numErrors"].get<int>(), 0) << report["issues"].dump(1);
}

// The corners of a box with edges `size` centred at the origin, corner i's bits x = 1, y = 2,
// z = 4, and its 12 outward triangles: the top (+z) face first (2 triangles), then the rest.
std::string box_positions(double sx, double sy, double sz) {
  std::string out;
  for (int i = 0; i < 8; ++i) {
    out += exact_text((i & 1) ? sx / 2 : -sx / 2) + " " + exact_text((i & 2) ? sy / 2 : -sy / 2) + " " +
           exact_text((i & 4) ? sz / 2 : -sz / 2) + " ";
  }
  return out;
}
const char* const kTopFace = "4 5 7 4 7 6";
const char* const kOtherFaces = "0 2 3 0 3 1 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5";

struct ColladaNode {
  std::string matrix;                 // 16 numbers, row-major, as COLLADA writes them.
  std::vector<ColladaNode> children;  // Nested nodes.
  bool box = true;                    // Instances the box geometry.
};

// A COLLADA document: one box geometry of `size` whose top face has material "red" (diffuse
// 1 0 0 1) and whose other faces have "grey" (0.5 0.5 0.5 1), placed by `nodes`.
std::string collada(const std::string& unit, const std::string& up, const std::vector<ColladaNode>& nodes,
                    const Eigen::Vector3d& size = {2, 4, 6}) {
  const auto effect = [](const std::string& name, const std::string& colour) {
    return "<effect id=\"" + name + "-effect\"><profile_COMMON><technique sid=\"common\"><lambert><diffuse><color sid=\"diffuse\">" +
           colour + "</color></diffuse></lambert></technique></profile_COMMON></effect>";
  };
  std::string text = R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset>)" + unit + "<up_axis>" + up + R"(</up_axis></asset>
<library_effects>)" + effect("red", "1 0 0 1") + effect("grey", "0.5 0.5 0.5 1") + R"(</library_effects>
<library_materials><material id="red-material" name="red"><instance_effect url="#red-effect"/></material>
<material id="grey-material" name="grey"><instance_effect url="#grey-effect"/></material></library_materials>
<library_geometries><geometry id="box-mesh" name="box"><mesh>
<source id="box-positions"><float_array id="box-positions-array" count="24">)" +
                     box_positions(size.x(), size.y(), size.z()) + R"(</float_array>
<technique_common><accessor source="#box-positions-array" count="8" stride="3"><param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
<vertices id="box-vertices"><input semantic="POSITION" source="#box-positions"/></vertices>
<triangles material="red-material" count="2"><input semantic="VERTEX" source="#box-vertices" offset="0"/><p>)" +
                     kTopFace + R"(</p></triangles>
<triangles material="grey-material" count="10"><input semantic="VERTEX" source="#box-vertices" offset="0"/><p>)" + kOtherFaces +
                     R"(</p></triangles>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="Scene" name="Scene">
)";
  int id = 0;
  const std::function<void(const ColladaNode&)> write = [&](const ColladaNode& node) {
    const std::string name = "n" + std::to_string(id++);
    text += "<node id=\"" + name + "\" name=\"" + name + "\" type=\"NODE\"><matrix sid=\"transform\">" + node.matrix +
            "</matrix>";
    if (node.box) {
      text += "<instance_geometry url=\"#box-mesh\"><bind_material><technique_common>"
              "<instance_material symbol=\"red-material\" target=\"#red-material\"/>"
              "<instance_material symbol=\"grey-material\" target=\"#grey-material\"/>"
              "</technique_common></bind_material></instance_geometry>";
    }
    for (const ColladaNode& child : node.children) write(child);
    text += "</node>\n";
  };
  for (const ColladaNode& node : nodes) write(node);
  return text + "</visual_scene></library_visual_scenes>\n<scene><instance_visual_scene url=\"#Scene\"/></scene>\n</COLLADA>\n";
}

const std::string kIdentity = "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1";
const std::string kMillimetres = "<unit name=\"millimeter\" meter=\"0.001\"/>";
const std::string kMetres = "<unit name=\"meter\" meter=\"1\"/>";

// A robot of one link 'a' (no <inertial>: its mass is its mesh's at 1000 kg/m^3) drawn by `mesh`
// in the <visual>'s colour "blue" (0 0 1 1); `extra` goes into the link.
std::string one_link(const std::string& mesh, const std::string& extra = "") {
  return "<robot name=\"r\">\n<link name=\"a\">\n<visual><geometry><mesh filename=\"" + mesh +
         "\"/></geometry><material name=\"blue\"><color rgba=\"0 0 1 1\"/></material></visual>\n" + extra +
         "</link>\n</robot>\n";
}

// The float32 rounding the glTF buffer gives each coordinate c (|c| <= extent) moves the volume of
// a box of edges e by at most sum of 2 ulp(extent) / e_i relative, and its centre by ulp(extent):
// ulp(x) <= 2^-23 |x|.
double float_bound(double extent) { return std::ldexp(extent, -23); }

// A box of 2 x 4 x 6 mm placed at (10, 20, 30) mm in a millimetre file: 48 mm^3, 4.8e-5 kg at
// 1000 kg/m^3, its centre at (0.01, 0.02, 0.03) m in the link frame (URDF axes), whatever the
// file's <up_axis> says; the result is the same bit for bit for Z_UP, Y_UP and X_UP.
TEST(UrdfImportMeshes, ColladaUnitIsAppliedAndUpAxisIgnored) {
  std::optional<Robot> first;
  for (const std::string up : {"Z_UP", "Y_UP", "X_UP"}) {
    SCOPED_TRACE(up);
    TempDir dir;
    testing::write_file(dir / "box.dae", collada(kMillimetres, up, {{"1 0 0 10 0 1 0 20 0 0 1 30 0 0 0 1", {}}}));
    testing::write_file(dir / "robot.urdf", one_link("box.dae"));
    Diagnostics diag;
    const Conversion conversion = import_ok(dir / "robot.urdf", diag);
    for (const Diagnostic& d : diag.all()) EXPECT_NE(d.severity, Severity::kError) << format(d);
    const Link& link = conversion.robot.links.at(0);
    const double extent = 0.033;
    const double volume_bound = 2 * float_bound(extent) * (1 / 0.002 + 1 / 0.004 + 1 / 0.006);
    EXPECT_NEAR(link.inertial.mass, 4.8e-5, 4.8e-5 * volume_bound);
    const Eigen::Vector3d center = gltf_to_urdf_axes() * link.inertial.center_of_mass;
    EXPECT_NEAR(center.x(), 0.01, float_bound(extent));
    EXPECT_NEAR(center.y(), 0.02, float_bound(extent));
    EXPECT_NEAR(center.z(), 0.03, float_bound(extent));
    if (!first) {
      first = conversion.robot;
    } else {
      EXPECT_EQ(link.inertial.mass, first->links[0].inertial.mass);
      EXPECT_EQ(link.inertial.center_of_mass, first->links[0].inertial.center_of_mass);
      EXPECT_EQ(link.inertial.inertia, first->links[0].inertial.inertia);
    }
  }
}

// The unit is the file's decimal, not assimp's float of it: 0.001 exactly. A box of 1000 x 1000 x
// 1000 mm corners +-500 (exact in float32) is 1 m^3: 1000 kg to the float32 rounding of 0.5 m.
TEST(UrdfImportMeshes, MillimetresAreScaledByExactlyAThousandth) {
  TempDir dir;
  testing::write_file(dir / "cube.dae", collada(kMillimetres, "Z_UP", {{kIdentity, {}}}, {1000, 1000, 1000}));
  testing::write_file(dir / "robot.urdf", one_link("cube.dae"));
  Diagnostics diag;
  const Conversion conversion = import_ok(dir / "robot.urdf", diag);
  // 0.001 * 500 = 0.5 in double, and 0.5 is a float: the volume is exact.
  EXPECT_EQ(conversion.robot.links[0].inertial.mass, 1000.0);
}

// Each part keeps its file's colour, one primitive per material; the triangles of both parts form
// one closed surface, welded over both.
TEST(UrdfImportMeshes, PartsKeepTheirFilesColours) {
  TempDir dir;
  testing::write_file(dir / "box.dae", collada(kMetres, "Z_UP", {{kIdentity, {}}}));
  testing::write_file(dir / "robot.urdf", one_link("box.dae"));
  Diagnostics diag;
  const Conversion conversion = import_ok(dir / "robot.urdf", diag);
  EXPECT_EQ(find_code(diag, "MESH_OPEN"), nullptr);
  EXPECT_EQ(conversion.robot.links[0].inertial.mass, 48000.0);  // Corners +-1, +-2, +-3: exact.
  const Json& document = conversion.asset.document;
  ASSERT_EQ(document["meshes"].size(), 1u);
  const Json& primitives = document["meshes"][0]["primitives"];
  ASSERT_EQ(primitives.size(), 2u) << primitives.dump();
  std::map<std::string, std::size_t> triangles;  // Colour -> triangles.
  for (const Json& primitive : primitives) {
    ASSERT_TRUE(primitive.contains("material")) << primitive.dump();
    const Json& colour = document["materials"][primitive["material"].get<std::size_t>()]["pbrMetallicRoughness"]["baseColorFactor"];
    triangles[colour.dump()] += document["accessors"][primitive["indices"].get<std::size_t>()]["count"].get<std::size_t>() / 3;
    EXPECT_EQ(primitive["attributes"]["POSITION"], primitives[0]["attributes"]["POSITION"]);
  }
  EXPECT_EQ(Json(triangles).dump(), R"({"[0.5,0.5,0.5,1.0]":10,"[1.0,0.0,0.0,1.0]":2})");
  // The <visual>'s "blue", which no part takes, is not written.
  EXPECT_EQ(document["materials"].size(), 2u) << document["materials"].dump();
  EXPECT_EQ(document["accessors"][primitives[0]["attributes"]["POSITION"].get<std::size_t>()]["count"], 8);
}

// COLLADA's transparency is not carried, as RViz draws every part opaque: Blender 2.7x writes
// <transparent opaque="RGB_ZERO"> white for its opaque materials (franka_ros's Panda, all of it),
// which assimp reads as opacity 0; a <transparency> of 0.5 is opaque too.
TEST(UrdfImportMeshes, ColladaTransparencyIsNotCarried) {
  for (const std::string& transparency :
       {std::string("<transparent opaque=\"RGB_ZERO\"><color>1 1 1 1</color></transparent>"),
        std::string("<transparent opaque=\"A_ONE\"><color>0 0 0 1</color></transparent><transparency><float>0.5</float></transparency>")}) {
    SCOPED_TRACE(transparency);
    TempDir dir;
    std::string text = collada(kMetres, "Z_UP", {{kIdentity, {}}});
    const std::string red = "1 0 0 1</color></diffuse>";
    text.replace(text.find(red), red.size(), red + transparency);
    testing::write_file(dir / "box.dae", text);
    testing::write_file(dir / "robot.urdf", one_link("box.dae"));
    Diagnostics diag;
    const Conversion conversion = import_ok(dir / "robot.urdf", diag);
    for (const Json& material : conversion.asset.document["materials"]) {
      EXPECT_EQ(material["pbrMetallicRoughness"]["baseColorFactor"][3], 1.0) << material.dump();
      EXPECT_FALSE(material.contains("alphaMode")) << material.dump();
    }
  }
}

// An open visual mesh (most published robots have some) on a link whose mass is its <inertial>
// changes no mass: MESH_OPEN is information there, saying so, and a warning that the mass is
// unreliable only where the mass comes from the mesh.
TEST(UrdfImportMeshes, AnOpenMeshOfALinkWithAnAuthoredMassIsInformation) {
  for (const bool authored : {true, false}) {
    SCOPED_TRACE(authored ? "with <inertial>" : "mass from the mesh");
    TempDir dir;
    // A tetrahedron without its base: three triangles, three boundary edges.
    testing::write_file(dir / "open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    const std::string inertial =
        "<inertial><mass value=\"2\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial>\n";
    testing::write_file(dir / "robot.urdf", one_link("open.obj", authored ? inertial : ""));
    Diagnostics diag;
    import_urdf(dir / "robot.urdf", UrdfImportOptions{}, diag);
    const Diagnostic* d = find_code(diag, "MESH_OPEN");
    ASSERT_NE(d, nullptr);
    EXPECT_EQ(d->severity, authored ? Severity::kInfo : Severity::kWarning);
    EXPECT_NE(d->message.find("3 boundary edges"), std::string::npos) << d->message;
    EXPECT_EQ(d->message.find("link 'a' has an authored inertial, so no mass comes from this mesh") != std::string::npos,
              authored)
        << d->message;
    EXPECT_EQ(d->message.find("its mass, is unreliable") != std::string::npos, !authored) << d->message;
  }
}

// A file without materials (an OBJ without .mtl: assimp's stand-in material) is drawn in the
// <visual>'s colour, as RViz draws it.
TEST(UrdfImportMeshes, AMeshWithoutColoursTakesTheVisualsMaterial) {
  TempDir dir;
  testing::write_file(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  testing::write_file(dir / "robot.urdf", one_link("tri.obj"));
  Diagnostics diag;
  const Conversion conversion = import_ok(dir / "robot.urdf", diag);
  const Json& document = conversion.asset.document;
  const Json& primitives = document["meshes"][0]["primitives"];
  ASSERT_EQ(primitives.size(), 1u) << primitives.dump();
  EXPECT_EQ(document["materials"][primitives[0]["material"].get<std::size_t>()]["pbrMetallicRoughness"]["baseColorFactor"].dump(),
            "[0.0,0.0,1.0,1.0]");
  EXPECT_NEAR(conversion.robot.links[0].inertial.mass, 1000.0 / 6, 1000.0 / 6 * 1e-15);
}

// Node transforms compose down the tree, a geometry instanced twice counts twice, and a mirrored
// instance (scale -1) is wound outward: two 2 x 4 x 6 m boxes, at (0, 0, 5) + (1, 0, 0) and at
// (-7, 0, 0) mirrored in x: 96 m^3, centre the midpoint (-3, 0, 2.5).
TEST(UrdfImportMeshes, NestedInstancedAndMirroredNodesAreAppliedAndWoundOutward) {
  TempDir dir;
  const ColladaNode child{"1 0 0 1 0 1 0 0 0 0 1 0 0 0 0 1", {}, true};
  const ColladaNode parent{"1 0 0 0 0 1 0 0 0 0 1 5 0 0 0 1", {child}, false};
  const ColladaNode mirrored{"-1 0 0 -7 0 1 0 0 0 0 1 0 0 0 0 1", {}, true};
  testing::write_file(dir / "two.dae", collada(kMetres, "Z_UP", {parent, mirrored}));
  testing::write_file(dir / "robot.urdf", one_link("two.dae"));
  Diagnostics diag;
  const Conversion conversion = import_ok(dir / "robot.urdf", diag);
  EXPECT_EQ(find_code(diag, "MESH_INSIDE_OUT"), nullptr);
  EXPECT_EQ(find_code(diag, "MESH_INCONSISTENT_WINDING"), nullptr);
  const Link& link = conversion.robot.links[0];
  EXPECT_NEAR(link.inertial.mass, 96000.0, 96000.0 * 1e-12);  // Every corner is exact in float32.
  const Eigen::Vector3d center = gltf_to_urdf_axes() * link.inertial.center_of_mass;
  EXPECT_NEAR(center.x(), -3.0, 1e-12);
  EXPECT_NEAR(center.y(), 0.0, 1e-12);
  EXPECT_NEAR(center.z(), 2.5, 1e-12);
}

// Files as Blender 3.4 writes them (tests/data/urdf_meshes: a box in millimetres with quads and two
// materials, the same with up_axis Y_UP, a parent chain with a linked duplicate, an OBJ with its
// .mtl), against expected.json, made by a reader of the files' text written without assimp
// (compute_expected.py). Each coordinate passes through float32 twice (assimp's vertex and
// matrix entries, then the glTF buffer): within 4 x 2^-23 of the extent, 0.6 m.
TEST(UrdfImportMeshes, BlenderExportsMatchAnIndependentReader) {
  const fs::path folder = testing::data_dir() / "urdf_meshes";
  const Json expected = Json::parse(testing::read_file(folder / "expected.json"));
  Diagnostics diag;
  const Conversion conversion = import_ok(folder / "robot.urdf", diag);
  for (const Diagnostic& d : diag.all()) {
    EXPECT_EQ(d.code.rfind("URDF_MESH", 0), std::string::npos) << format(d);
    EXPECT_NE(d.code, "MESH_OPEN") << format(d);
  }
  const Json& document = conversion.asset.document;
  const double bound = 4 * float_bound(0.6);
  const std::map<std::string, std::string> file_of{
      {"base_link", "box_mm.dae"}, {"nested_link", "nested.dae"}, {"obj_link", "box.obj"}, {"yup_link", "box_yup.dae"}};
  std::map<std::string, Json> bounds;
  for (const Json& mesh : document["meshes"]) {
    const std::string name = mesh["name"].get<std::string>();
    const std::string link = name.substr(0, name.rfind("_visual"));
    ASSERT_TRUE(file_of.count(link)) << name;
    SCOPED_TRACE(file_of.at(link));
    const Json& file = expected["files"][file_of.at(link)];
    const Json& positions = document["accessors"][mesh["primitives"][0]["attributes"]["POSITION"].get<std::size_t>()];
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(positions["min"][i].get<double>(), file["min"][i].get<double>(), bound) << i;
      EXPECT_NEAR(positions["max"][i].get<double>(), file["max"][i].get<double>(), bound) << i;
    }
    bounds[link] = Json{positions["min"], positions["max"]};
    // One primitive per material, each with its triangles and the file's diffuse colour.
    std::map<std::string, std::size_t> got, want;
    for (const Json& primitive : mesh["primitives"]) {
      const Json& material = document["materials"][primitive["material"].get<std::size_t>()];
      got[material["pbrMetallicRoughness"]["baseColorFactor"].dump()] +=
          document["accessors"][primitive["indices"].get<std::size_t>()]["count"].get<std::size_t>() / 3;
    }
    for (const Json& material : file["materials"]) want[material["diffuse_rgba"].dump()] += material["triangles"].get<std::size_t>();
    EXPECT_EQ(Json(got).dump(), Json(want).dump());
  }
  // Up-axis ignored: the Y_UP copy is the Z_UP file, bit for bit.
  EXPECT_EQ(bounds["base_link"].dump(), bounds["yup_link"].dump());
  // The link without <inertial> weighs its two boxes at 1000 kg/m^3: a coordinate's error `bound`
  // moves a box's volume by at most 2 bound / e relative per edge e (edges of 0.1 m and more).
  for (const Link& link : conversion.robot.links) {
    if (link.name != "nested_link") continue;
    const double volume = expected["files"]["nested.dae"]["volume"].get<double>();
    EXPECT_NEAR(link.inertial.mass, 1000 * volume, 1000 * volume * 3 * 2 * bound / 0.1);
  }
  const TempDir out;
  expect_no_validator_errors(conversion, out / "out.gltf");
}

// The ROS tutorial's PR2 fingers: COLLADA files that say Y_UP and hold Z-up data, a node scale of
// 0.1 (RViz shows them in place because it ignores the up axis). Bounds against
// urdf_tutorial/meshes/expected.json (reference.py, a reader of the files' text), to twice float32.
TEST(UrdfImportMeshes, TheTutorialsFingersAreWhereRvizShowsThem) {
  const fs::path folder = testing::data_dir() / "urdf" / "urdf_tutorial";
  const Json expected = Json::parse(testing::read_file(folder / "meshes" / "expected.json"));
  Diagnostics diag;
  const Conversion conversion = import_ok(folder / "05-visual.urdf", diag);
  const Json& document = conversion.asset.document;
  int checked = 0;
  for (const Json& mesh : document["meshes"]) {
    const std::string name = mesh["name"].get<std::string>();
    const char* file = name == "left_gripper_visual" ? "l_finger.dae" : name == "left_tip_visual" ? "l_finger_tip.dae" : nullptr;
    if (file == nullptr) continue;
    SCOPED_TRACE(file);
    const Json& positions = document["accessors"][mesh["primitives"][0]["attributes"]["POSITION"].get<std::size_t>()];
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(positions["min"][i].get<double>(), expected[file]["min"][i].get<double>(), 4 * float_bound(0.1)) << i;
      EXPECT_NEAR(positions["max"][i].get<double>(), expected[file]["max"][i].get<double>(), 4 * float_bound(0.1)) << i;
    }
    ++checked;
  }
  EXPECT_EQ(checked, 2);
}

// An OBJ with its .mtl: Kd colours per part, opaque whatever `d` says (as RViz draws them),
// coordinates in metres as written; the URDF's scale on top. A unit cube scaled by 2 is 8 m^3.
TEST(UrdfImportMeshes, ObjWithItsMaterialsAndTheUrdfScale) {
  TempDir dir;
  testing::write_file(dir / "cube.mtl", "newmtl red\nKd 1 0 0\nnewmtl green\nKd 0 1 0\nd 0.5\n");
  std::string obj = "mtllib cube.mtl\n";
  for (int i = 0; i < 8; ++i) {
    obj += std::string("v ") + ((i & 1) ? "1" : "0") + " " + ((i & 2) ? "1" : "0") + " " + ((i & 4) ? "1" : "0") + "\n";
  }
  // OBJ counts vertices from 1; quads, triangulated on reading.
  obj += "usemtl red\nf 5 6 8 7\nusemtl green\nf 1 3 4 2\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  testing::write_file(dir / "cube.obj", obj);
  testing::write_file(dir / "robot.urdf",
                      "<robot name=\"r\">\n<link name=\"a\">\n<visual><geometry><mesh filename=\"cube.obj\" scale=\"2 2 2\"/>"
                      "</geometry></visual>\n</link>\n</robot>\n");
  Diagnostics diag;
  const Conversion conversion = import_ok(dir / "robot.urdf", diag);
  EXPECT_EQ(find_code(diag, "MESH_OPEN"), nullptr);
  EXPECT_EQ(conversion.robot.links[0].inertial.mass, 8000.0);
  const Eigen::Vector3d center = gltf_to_urdf_axes() * conversion.robot.links[0].inertial.center_of_mass;
  EXPECT_NEAR((center - Eigen::Vector3d(1, 1, 1)).norm(), 0.0, 1e-12);
  const Json& document = conversion.asset.document;
  std::vector<std::string> colours;
  for (const Json& primitive : document["meshes"][0]["primitives"]) {
    colours.push_back(document["materials"][primitive["material"].get<std::size_t>()]["pbrMetallicRoughness"]["baseColorFactor"].dump());
  }
  std::sort(colours.begin(), colours.end());
  EXPECT_EQ(colours, (std::vector<std::string>{"[0.0,1.0,0.0,1.0]", "[1.0,0.0,0.0,1.0]"}));
  expect_no_validator_errors(conversion, dir / "out.gltf");
}

// An OBJ whose .mtl is a FIFO: the import does not wait on it. The face's `usemtl red`, which no
// .mtl defines, is assimp's material of that name in its stand-in grey (0.6), as RViz draws it.
TEST(UrdfImportMeshes, AnObjsMaterialFileThatIsAFifoIsNotOpened) {
  TempDir dir;
  ASSERT_EQ(::mkfifo((dir / "tri.mtl").c_str(), 0600), 0);
  testing::write_file(dir / "tri.obj",
                      "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl red\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  testing::write_file(dir / "robot.urdf", one_link("tri.obj"));
  Diagnostics diag;
  const Conversion conversion = import_ok(dir / "robot.urdf", diag);
  EXPECT_NEAR(conversion.robot.links[0].inertial.mass, 1000.0 / 6, 1000.0 / 6 * 1e-15);
  const Json& document = conversion.asset.document;
  const Json& primitives = document["meshes"][0]["primitives"];
  ASSERT_EQ(primitives.size(), 1u);
  const Json& material = document["materials"][primitives[0]["material"].get<std::size_t>()];
  EXPECT_EQ(material["name"], "red");
  EXPECT_EQ(material["pbrMetallicRoughness"]["baseColorFactor"].dump(), "[0.6,0.6,0.6,1.0]");
}

// A file assimp crashes on (an <instance_node> that instances itself: assimp recurses until its
// stack runs out) ends only the child process that reads it: the import names the file and goes
// on, the link keeps its <inertial>.
TEST(UrdfImportMeshes, AFileThatCrashesAssimpEndsOnlyItsReader) {
  TempDir dir;
  std::string text = collada(kMetres, "Z_UP", {{kIdentity, {}}});
  const std::string geometry_end = "</node>\n</visual_scene>";
  text.replace(text.find(geometry_end), geometry_end.size(),
               "<node id=\"loop\" name=\"loop\"><instance_node url=\"#loop\"/></node></node>\n</visual_scene>");
  testing::write_file(dir / "loop.dae", text);
  testing::write_file(dir / "robot.urdf",
                      one_link("loop.dae", "<inertial><mass value=\"2\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" "
                                           "iyz=\"0\" izz=\"1\"/></inertial>\n"));
  Diagnostics diag;
  const Conversion conversion = import_ok(dir / "robot.urdf", diag);
  EXPECT_EQ(conversion.robot.links[0].inertial.mass, 2.0);
  const Diagnostic* d = find_code(diag, "URDF_MESH_INVALID");
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->severity, Severity::kWarning);
  EXPECT_NE(d->message.find("assimp failed reading it"), std::string::npos) << d->message;
}

// A file assimp cannot read: a warning where the link has an <inertial> (only its look is lost),
// an error where its mass would come from the mesh. Both name the file and say COLLADA.
TEST(UrdfImportMeshes, AFileAssimpCannotReadIsNamed) {
  for (const bool authored : {true, false}) {
    SCOPED_TRACE(authored ? "with <inertial>" : "mass from the mesh");
    TempDir dir;
    const std::string whole = collada(kMetres, "Z_UP", {{kIdentity, {}}});
    testing::write_file(dir / "cut.dae", whole.substr(0, whole.size() / 2));
    const std::string inertial =
        "<inertial><mass value=\"2\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial>\n";
    testing::write_file(dir / "robot.urdf", one_link("cut.dae", authored ? inertial : ""));
    Diagnostics diag;
    const auto conversion = import_urdf(dir / "robot.urdf", UrdfImportOptions{}, diag);
    EXPECT_EQ(conversion.has_value(), authored);
    const Diagnostic* d = find_code(diag, "URDF_MESH_INVALID");
    ASSERT_NE(d, nullptr);
    EXPECT_EQ(d->severity, authored ? Severity::kWarning : Severity::kError);
    EXPECT_EQ(d->pointer, "/robot/link[@name='a']/visual[1]");
    EXPECT_NE(d->message.find((dir / "cut.dae").string() + "': COLLADA: "), std::string::npos) << d->message;
  }
}

// assimp sizes its arrays from COLLADA's counts before reading what they count (a 5 KB file with
// <triangles count="1500000000"> asked for 72 GB): a count or stride above the file's size in
// bytes, impossible in a real file, or not plain decimal digits, is refused with its line before
// assimp reads the file.
TEST(UrdfImportMeshes, ACountTheFileCannotHoldIsRefusedBeforeReading) {
  // Each as written, and as assimp's XML parser also reads it: spaces around '=', a sign, hex.
  for (const std::string& attribute : {std::string("count=\"1500000000\""), std::string("stride=\"900000000\""),
                                       std::string("count = \"1500000000\""), std::string("count=\"+10\""),
                                       std::string("count=\"0x59682F00\"")}) {
    SCOPED_TRACE(attribute);
    TempDir dir;
    std::string text = collada(kMetres, "Z_UP", {{kIdentity, {}}});
    const std::string old = attribute.rfind("count", 0) == 0 ? "count=\"10\"" : "stride=\"3\"";
    text.replace(text.find(old), old.size(), attribute);
    testing::write_file(dir / "crafted.dae", text);
    testing::write_file(dir / "robot.urdf", one_link("crafted.dae"));
    Diagnostics diag;
    EXPECT_FALSE(import_urdf(dir / "robot.urdf", UrdfImportOptions{}, diag));
    const Diagnostic* d = find_code(diag, "URDF_MESH_INVALID");
    ASSERT_NE(d, nullptr);
    EXPECT_NE(d->message.find(" on line "), std::string::npos) << d->message;
    const bool plain = attribute.find_first_of("+x") == std::string::npos;  // Digits, spaced or not.
    EXPECT_NE(d->message.find(plain ? "bytes can hold" : "is not a plain decimal number"), std::string::npos) << d->message;
  }
}

// The triangle limit counts every instance, before the triangles are kept: 12 instances of a box
// (144 triangles) against a limit of 100.
TEST(UrdfImportMeshes, InstancesCountAgainstTheTriangleLimit) {
  TempDir dir;
  std::vector<ColladaNode> nodes(12, ColladaNode{kIdentity, {}, true});
  testing::write_file(dir / "many.dae", collada(kMetres, "Z_UP", nodes));
  testing::write_file(dir / "robot.urdf", one_link("many.dae"));
  UrdfImportOptions options;
  options.convert.limits.max_triangles = 100;
  Diagnostics diag;
  EXPECT_FALSE(import_urdf(dir / "robot.urdf", options, diag));
  const Diagnostic* d = find_code(diag, "TOO_MANY_TRIANGLES");
  ASSERT_NE(d, nullptr);
  EXPECT_NE(d->message.find("more than 100 triangles with this file's"), std::string::npos) << d->message;
}

// A vertex that its node transforms carry beyond float32 (1e30 m times 1e30) cannot be written to a
// glTF buffer: named, not written as infinity.
TEST(UrdfImportMeshes, AVertexBeyondFloatRangeIsNamed) {
  TempDir dir;
  testing::write_file(dir / "far.dae", collada(kMetres, "Z_UP", {{"1e30 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1", {}}}, {2e30, 4, 6}));
  testing::write_file(dir / "robot.urdf", one_link("far.dae"));
  Diagnostics diag;
  EXPECT_FALSE(import_urdf(dir / "robot.urdf", UrdfImportOptions{}, diag));
  const Diagnostic* d = find_code(diag, "URDF_MESH_INVALID");
  ASSERT_NE(d, nullptr);
  EXPECT_NE(d->message.find("beyond"), std::string::npos) << d->message;
}

// Formats import does not read are still named (and the collision geometry stands in).
TEST(UrdfImportMeshes, OtherFormatsAreNamedWithTheOnesImportReads) {
  TempDir dir;
  testing::write_file(dir / "part.ply", "ply\n");
  testing::write_file(dir / "robot.urdf",
                      one_link("part.ply", "<inertial><mass value=\"1\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" "
                                           "iyz=\"0\" izz=\"1\"/></inertial>\n"));
  Diagnostics diag;
  import_ok(dir / "robot.urdf", diag);
  const Diagnostic* d = find_code(diag, "URDF_MESH_FORMAT_UNSUPPORTED");
  ASSERT_NE(d, nullptr);
  EXPECT_NE(d->message.find("STL, COLLADA (.dae) and OBJ"), std::string::npos) << d->message;
}

}  // namespace
}  // namespace rdtf
