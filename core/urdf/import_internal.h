// URDF import internals: the structural pre-check of the XML (clear errors with line numbers
// before urdfdom sees it) and the geometry that becomes glTF meshes.
#pragma once

#include <array>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/triangle_mesh.h"

namespace urdf {
class Geometry;
}

namespace rdtf::urdf_internal {

// The URDF's text checked to be UTF-8 throughout, with numeric character references beyond ASCII
// ("&#xE9;") written out as UTF-8, so that urdfdom (TinyXML's legacy encoding, which would make
// one byte of them) and the scan below read the same names. URDF_NOT_UTF8 at the line and column
// of a byte that is not UTF-8 or a reference to no Unicode character (a surrogate).
std::optional<std::string> urdf_text_as_utf8(std::string_view text, Diagnostics& diag);

struct XmlLink {
  std::string name;
  int row = 0;
  std::vector<int> visual_rows;     // Line of each <visual>, in order.
  std::vector<int> collision_rows;  // Line of each <collision>, in order.
};

struct XmlJoint {
  std::string name, type, parent, child;
  int row = 0;
  int mimic_row = 0;    // The line of its <mimic>, 0 when it has none.
  int ignored_row = 0;  // The line of its <safety_controller>, else of its <calibration>; 0: none.
};

// The robot's structure in document order, checked: a <robot> root; named, unique links and
// joints; known joint types; parents and children that exist; a tree (one parent per link, no
// loops, one root). And every attribute import uses, read from the XML as urdfdom reads it (urdfdom
// 3.0 keeps a link whose <inertial> or geometry it cannot read, with a zero mass or without the
// geometry): present where urdfdom requires it; numbers that are finite and in range (sizes and
// radii above 0, mass, effort, velocity, damping and friction 0 or more, no zero axis or scale,
// colours in 0..1, lower not above upper). Each problem is an error at the attribute
// ("/robot/link[@name='a']/inertial/mass/@value") with the element's line: URDF_INVALID_NUMBER,
// URDF_INVALID_INERTIAL inside <inertial>, URDF_INVALID for a missing element or attribute.
struct XmlRobot {
  std::vector<XmlLink> links;
  std::vector<XmlJoint> joints;
  std::size_t root = 0;                      // Index into links.
  int row = 0;                               // Line of <robot>.
  std::map<std::string, int> material_rows;  // Line of the first top-level <material> of each name.
};

std::optional<XmlRobot> scan_urdf_xml(const std::string& text, Diagnostics& diag);

// urdfdom's console messages while `body` runs, errors apart from warnings (the same lock as
// with_console_captured: console_bridge's handler is global).
struct ConsoleMessages {
  std::vector<std::string> errors;
  std::vector<std::string> warnings;
};
ConsoleMessages capture_console(const std::function<void()>& body);

// "/robot/link[@name='base']", the place an import diagnostic points at.
std::string link_pointer(const std::string& name);
std::string joint_pointer(const std::string& name);

// Generated surfaces, outward wound, in the geometry's own frame as URDF defines it (box centred;
// cylinder along z, centred; sphere centred). The cylinder's polygon and the sphere's polyhedron
// are scaled so that their volumes are exactly the true solid's (pi r^2 l, 4/3 pi r^3).
// Why a primitive shape has no volume (a box with a side of 0, a cylinder of radius or length 0,
// a sphere of radius 0), e.g. "<cylinder> has length 0: it has no volume"; nothing for a shape with
// volume and for meshes.
std::optional<std::string> degenerate_shape(const urdf::Geometry& geometry);
TriangleMesh box_mesh(const Eigen::Vector3d& size);
TriangleMesh cylinder_mesh(double radius, double length, int segments = 32);
TriangleMesh sphere_mesh(double radius, int subdivisions = 3);

// "my%20dir" as "my dir": every %XX escape (two hex digits) as its byte.
std::string percent_decoded(const std::string& text);

// Where a <mesh filename> is on disk: a path relative to the URDF's folder, an absolute path,
// file://, or package://NAME/rest (found as rest under a folder named NAME among the URDF's folder
// and its ancestors, or under NAME/ in one of them). Nothing, and `why` (naming it as `what`), when
// it is not there.
std::optional<std::filesystem::path> resolve_mesh_path(const std::string& filename,
                                                       const std::filesystem::path& urdf_folder,
                                                       std::string& why,
                                                       const char* what = "mesh file");

// Collects triangle corners, welding equal positions into one vertex (an STL repeats each vertex in
// every triangle; COLLADA and OBJ split one per normal and texture coordinate). With texture
// coordinates, a vertex is an equal position and coordinate: a seam keeps its two.
class Welder {
 public:
  using Texcoord = std::array<float, 2>;
  // Use one form for every corner of a mesh: take_texcoords() has one coordinate per vertex only
  // when every corner came with one.
  void add_corner(const Eigen::Vector3d& p) { add(p, Texcoord{}, false); }
  void add_corner(const Eigen::Vector3d& p, const Texcoord& uv) { add(p, uv, true); }
  std::size_t triangles() const { return mesh_.triangles.size(); }
  TriangleMesh take() { return std::move(mesh_); }
  std::vector<Texcoord> take_texcoords() { return std::move(texcoords_); }

 private:
  void add(const Eigen::Vector3d& p, const Texcoord& uv, bool keep_uv) {
    const std::array<double, 5> key{p.x(), p.y(), p.z(), uv[0], uv[1]};
    auto [it, inserted] = index_.try_emplace(key, static_cast<std::uint32_t>(mesh_.positions.size()));
    if (inserted) {
      mesh_.positions.push_back(p);
      if (keep_uv) texcoords_.push_back(uv);
    }
    corner_[corners_++ % 3] = it->second;
    if (corners_ % 3 == 0) mesh_.triangles.push_back(corner_);
  }
  struct KeyHash {
    std::size_t operator()(const std::array<double, 5>& k) const {
      const std::hash<double> h;
      return h(k[0]) ^ (h(k[1]) * 31) ^ (h(k[2]) * 1000003) ^ (h(k[3]) * 998244353) ^ (h(k[4]) * 1000000007);
    }
  };
  std::unordered_map<std::array<double, 5>, std::uint32_t, KeyHash> index_;
  TriangleMesh mesh_;
  std::vector<Texcoord> texcoords_;
  std::array<std::uint32_t, 3> corner_{};
  std::size_t corners_ = 0;
};

// The mesh file formats import reads, by the name's extension (any case).
enum class MeshFormat { kStl, kCollada, kObj, kOther };
MeshFormat mesh_format(const std::string& filename);
inline constexpr const char* kMeshFormatsRead = "STL, COLLADA (.dae) and OBJ";

// A mesh file's triangles in metres, welded, and the parts drawn in one material each (triangles
// first .. first + count - 1); a part without a material of its own takes the URDF's <material>.
// A material's base colour image (its diffuse texture) is named as the file names it; the image
// multiplies `rgba` only where every triangle of the part has the coordinates it is mapped by.
struct MeshMaterial {
  std::string name;
  std::array<double, 4> rgba{};
  std::string texture;         // "" when it has none.
  bool texcoords = false;      // Whether the part's vertices carry the texture's coordinates.
};
struct MeshPart {
  std::size_t first = 0, count = 0;
  std::optional<MeshMaterial> material;
};
struct MeshFile {
  TriangleMesh mesh;
  // Each vertex's texture coordinate the glTF way (origin at the image's top left), when a part
  // has a texture and the coordinates for it; else empty.
  std::vector<std::array<float, 2>> texcoords;
  std::vector<MeshPart> parts;
  std::filesystem::path source;  // The file read (what its textures' names are relative to).
};
struct MeshLimits {
  std::uint64_t max_file_bytes = 0;
  std::uint64_t max_triangles = 0;
};

// A COLLADA or OBJ file read with assimp as ROS tools (RViz, MoveIt) read it: every node transform
// applied, COLLADA's <up_axis> ignored, its <unit meter> applied (exactly as `text`, the file's
// bytes, writes it), OBJ in metres as written, an OBJ's .mtl found beside it. Points and lines are
// left out; a mirrored instance is wound outward. Nothing, and `why`, when assimp cannot read it,
// a vertex is not finite, or (`too_many`) it holds more than the limit of triangles.
std::optional<MeshFile> read_assimp_mesh(const std::filesystem::path& path, MeshFormat format, std::string_view text,
                                         const MeshLimits& limits, std::string& why, bool& too_many);

// Builds the binary buffer of a generated glTF: one mesh per call, positions as float32 (with
// min and max) and indices as uint32.
class GltfMeshWriter {
 public:
  explicit GltfMeshWriter(Json& document) : document_(document) {}
  // One primitive of triangles first .. first + count - 1, in a material or none.
  struct Primitive {
    std::size_t first = 0, count = 0;
    std::optional<std::size_t> material;
    bool textured = false;  // Its material maps a texture by TEXCOORD_0.
  };
  // Returns the index of the new mesh: the positions (and texture coordinates, when given, one per
  // vertex) once, indices for each primitive.
  std::size_t add_mesh(const TriangleMesh& mesh, const std::vector<std::array<float, 2>>& texcoords,
                       const std::string& name, const std::vector<Primitive>& primitives);
  // An image in the buffer (PNG or JPEG bytes) and a texture sampling it; returns the texture's index.
  std::size_t add_texture(const std::string& bytes, const char* mime_type, const std::string& name);
  std::vector<std::uint8_t> take_buffer();

 private:
  std::size_t add_view(std::size_t offset, std::size_t length, int target);
  Json& document_;
  std::vector<std::uint8_t> bin_;
};

}  // namespace rdtf::urdf_internal
