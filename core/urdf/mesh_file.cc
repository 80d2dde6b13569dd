// COLLADA and OBJ meshes of a URDF, read with assimp the way ROS tools read them.
//
// RViz and MoveIt (geometric_shapes) load these files with assimp, and what a published robot
// looks like is what they show: every node transform of the file applied, COLLADA's <up_axis>
// ignored (assimp would turn a Z-up file to Y-up at its root node; ROS meshes are in the link
// frame, Z up, whatever the file says), COLLADA's <unit meter> applied, OBJ as written in metres,
// and each part in the material the file gives it.
#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <system_error>

#include <Eigen/LU>

#include "import_internal.h"

namespace rdtf::urdf_internal {
namespace {

namespace fs = std::filesystem;

// assimp opens the files a mesh names (an OBJ's .mtl) itself: only regular files within the size
// limit, read-only, so that a FIFO in a material's place cannot block the import and a device
// cannot feed it without end.
class RegularFilesOnly : public Assimp::DefaultIOSystem {
 public:
  explicit RegularFilesOnly(std::uint64_t max_bytes) : max_bytes_(max_bytes) {}

  bool Exists(const char* file) const override {
    std::error_code error;
    return fs::is_regular_file(fs::path(file), error);
  }

  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (mode == nullptr || std::strpbrk(mode, "wa+") != nullptr) return nullptr;
    std::error_code error;
    const fs::path path(file);
    if (!fs::is_regular_file(path, error) || error) return nullptr;
    const auto size = fs::file_size(path, error);
    if (error || size > max_bytes_) return nullptr;
    return DefaultIOSystem::Open(file, mode);
  }

 private:
  std::uint64_t max_bytes_;
};

// A float as the shortest decimal that reads back as that float, then as a double: the 0.8 a file
// wrote, not 0.800000011920929 (assimp keeps colours and matrices in float).
double decimal_of(float value) {
  char text[32];
  const auto written = std::to_chars(text, text + sizeof text, value);
  double out = value;
  std::from_chars(text, written.ptr, out);
  return out;
}

Eigen::Matrix4d matrix_of(const aiMatrix4x4& m) {
  Eigen::Matrix4d out;
  out << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return out;
}

// COLLADA's <unit meter="0.001"/> as written. assimp folds it into the root node's matrix in float
// (0.001f is 1.0000000475e-3); the decimal of the file makes millimetres exact.
std::optional<double> collada_unit(std::string_view text) {
  const std::size_t unit = text.find("<unit");
  if (unit == std::string_view::npos) return std::nullopt;
  const std::size_t end = text.find('>', unit);
  const std::string_view element = text.substr(unit, end == std::string_view::npos ? 256 : end - unit);
  const std::size_t meter = element.find("meter=");
  if (meter == std::string_view::npos || meter + 7 >= element.size()) return std::nullopt;
  const char quote = element[meter + 6];
  const std::size_t close = element.find(quote, meter + 7);
  if ((quote != '"' && quote != '\'') || close == std::string_view::npos) return std::nullopt;
  std::string_view number = element.substr(meter + 7, close - meter - 7);
  while (!number.empty() && std::isspace(static_cast<unsigned char>(number.front()))) number.remove_prefix(1);
  while (!number.empty() && std::isspace(static_cast<unsigned char>(number.back()))) number.remove_suffix(1);
  double value = 0;
  const auto [ptr, ec] = std::from_chars(number.data(), number.data() + number.size(), value);
  if (ec != std::errc() || ptr != number.data() + number.size() || !(value > 0) || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

// The file's own colour for a part, or nothing where it has none (assimp's stand-in material for
// faces without one, or no diffuse colour): the URDF's <material> applies there, as in RViz.
std::optional<MeshMaterial> material_of(const aiMaterial& material) {
  aiString name;
  material.Get(AI_MATKEY_NAME, name);
  if (std::strcmp(name.C_Str(), AI_DEFAULT_MATERIAL_NAME) == 0) return std::nullopt;
  aiColor4D diffuse;
  if (aiGetMaterialColor(&material, AI_MATKEY_COLOR_DIFFUSE, &diffuse) != AI_SUCCESS) return std::nullopt;
  float opacity = 1;
  const bool has_opacity = aiGetMaterialFloat(&material, AI_MATKEY_OPACITY, &opacity) == AI_SUCCESS;
  const auto unit = [](float v) { return std::isfinite(v) ? std::min(1.0, std::max(0.0, decimal_of(v))) : 1.0; };
  MeshMaterial out;
  out.name = name.C_Str();
  out.rgba = {unit(diffuse.r), unit(diffuse.g), unit(diffuse.b), unit(has_opacity ? opacity : diffuse.a)};
  return out;
}

// assimp sizes its arrays from COLLADA's count attributes before reading what they count: 5 KB
// with <triangles count="1500000000"> asked for 72 GB. Every count (and stride) counts items
// written in the text, each at least a byte, so one above the file's size is a lie: refused with
// its line before assimp reads the file.
std::optional<std::string> impossible_count(std::string_view text) {
  for (const std::string_view name : {std::string_view("count="), std::string_view("stride=")}) {
    for (std::size_t at = text.find(name); at != std::string_view::npos; at = text.find(name, at + 1)) {
      if (at == 0 || !std::isspace(static_cast<unsigned char>(text[at - 1]))) continue;
      std::size_t digit = at + name.size() + 1;
      if (digit > text.size() || (text[digit - 1] != '"' && text[digit - 1] != '\'')) continue;
      while (digit < text.size() && std::isspace(static_cast<unsigned char>(text[digit]))) ++digit;
      std::size_t end = digit;
      while (end < text.size() && std::isdigit(static_cast<unsigned char>(text[end]))) ++end;
      if (end == digit) continue;
      const std::string_view number = text.substr(digit, end - digit);
      std::uint64_t value = 0;
      const auto parsed = std::from_chars(number.data(), number.data() + number.size(), value);
      if (parsed.ec == std::errc() && value <= text.size()) continue;
      const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
      return std::string(name.substr(0, name.size() - 1)) + "=\"" + std::string(number) + "\" on line " +
             std::to_string(line) + " is more than the file's " + std::to_string(text.size()) +
             " bytes can hold: the file is cut short or crafted (not read)";
    }
  }
  return std::nullopt;
}

}  // namespace

MeshFormat mesh_format(const std::string& filename) {
  std::string extension = fs::path(filename).extension().string();
  for (char& ch : extension) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (extension == ".stl") return MeshFormat::kStl;
  if (extension == ".dae") return MeshFormat::kCollada;
  if (extension == ".obj") return MeshFormat::kObj;
  return MeshFormat::kOther;
}

std::optional<MeshFile> read_assimp_mesh(const fs::path& path, MeshFormat format, std::string_view text,
                                         const MeshLimits& limits, std::string& why, bool& too_many) {
  too_many = false;
  if (format == MeshFormat::kCollada) {
    if (auto impossible = impossible_count(text)) {
      why = *impossible;
      return std::nullopt;
    }
  }
  Assimp::Importer importer;
  importer.SetIOHandler(new RegularFilesOnly(limits.max_file_bytes));  // The importer owns it.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  // Points and lines are left as faces of one and two corners and skipped below.
  const unsigned flags = aiProcess_Triangulate | aiProcess_ValidateDataStructure;
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(path.string(), flags);
  } catch (const std::exception& e) {
    why = e.what();
    return std::nullopt;
  }
  if (scene != nullptr && scene->mNumMeshes == 0) return MeshFile{};  // "has no triangles"
  if (scene == nullptr || scene->mRootNode == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) {
    why = importer.GetErrorString();
    if (why.empty()) why = "assimp read no scene from it";
    return std::nullopt;
  }

  Eigen::Matrix4d root = matrix_of(scene->mRootNode->mTransformation);
  if (format == MeshFormat::kCollada) {
    // With <up_axis> ignored the root is the unit alone: diag(u, u, u, 1) in float.
    const auto unit = collada_unit(text);
    const Eigen::Matrix4d float_unit = Eigen::Vector4d(root(0, 0), root(0, 0), root(0, 0), 1).asDiagonal();
    if (unit && root == float_unit && static_cast<float>(*unit) == static_cast<float>(root(0, 0))) {
      root = Eigen::Vector4d(*unit, *unit, *unit, 1).asDiagonal();
    }
  }

  // Each mesh instance's triangles, by material, in the link's frame: a node's meshes under the
  // product of the matrices from the root down (an explicit stack: a file's nesting is its own).
  std::vector<std::vector<Eigen::Vector3d>> corners(scene->mNumMaterials + 1);
  std::uint64_t triangles = 0;
  std::vector<std::pair<const aiNode*, Eigen::Matrix4d>> stack{{scene->mRootNode, root}};
  while (!stack.empty()) {
    const auto [node, X] = stack.back();
    stack.pop_back();
    const Eigen::Matrix3d linear = X.topLeftCorner<3, 3>();
    const bool mirrored = linear.determinant() < 0;  // Keeps a mirrored instance wound outward.
    for (unsigned m = 0; m < node->mNumMeshes; ++m) {
      if (node->mMeshes[m] >= scene->mNumMeshes) continue;
      const aiMesh& mesh = *scene->mMeshes[node->mMeshes[m]];
      auto& out = corners[std::min<std::size_t>(mesh.mMaterialIndex, scene->mNumMaterials)];
      for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
        const aiFace& face = mesh.mFaces[f];
        if (face.mNumIndices != 3) continue;
        if (++triangles > limits.max_triangles) {
          too_many = true;
          why = "more than " + std::to_string(limits.max_triangles) + " triangles (each instance of a mesh counted)";
          return std::nullopt;
        }
        const std::size_t start = out.size();
        for (unsigned k = 0; k < 3; ++k) {
          const aiVector3D& v = mesh.mVertices[face.mIndices[k]];
          const Eigen::Vector3d p = (X * Eigen::Vector4d(v.x, v.y, v.z, 1)).head<3>();
          // Positions go into the glTF buffer as float32: a vertex its nodes carry beyond float's
          // range would be written as infinity.
          if (!p.allFinite() || p.cwiseAbs().maxCoeff() > std::numeric_limits<float>::max()) {
            why = "mesh '" + std::string(mesh.mName.C_Str()) + "' has a vertex " +
                  (p.allFinite() ? "beyond float32's range once its node transforms are applied" : "that is not finite");
            return std::nullopt;
          }
          out.push_back(p);
        }
        if (mirrored) std::swap(out[start + 1], out[start + 2]);
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) {
      if (node->mChildren[c] != nullptr) stack.emplace_back(node->mChildren[c], X * matrix_of(node->mChildren[c]->mTransformation));
    }
  }

  MeshFile file;
  Welder welder;
  for (std::size_t material = 0; material < corners.size(); ++material) {
    if (corners[material].empty()) continue;
    MeshPart part;
    part.first = welder.triangles();
    part.count = corners[material].size() / 3;
    if (material < scene->mNumMaterials && scene->mMaterials[material] != nullptr) {
      part.material = material_of(*scene->mMaterials[material]);
    }
    for (const Eigen::Vector3d& p : corners[material]) welder.add_corner(p);
    file.parts.push_back(std::move(part));
  }
  file.mesh = welder.take();
  return file;
}

}  // namespace rdtf::urdf_internal
