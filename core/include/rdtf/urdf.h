// URDF out of RDTF (the paper's section 5.2: "many tools in ROS" can use the models) and URDF into
// RDTF. docs/urdf.md documents the mapping, the frame conversion, names, limits and mesh paths.
//
// Export builds the model with urdfdom's own types, writes it with urdfdom's exporter (whose six
// significant digits are replaced by the shortest text that reads back as the same double) and
// parses the result back with urdfdom as a check. Import parses with urdfdom and builds a glTF
// with extras.RDTF, then runs the ordinary conversion on it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "rdtf/atomic_file.h"
#include "rdtf/convert.h"
#include "rdtf/diagnostics.h"

namespace rdtf {

struct UrdfOptions {
  // glTF is Y up, ROS is Z up: by default every frame is turned +90 degrees about X, so a
  // coordinate (x, y, z) of glTF becomes (x, -z, y). True keeps glTF's axes as they are.
  bool y_up = false;
  // Put in front of "meshes/<link>.stl" in every <mesh filename>: "" (a path relative to the
  // URDF, which MuJoCo, pybullet, Drake and Gazebo resolve), or e.g. "package://my_robot/urdf/"
  // or "file:///abs/dir/" for RViz: a folder, so a '/' is added when it does not end in one.
  // The files are always written to DIR/meshes/.
  std::string mesh_uri_prefix;
  // Add <mujoco><compiler meshdir="meshes" fusestatic="false" inertiafromgeom="false"/></mujoco>
  // so that MuJoCo finds the meshes and keeps one body per link with our inertials.
  bool mujoco_compiler = true;
  // How mesh files are named. Empty (`rdtf urdf`): "meshes/<link>.stl", overwritten in place.
  // Given (rdtfd): content-addressed, "meshes/<link>.<16 hex digits of the digest>.stl"
  // (atomic_file.h): write_urdf writes them before robot.urdf, whose rename commits them all,
  // then removes every content-addressed file of DIR/meshes that neither the new nor the replaced
  // robot.urdf refers to (a reader that opened the previous URDF a moment ago still finds its
  // meshes). DIR is taken to hold this one URDF.
  ContentDigest mesh_digest;
  // Set when DIR is a StagedOutput's folder whose commit will move it into this folder (rdtfd):
  // files are written with write_staged_file (commit syncs what it moves), and a mesh this folder
  // already holds with the very same bytes is not written again. robot.urdf is always written.
  std::filesystem::path staged_for;
};

struct UrdfMeshFile {
  std::string path;                 // Relative to the URDF's folder: "meshes/<link>[.<hash>].stl".
  std::vector<std::uint8_t> bytes;  // Binary STL.
};

struct UrdfExport {
  std::string text;  // robot.urdf
  std::vector<UrdfMeshFile> meshes;
  std::vector<std::string> link_names;   // URDF name of each RDTF link (Robot::links order).
  std::vector<std::string> joint_names;  // URDF name of each RDTF joint (Robot::joints order).
};

// The URDF of a converted model, in memory. Nothing (and errors) when the robot cannot be said in
// URDF (a ball joint, a prismatic joint without limits) or urdfdom refuses the result.
std::optional<UrdfExport> export_urdf(const Conversion& conversion, const UrdfOptions& options,
                                      Diagnostics& diag);

// export_urdf, then DIR/robot.urdf and DIR/meshes/<link>.stl, each written atomically (meshes
// first). `urdf_text`, when given, receives the URDF. With content-addressed names
// (UrdfOptions::mesh_digest) no mesh file this call created is left behind when it fails.
bool write_urdf(const Conversion& conversion, const std::filesystem::path& dir,
                const UrdfOptions& options, Diagnostics& diag, std::string* urdf_text = nullptr);

// The filename of every <mesh> in a URDF's text, as written (empty when the text is no XML).
std::vector<std::string> urdf_mesh_filenames(const std::string& urdf_text);

// Binary STL of triangles (little endian, float32, facet normals from the winding).
std::vector<std::uint8_t> stl_bytes(const TriangleMesh& mesh, const std::string& header);

// Reads a binary or ASCII STL. Vertices are welded by exact position so that the result is an
// indexed surface. Nothing, and `why`, when the bytes are no STL.
std::optional<TriangleMesh> parse_stl(const std::vector<std::uint8_t>& bytes, std::string& why);

struct UrdfImportOptions {
  // URDF is Z up, glTF Y up: by default every frame is turned -90 degrees about X (the inverse of
  // the export's conversion), so (x, y, z) of URDF becomes (x, z, -y). True keeps URDF's axes.
  bool z_up = false;
  ConvertOptions convert;  // Applied to the imported model (density for links without inertial).
};

// URDF -> RDTF: links, joints, inertials (kept as authored) and visual geometry (box, cylinder and
// sphere as generated meshes, STL files read; other mesh formats skipped with a warning) as a glTF
// with extras.RDTF, converted like any model. Its one buffer has no URI: write_rdtf puts it
// beside a .gltf or inside a .glb. Nothing (and errors naming the file and element) on bad input.
std::optional<Conversion> import_urdf(const std::filesystem::path& urdf,
                                      const UrdfImportOptions& options, Diagnostics& diag);

}  // namespace rdtf
