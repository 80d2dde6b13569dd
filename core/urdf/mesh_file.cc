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

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <system_error>
#include <type_traits>

#include <Eigen/LU>

#include "import_internal.h"

// Whether AddressSanitizer is on (GCC says so with a macro, clang with __has_feature).
#if defined(__SANITIZE_ADDRESS__)
#define RDTF_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RDTF_ADDRESS_SANITIZER 1
#endif
#endif
#ifndef RDTF_ADDRESS_SANITIZER
#define RDTF_ADDRESS_SANITIZER 0
#endif

namespace rdtf::urdf_internal {
namespace {

namespace fs = std::filesystem;

// How long assimp may read one file (CPU and wall clock): a 100 MB COLLADA file reads in a few
// seconds; a file that keeps it longer is refused, not waited on.
constexpr int kReaderSeconds = 60;

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
  const auto unit = [](float v) { return std::isfinite(v) ? std::min(1.0, std::max(0.0, decimal_of(v))) : 1.0; };
  MeshMaterial out;
  out.name = name.C_Str();
  // Opaque, as RViz draws every COLLADA and OBJ part (it reads the diffuse colour's RGB, and looks
  // for opacity under a key assimp does not use). COLLADA's transparency cannot be trusted anyway:
  // Blender 2.7x writes <transparent opaque="RGB_ZERO"> white for opaque materials, which the
  // standard reads as fully transparent (every part of franka_ros's Panda).
  out.rgba = {unit(diffuse.r), unit(diffuse.g), unit(diffuse.b), 1.0};
  aiString texture;
  if (material.GetTextureCount(aiTextureType_DIFFUSE) > 0 &&
      material.GetTexture(aiTextureType_DIFFUSE, 0, &texture) == AI_SUCCESS) {
    out.texture = texture.C_Str();
  }
  return out;
}

// The texture coordinate set a material's diffuse texture is mapped by (0 unless the file says).
unsigned texcoord_set(const aiMaterial& material) {
  int set = 0;
  if (material.Get(AI_MATKEY_UVWSRC(aiTextureType_DIFFUSE, 0), set) != AI_SUCCESS || set < 0 ||
      set >= static_cast<int>(AI_MAX_NUMBER_OF_TEXTURECOORDS)) {
    return 0;
  }
  return static_cast<unsigned>(set);
}

// assimp sizes its arrays from COLLADA's count attributes before reading what they count: 5 KB
// with <triangles count="1500000000"> asked for 72 GB. Every count (and stride) counts items
// written in the text, each at least a byte, so one above the file's size is a lie; and one that
// is not plain decimal digits ("+N", "0x...", a character reference) is read by assimp's XML
// parser however it likes. Either is refused, with its line, before assimp reads the file.
std::optional<std::string> impossible_count(std::string_view text) {
  for (const std::string_view name : {std::string_view("count"), std::string_view("stride")}) {
    for (std::size_t at = text.find(name); at != std::string_view::npos; at = text.find(name, at + 1)) {
      // An attribute: white space before the name, then (white space) '=' (white space) a quote.
      if (at == 0 || !std::isspace(static_cast<unsigned char>(text[at - 1]))) continue;
      std::size_t i = at + name.size();
      while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
      if (i >= text.size() || text[i] != '=') continue;
      ++i;
      while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
      if (i >= text.size() || (text[i] != '"' && text[i] != '\'')) continue;
      const std::size_t close = text.find(text[i], i + 1);
      if (close == std::string_view::npos) continue;
      std::string_view value = text.substr(i + 1, close - i - 1);
      while (!value.empty() && std::isspace(static_cast<unsigned char>(value.front()))) value.remove_prefix(1);
      while (!value.empty() && std::isspace(static_cast<unsigned char>(value.back()))) value.remove_suffix(1);
      std::uint64_t number = 0;
      const auto parsed = std::from_chars(value.data(), value.data() + value.size(), number);
      const bool digits = !value.empty() && std::all_of(value.begin(), value.end(), [](char c) {
        return std::isdigit(static_cast<unsigned char>(c)) != 0;
      });
      if (digits && parsed.ec == std::errc() && number <= text.size()) continue;
      const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
      const std::string shown = std::string(name) + "=\"" + std::string(value.substr(0, 40)) + "\" on line " + std::to_string(line);
      if (!digits) return shown + " is not a plain decimal number (not read)";
      return shown + " is more than the file's " + std::to_string(text.size()) +
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

namespace {

// Reads the file with assimp in this process (the child of read_assimp_mesh).
std::optional<MeshFile> read_here(const fs::path& path, MeshFormat format, std::string_view text,
                                  const MeshLimits& limits, std::string& why, bool& too_many) {
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
  // A textured material's corners carry their texture coordinates, the glTF way (v from the top),
  // while every mesh drawn in it has them.
  std::vector<MeshMaterial> materials(scene->mNumMaterials + 1);
  std::vector<std::optional<MeshMaterial>> own(scene->mNumMaterials + 1);
  std::vector<std::vector<Welder::Texcoord>> texcoords(scene->mNumMaterials + 1);
  std::vector<unsigned> sets(scene->mNumMaterials + 1, 0);
  for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
    if (scene->mMaterials[m] == nullptr) continue;
    own[m] = material_of(*scene->mMaterials[m]);
    if (own[m] && !own[m]->texture.empty()) {
      own[m]->texcoords = true;
      sets[m] = texcoord_set(*scene->mMaterials[m]);
    }
  }
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
      const std::size_t material = std::min<std::size_t>(mesh.mMaterialIndex, scene->mNumMaterials);
      auto& out = corners[material];
      auto& out_uv = texcoords[material];
      std::optional<MeshMaterial>& drawn_in = own[material];
      if (drawn_in && drawn_in->texcoords && !mesh.HasTextureCoords(sets[material])) drawn_in->texcoords = false;
      const aiVector3D* uv = drawn_in && drawn_in->texcoords ? mesh.mTextureCoords[sets[material]] : nullptr;
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
          if (uv != nullptr) {
            const aiVector3D& t = uv[face.mIndices[k]];
            // A coordinate that is not finite maps nothing (and is no valid glTF): the part keeps
            // its colour, as where a mesh has none (the part's counts no longer match, below).
            if (std::isfinite(t.x) && std::isfinite(t.y)) {
              out_uv.push_back({t.x, 1.0f - t.y});
            } else {
              drawn_in->texcoords = false;
              uv = nullptr;
            }
          }
        }
        if (mirrored) std::swap(out[start + 1], out[start + 2]);
        if (mirrored && uv != nullptr) std::swap(out_uv[start + 1], out_uv[start + 2]);
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) {
      if (node->mChildren[c] != nullptr) stack.emplace_back(node->mChildren[c], X * matrix_of(node->mChildren[c]->mTransformation));
    }
  }

  MeshFile file;
  Welder welder;
  bool any_texcoords = false;
  for (std::size_t material = 0; material < corners.size(); ++material) {
    if (corners[material].empty()) continue;
    MeshPart part;
    part.first = welder.triangles();
    part.count = corners[material].size() / 3;
    part.material = own[material];
    // A mesh without the coordinates came after others had them: the part keeps its colour alone.
    const bool mapped = part.material && part.material->texcoords && texcoords[material].size() == corners[material].size();
    if (part.material && !mapped) part.material->texcoords = false;
    any_texcoords = any_texcoords || mapped;
    for (std::size_t c = 0; c < corners[material].size(); ++c) {
      welder.add_corner(corners[material][c], mapped ? texcoords[material][c] : Welder::Texcoord{});
    }
    file.parts.push_back(std::move(part));
  }
  file.mesh = welder.take();
  if (any_texcoords) file.texcoords = welder.take_texcoords();
  return file;
}

// What the child sends back through its pipe: a status byte (0 read, 1 not read, 2 too many
// triangles), the reason, then the mesh. Native byte order: the same program reads it.
class Writer {
 public:
  template <typename T>
  void put(const T& value) {
    const auto* bytes = reinterpret_cast<const char*>(&value);
    out_.append(bytes, sizeof(T));
  }
  void put_text(const std::string& text) {
    put<std::uint64_t>(text.size());
    out_ += text;
  }
  const std::string& bytes() const { return out_; }

 private:
  std::string out_;
};

class Reader {
 public:
  explicit Reader(std::string_view in) : in_(in) {}
  template <typename T>
  bool get(T& value) {
    if (in_.size() < sizeof(T)) return false;
    static_assert(std::is_trivially_copyable_v<T> || std::is_same_v<T, Eigen::Vector3d>);
    std::memcpy(static_cast<void*>(&value), in_.data(), sizeof(T));  // Eigen's vector is three doubles.
    in_.remove_prefix(sizeof(T));
    return true;
  }
  bool get_text(std::string& text) {
    std::uint64_t size = 0;
    if (!get(size) || in_.size() < size) return false;
    text.assign(in_.substr(0, size));
    in_.remove_prefix(size);
    return true;
  }
  bool done() const { return in_.empty(); }

 private:
  std::string_view in_;
};

std::string encode(const std::optional<MeshFile>& file, const std::string& why, bool too_many) {
  Writer out;
  out.put<std::uint8_t>(file ? 0 : too_many ? 2 : 1);
  out.put_text(why);
  if (!file) return out.bytes();
  out.put<std::uint64_t>(file->mesh.positions.size());
  for (const Eigen::Vector3d& p : file->mesh.positions) out.put(p);
  out.put<std::uint64_t>(file->mesh.triangles.size());
  for (const auto& t : file->mesh.triangles) out.put(t);
  out.put<std::uint64_t>(file->texcoords.size());
  for (const auto& uv : file->texcoords) out.put(uv);
  out.put<std::uint64_t>(file->parts.size());
  for (const MeshPart& part : file->parts) {
    out.put<std::uint64_t>(part.first);
    out.put<std::uint64_t>(part.count);
    out.put<std::uint8_t>(part.material ? 1 : 0);
    if (part.material) {
      out.put_text(part.material->name);
      out.put(part.material->rgba);
      out.put_text(part.material->texture);
      out.put<std::uint8_t>(part.material->texcoords ? 1 : 0);
    }
  }
  return out.bytes();
}

bool decode(std::string_view bytes, std::optional<MeshFile>& file, std::string& why, bool& too_many) {
  Reader in(bytes);
  std::uint8_t status = 0;
  if (!in.get(status) || status > 2 || !in.get_text(why)) return false;
  too_many = status == 2;
  if (status != 0) return in.done();
  MeshFile out;
  std::uint64_t count = 0;
  // Each count is checked against what is left before anything is sized from it.
  if (!in.get(count) || count > bytes.size() / sizeof(Eigen::Vector3d)) return false;
  out.mesh.positions.resize(count);
  for (Eigen::Vector3d& p : out.mesh.positions) {
    if (!in.get(p)) return false;
  }
  if (!in.get(count) || count > bytes.size() / 12) return false;
  out.mesh.triangles.resize(count);
  for (auto& t : out.mesh.triangles) {
    if (!in.get(t)) return false;
    for (std::uint32_t v : t) {
      if (v >= out.mesh.positions.size()) return false;
    }
  }
  if (!in.get(count) || (count != 0 && count != out.mesh.positions.size())) return false;
  out.texcoords.resize(count);
  for (auto& uv : out.texcoords) {
    if (!in.get(uv)) return false;
  }
  if (!in.get(count) || count > bytes.size()) return false;
  for (std::uint64_t i = 0; i < count; ++i) {
    MeshPart part;
    std::uint64_t first = 0, size = 0;
    std::uint8_t has_material = 0;
    if (!in.get(first) || !in.get(size) || !in.get(has_material)) return false;
    if (first > out.mesh.triangles.size() || size > out.mesh.triangles.size() - first) return false;
    part.first = first;
    part.count = size;
    if (has_material != 0) {
      MeshMaterial material;
      std::uint8_t texcoords = 0;
      if (!in.get_text(material.name) || !in.get(material.rgba) || !in.get_text(material.texture) ||
          !in.get(texcoords)) {
        return false;
      }
      material.texcoords = texcoords != 0 && !out.texcoords.empty();
      part.material = std::move(material);
    }
    out.parts.push_back(std::move(part));
  }
  if (!in.done()) return false;
  file = std::move(out);
  return true;
}

}  // namespace

std::optional<MeshFile> read_assimp_mesh(const fs::path& path, MeshFormat format, std::string_view text,
                                         const MeshLimits& limits, std::string& why, bool& too_many) {
  too_many = false;
  if (format == MeshFormat::kCollada) {
    if (auto impossible = impossible_count(text)) {
      why = *impossible;
      return std::nullopt;
    }
  }
  // assimp is not written for hostile files: the mutations of a few fixtures made it overflow its
  // stack on nested nodes, abort on its own assertions, and loop for minutes. It reads in a child
  // process, so that whatever it does to that process, `rdtf import` names the file and goes on;
  // the child's stderr is closed to keep assimp's and a sanitizer's output out of the user's.
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) {
    why = std::string("could not start the reader: ") + std::strerror(errno);
    return std::nullopt;
  }
  const pid_t child = ::fork();
  if (child < 0) {
    why = std::string("could not start the reader: ") + std::strerror(errno);
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    return std::nullopt;
  }
  if (child == 0) {
    ::close(pipe_fds[0]);
    if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) ::dup2(null, STDERR_FILENO);
    const rlimit cpu{kReaderSeconds, kReaderSeconds};
    ::setrlimit(RLIMIT_CPU, &cpu);
#if !RDTF_ADDRESS_SANITIZER
    // Address space for assimp beyond what the process holds: 2 GiB and 40 bytes for each byte of
    // the file (assimp's COLLADA reader holds about 15 for each byte of a large file). A crafted
    // file that would grow without end fails an allocation instead. (AddressSanitizer's shadow
    // memory needs terabytes of address space: no limit in such a build.)
    long pages = 0;
    if (std::FILE* statm = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(statm, "%ld", &pages) != 1) pages = 0;
      std::fclose(statm);
    }
    const rlim_t budget = (rlim_t{2} << 30) + 40 * static_cast<rlim_t>(text.size()) +
                          static_cast<rlim_t>(pages) * static_cast<rlim_t>(::sysconf(_SC_PAGESIZE));
    const rlimit space{budget, budget};
    ::setrlimit(RLIMIT_AS, &space);
#endif
    std::string child_why;
    bool child_too_many = false;
    std::optional<MeshFile> read;
    try {
      read = read_here(path, format, text, limits, child_why, child_too_many);
    } catch (const std::exception& e) {
      child_why = e.what();
    }
    const std::string bytes = encode(read, child_why, child_too_many);
    for (std::size_t sent = 0; sent < bytes.size();) {
      const ssize_t n = ::write(pipe_fds[1], bytes.data() + sent, bytes.size() - sent);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) ::_exit(3);
      sent += static_cast<std::size_t>(n);
    }
    ::_exit(0);
  }
  ::close(pipe_fds[1]);
  // Read everything the child sends until it closes the pipe or the time is up.
  std::string bytes;
  bool timed_out = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kReaderSeconds);
  char buffer[65536];
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      break;
    }
    pollfd poll_fd{pipe_fds[0], POLLIN, 0};
    const int ready = ::poll(&poll_fd, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) {
      timed_out = ready == 0;
      break;
    }
    const ssize_t n = ::read(pipe_fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    bytes.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(pipe_fds[0]);
  if (timed_out) ::kill(child, SIGKILL);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out || (WIFSIGNALED(status) && WTERMSIG(status) == SIGXCPU)) {
    why = "assimp did not finish reading it in " + std::to_string(kReaderSeconds) + " s (stopped)";
    return std::nullopt;
  }
  if (WIFSIGNALED(status)) {
    why = std::string("assimp failed reading it (its reader was ended by ") + ::strsignal(WTERMSIG(status)) +
          ": a file it cannot parse, or one made to crash it)";
    return std::nullopt;
  }
  std::optional<MeshFile> file;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !decode(bytes, file, why, too_many)) {
    why = "assimp failed reading it (its reader stopped without a result: a file it cannot parse, or one made to "
          "crash it)";
    return std::nullopt;
  }
  return file;
}

}  // namespace rdtf::urdf_internal
