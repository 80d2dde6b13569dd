// URDF -> RDTF: a glTF whose every node is typed in extras.RDTF, then the ordinary conversion.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <map>
#include <string_view>

#include <urdf_parser/urdf_parser.h>

#include "../gltf/confined_files.h"
#include "import_internal.h"
#include "rdtf/glb.h"
#include "rdtf/rdtf_extras.h"
#include "rdtf/urdf.h"
#include "urdf_internal.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

using namespace urdf_internal;
namespace fs = std::filesystem;

// The bytes of a file, or an error saying why not in the user's terms: no such file, a folder,
// not a regular file, over the size limit, or what the system says (permission denied). Read
// without blocking on a FIFO put in its place meanwhile.
std::optional<std::string> read_text(const fs::path& path, std::uint64_t max_bytes, Diagnostics& diag) {
  auto refuse = [&](const std::string& why) {
    diag.error(codes::URDF_READ_FAILED, "", "cannot read " + path.string() + ": " + why);
    return std::nullopt;
  };
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (status.type() == fs::file_type::not_found) {
    std::error_code link_error;
    return refuse(fs::is_symlink(fs::symlink_status(path, link_error)) ? "no such file (a symbolic link to nothing)"
                                                                      : "no such file");
  }
  if (error) return refuse(error.message());  // E.g. a folder on the way that may not be entered.
  switch (status.type()) {
    case fs::file_type::regular:
      break;
    case fs::file_type::directory:
      return refuse("it is a folder, not a file");
    case fs::file_type::fifo:
      return refuse("it is a FIFO, not a regular file");
    case fs::file_type::socket:
      return refuse("it is a socket, not a regular file");
    case fs::file_type::block:
    case fs::file_type::character:
      return refuse("it is a device, not a regular file");
    default:
      return refuse("not a regular file");
  }
  if (const auto size = fs::file_size(path, error); !error && size > max_bytes) {
    diag.error(codes::FILE_TOO_LARGE, "", path.string() + " is larger than " + std::to_string(max_bytes) + " bytes");
    return std::nullopt;
  }
  std::vector<std::uint8_t> bytes;
  std::string why;
  if (!internal::read_regular_file(path, max_bytes, bytes, why)) {
    // strerror's "Permission denied" reads as the rest of the sentence.
    if (!why.empty()) why[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(why[0])));
    return refuse(why);
  }
  return std::string(bytes.begin(), bytes.end());
}

Eigen::Isometry3d to_isometry(const urdf::Pose& pose) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  const urdf::Rotation& q = pose.rotation;
  X.linear() = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
  X.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  return X;
}

Eigen::Vector3d to_eigen(const urdf::Vector3& v) { return {v.x, v.y, v.z}; }

// translation and rotation of a glTF node (left out when they are the identity's).
void set_transform(Json& node, const Eigen::Isometry3d& X) {
  const Eigen::Vector3d t = X.translation();
  if (!t.isZero(0)) node["translation"] = vector_to_json(t);
  Eigen::Quaterniond q(X.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  if (!(q.x() == 0 && q.y() == 0 && q.z() == 0)) node["rotation"] = Json::array({q.x(), q.y(), q.z(), q.w()});
}

class Builder {
 public:
  Builder(const fs::path& urdf_path, const UrdfImportOptions& import_options, Diagnostics& diagnostics,
          const Eigen::Matrix3d& axes)
      : urdf(urdf_path), options(import_options), diag(diagnostics), C(axes), writer(document) {}

  const fs::path& urdf;
  const UrdfImportOptions& options;
  Diagnostics& diag;
  const Eigen::Matrix3d C;  // URDF axes -> glTF axes.
  Json document = Json{{"asset", {{"version", "2.0"}, {"generator", "rdtf import (URDF)"}}},
                       {"nodes", Json::array()}};
  GltfMeshWriter writer;  // One buffer for every mesh.
  Json entries = Json::array();
  std::map<std::string, std::size_t> materials;
  std::map<std::string, std::size_t> file_materials;
  std::uint64_t triangles = 0;
  bool ok = true;

  std::size_t add_node(Json node, const char* type, Json extra = nullptr) {
    document["nodes"].push_back(std::move(node));
    const std::size_t index = document["nodes"].size() - 1;
    Json entry{{"node", index}, {"type", type}};
    if (!extra.is_null()) entry[type] = std::move(extra);
    entries.push_back(std::move(entry));
    return index;
  }

  // A mesh file's own colour, one glTF material for each name and colour.
  // A texture maps the image as its author painted it: the colour factor is white (with the
  // material's opacity), as Blender and glTF viewers show a textured COLLADA or OBJ material.
  std::size_t material_for(const MeshMaterial& material, std::optional<std::size_t> texture = std::nullopt) {
    const std::string key = material.name + '\0' + Json(material.rgba).dump() + '\0' +
                            (texture ? std::to_string(*texture) : std::string());
    if (const auto found = file_materials.find(key); found != file_materials.end()) return found->second;
    const std::array<double, 4> factor =
        texture ? std::array<double, 4>{1.0, 1.0, 1.0, material.rgba[3]} : material.rgba;
    Json out{{"name", material.name},
             {"pbrMetallicRoughness", {{"baseColorFactor", factor}, {"metallicFactor", 0.0}}}};
    if (texture) out["pbrMetallicRoughness"]["baseColorTexture"] = Json{{"index", *texture}};
    if (material.rgba[3] < 1) out["alphaMode"] = "BLEND";
    document["materials"].push_back(std::move(out));
    return file_materials[key] = document["materials"].size() - 1;
  }

  std::optional<std::size_t> material_for(const urdf::Visual& visual) {
    if (!visual.material || visual.material_name.empty()) return std::nullopt;
    if (const auto found = materials.find(visual.material_name); found != materials.end()) return found->second;
    const urdf::Color& c = visual.material->color;
    auto clamp = [](float v) { return std::min(1.0, std::max(0.0, static_cast<double>(v))); };
    Json material{{"name", visual.material_name},
                  {"pbrMetallicRoughness",
                   {{"baseColorFactor", Json::array({clamp(c.r), clamp(c.g), clamp(c.b), clamp(c.a)})},
                    {"metallicFactor", 0.0}}}};
    if (clamp(c.a) < 1) material["alphaMode"] = "BLEND";
    document["materials"].push_back(std::move(material));
    return materials[visual.material_name] = document["materials"].size() - 1;
  }

  // The glTF texture of a part's material, or nothing (and a warning, once for each mesh file and
  // texture) where the image is not there, not PNG or JPEG (all glTF carries), or not mapped.
  std::map<std::string, std::optional<std::size_t>> textures;
  std::optional<std::size_t> texture_for(const MeshFile& file, const MeshMaterial& material, const std::string& pointer,
                                         int row) {
    if (material.texture.empty()) return std::nullopt;
    const std::string key = file.source.string() + '\0' + material.texture + '\0' + (material.texcoords ? "1" : "0");
    if (const auto found = textures.find(key); found != textures.end()) return found->second;
    std::string why;
    const auto texture = material.texcoords ? read_texture(file.source, material.texture, why) : std::nullopt;
    if (!material.texcoords) why = "the mesh has no texture coordinates for it (or some that are not finite)";
    if (!texture) {
      diag.warning_at_line(codes::URDF_TEXTURE_SKIPPED, pointer, row,
                           "mesh '" + file.source.string() + "': the texture '" + material.texture + "' of material '" +
                               material.name + "' is not applied: " + why + "; the part keeps the material's colour");
    }
    return textures[key] = texture;
  }

  // A texture named in a mesh file, found as the file names it (relative to the file's folder, an
  // absolute path, file://, with %-escapes or backslashes), and its bytes put in the buffer.
  std::optional<std::size_t> read_texture(const fs::path& mesh_path, const std::string& name, std::string& why) {
    if (name.starts_with('*')) {
      why = "it is embedded in the mesh file, which import does not read";
      return std::nullopt;
    }
    // As assimp gives it (it does not decode a COLLADA image's URI), then decoded, then with a
    // Windows exporter's backslashes as slashes.
    std::string forward = percent_decoded(name);
    std::replace(forward.begin(), forward.end(), '\\', '/');
    std::optional<fs::path> found;
    for (const std::string& spelling : {name, percent_decoded(name), forward}) {
      std::string not_here;
      found = resolve_mesh_path(spelling, mesh_path.parent_path(), not_here, "image");
      if (found) break;
      if (why.empty()) why = not_here;
    }
    if (!found) return std::nullopt;
    why.clear();
    // Only an image inside the folder the URDF and the mesh file share is read: a crafted mesh
    // naming a photo elsewhere on the machine (~/Pictures/...) gets nothing of it into the model.
    std::error_code error;
    const fs::path image = fs::weakly_canonical(fs::absolute(*found, error), error);
    const fs::path shared = common_folder(fs::weakly_canonical(fs::absolute(urdf, error), error).parent_path(),
                                          fs::weakly_canonical(fs::absolute(mesh_path, error), error).parent_path());
    if (error || !within(image, shared)) {
      why = found->string() + " is outside " + shared.string() +
            ", the folder the URDF and the mesh file share (an image elsewhere is not read)";
      return std::nullopt;
    }
    if (const auto known = image_textures.find(image.string()); known != image_textures.end()) return known->second;
    Diagnostics read_diag(found->string());
    const auto bytes = read_text(*found, options.convert.limits.max_file_bytes, read_diag);
    if (!bytes) {
      why = read_diag.all().front().message;
      return std::nullopt;
    }
    // Only an image is copied into the model: a crafted mesh naming some other file of the user's
    // as its texture gets nothing of it into the output.
    const char* mime = bytes->starts_with("\x89PNG\r\n\x1a\n") ? "image/png"
                       : bytes->starts_with("\xFF\xD8\xFF")      ? "image/jpeg"
                                                                    : nullptr;
    if (mime == nullptr) {
      why = found->string() + " is not a PNG or JPEG image (the image formats glTF carries)";
      return std::nullopt;
    }
    return image_textures[image.string()] = writer.add_texture(*bytes, mime, found->filename().string());
  }
  std::map<std::string, std::size_t> image_textures;  // By the image's canonical path: one copy each.

  // The deepest folder holding both `a` and `b` (absolute, normal paths).
  static fs::path common_folder(const fs::path& a, const fs::path& b) {
    fs::path out;
    for (auto i = a.begin(), j = b.begin(); i != a.end() && j != b.end() && *i == *j; ++i, ++j) out /= *i;
    return out;
  }
  // Whether `path` is `folder` or below it, component by component.
  static bool within(const fs::path& path, const fs::path& folder) {
    auto i = path.begin();
    for (auto j = folder.begin(); j != folder.end(); ++j, ++i) {
      if (i == path.end() || *i != *j) return false;
    }
    return true;
  }

  static MeshFile whole(TriangleMesh mesh) {
    const std::size_t count = mesh.triangles.size();
    MeshFile file;
    file.mesh = std::move(mesh);
    file.parts = {MeshPart{0, count, std::nullopt}};
    return file;
  }

  // The triangles of one <visual> (or <collision>) geometry in its own frame, or nothing.
  // `mass_from`: why the link's mass does not come from this geometry ("the link's mass is its
  // <inertial>"), or null where it does.
  std::optional<MeshFile> geometry(const urdf::Geometry& g, const std::string& pointer, int row,
                                   const char* mass_from, Eigen::Vector3d& scale) {
    auto skip = [&](const std::string& why) {
      diag.warning_at_line(codes::URDF_GEOMETRY_SKIPPED, pointer, row, why + "; this geometry is skipped");
      return std::nullopt;
    };
    scale = Eigen::Vector3d::Ones();
    if (const auto why = degenerate_shape(g)) {
      diag.warning_at_line(codes::URDF_SHAPE_DEGENERATE, pointer, row, *why + "; this geometry is skipped, the link is kept");
      return std::nullopt;
    }
    switch (g.type) {
      // Sizes were checked in the XML (scan_urdf_xml): finite and not negative; 0 is skipped above.
      case urdf::Geometry::BOX:
        return whole(box_mesh(to_eigen(static_cast<const urdf::Box&>(g).dim)));
      case urdf::Geometry::CYLINDER: {
        const auto& cylinder = static_cast<const urdf::Cylinder&>(g);
        return whole(cylinder_mesh(cylinder.radius, cylinder.length));
      }
      case urdf::Geometry::SPHERE:
        return whole(sphere_mesh(static_cast<const urdf::Sphere&>(g).radius));
      case urdf::Geometry::MESH:
        break;
    }
    const auto& mesh = static_cast<const urdf::Mesh&>(g);
    const MeshFormat format = mesh_format(mesh.filename);
    if (format == MeshFormat::kOther) {
      diag.warning_at_line(codes::URDF_MESH_FORMAT_UNSUPPORTED, pointer, row,
                           "mesh '" + mesh.filename + "' is none of the formats import reads (" +
                               kMeshFormatsRead + "); skipped");
      return std::nullopt;
    }
    std::string why;
    const auto path = resolve_mesh_path(mesh.filename, urdf_folder(), why);
    // A published robot often comes without its mesh package, or with a mesh no tool can read.
    // Where the link's mass is its <inertial>, such a mesh costs only its look: a warning, and
    // the rest is imported. Where the mass would be computed from the mesh, it cannot be: an error.
    const auto unusable = [&](const char* code, const std::string& message) {
      if (mass_from != nullptr) {
        diag.warning_at_line(code, pointer, row, message + "; this geometry is skipped (" + mass_from + ")");
      } else {
        diag.error_at_line(code, pointer, row, message + " (the link has no <inertial>: its mass would come from this mesh)");
        ok = false;
      }
      return std::nullopt;
    };
    if (!path) return unusable(codes::URDF_MESH_NOT_FOUND, why);
    Diagnostics read_diag(path->string());
    const auto bytes = read_text(*path, options.convert.limits.max_file_bytes, read_diag);
    if (!bytes) {
      const Diagnostic& failure = read_diag.all().front();
      const std::string message = "mesh '" + mesh.filename + "': " + failure.message;
      // A mesh that is there, a regular file this process may read, and still could not be read
      // failed for a reason of the system's (out of descriptors or memory, an I/O error), not of the
      // robot's: the import fails rather than leave the geometry out of a model that looks whole.
      std::error_code type_error;
      if (failure.code == codes::URDF_READ_FAILED && fs::is_regular_file(*path, type_error) &&
          ::access(path->c_str(), R_OK) == 0) {
        diag.error_at_line(codes::URDF_READ_FAILED, pointer, row,
                           message + " (the file is there and readable: the system could not read it now)");
        ok = false;
        return std::nullopt;
      }
      return unusable(codes::URDF_MESH_NOT_FOUND, message);
    }
    std::optional<MeshFile> read;
    if (format == MeshFormat::kStl) {
      auto stl = parse_stl(std::vector<std::uint8_t>(bytes->begin(), bytes->end()), why);
      if (stl) read = whole(std::move(*stl));
    } else {
      bool too_many = false;
      const MeshLimits limits{options.convert.limits.max_file_bytes,
                              options.convert.limits.max_triangles - std::min(triangles, options.convert.limits.max_triangles)};
      read = read_assimp_mesh(*path, format, *bytes, limits, why, too_many);
      if (too_many) {
        diag.error_at_line(codes::TOO_MANY_TRIANGLES, pointer, row,
                           "mesh '" + path->string() + "': the URDF's meshes have more than " +
                               std::to_string(options.convert.limits.max_triangles) +
                               " triangles with this file's (each instance of a mesh counted)");
        ok = false;
        return std::nullopt;
      }
      if (!read) why = std::string(format == MeshFormat::kCollada ? "COLLADA" : "OBJ") + ": " + why;
    }
    if (!read) return unusable(codes::URDF_MESH_INVALID, "mesh '" + path->string() + "': " + why);
    read->source = *path;
    if (read->mesh.triangles.empty()) return skip("mesh '" + path->string() + "' has no triangles");
    scale = to_eigen(mesh.scale);
    return read;
  }

  // Whether import can read this geometry: a shape with sizes, or a mesh of a format import reads
  // that is there. (A file that is there but cannot be read is still an error where the mass must
  // come from it.)
  bool readable(const urdf::GeometrySharedPtr& g) const {
    if (!g || degenerate_shape(*g)) return false;
    if (g->type != urdf::Geometry::MESH) return true;
    const auto& mesh = static_cast<const urdf::Mesh&>(*g);
    std::string why;
    return mesh_format(mesh.filename) != MeshFormat::kOther && resolve_mesh_path(mesh.filename, urdf_folder(), why);
  }

  // Where relative mesh file names start: the URDF's folder.
  fs::path urdf_folder() const { return urdf.parent_path().empty() ? fs::path(".") : urdf.parent_path(); }

  // The link's visual node with a mesh node per geometry, or nothing when it has none.
  // `mass_from`: why the link's mass is not its geometry's (an <inertial>, or massless on a fixed
  // joint), so that a geometry that cannot be read costs only its look; null where it is.
  std::optional<std::size_t> visuals(const urdf::Link& link, const XmlLink& xml, const char* mass_from) {
    const bool mass_authored = mass_from != nullptr;
    // The <collision> geometry stands in for the <visual> where that gives nothing to show, or
    // where the mass comes from the geometry and a visual cannot be read: a published robot's
    // visuals are often COLLADA or missing while its collision meshes are STL (UR, Fetch, TIAGo).
    const auto all_readable = [&](const auto& elements) {
      return std::all_of(elements.begin(), elements.end(), [&](const auto& e) { return readable(e->geometry); });
    };
    const auto any_readable = [&](const auto& elements) {
      return std::any_of(elements.begin(), elements.end(), [&](const auto& e) { return readable(e->geometry); });
    };
    bool use_collision = false;
    if (link.visual_array.empty()) {
      use_collision = !link.collision_array.empty();
      if (use_collision) {
        diag.info(codes::URDF_COLLISION_AS_VISUAL, link_pointer(link.name),
                  "link '" + link.name + "' has no <visual>: its <collision> geometry is its mesh");
      }
    } else if (any_readable(link.collision_array) &&
               (mass_authored ? !any_readable(link.visual_array) : !all_readable(link.visual_array))) {
      use_collision = true;
      std::string unread;  // The first visual import cannot read, by its file where it has one.
      for (std::size_t i = 0; i < link.visual_array.size(); ++i) {
        const urdf::GeometrySharedPtr& g = link.visual_array[i]->geometry;
        if (readable(g)) continue;
        // A shape of size 0 (pybullet's laikago draws its toes as spheres of radius 0) is said
        // of itself, with its line, as where the visual is drawn.
        const auto degenerate = g ? degenerate_shape(*g) : std::nullopt;
        const std::string visual_pointer = link_pointer(link.name) + "/visual[" + std::to_string(i + 1) + "]";
        const int visual_row = i < xml.visual_rows.size() ? xml.visual_rows[i] : xml.row;
        if (degenerate) {
          diag.warning_at_line(codes::URDF_SHAPE_DEGENERATE, visual_pointer, visual_row,
                               *degenerate + "; this geometry is skipped, the link is kept");
        }
        // A visual mesh that is not there, or of a format import does not read, loses the look
        // its author gave the link: a warning of its own (a TurtleBot3 whose visual meshes were
        // missing was drawn in its collision boxes with nothing said but an info).
        if (g && g->type == urdf::Geometry::MESH) {
          const std::string& filename = static_cast<const urdf::Mesh&>(*g).filename;
          std::string why;
          if (mesh_format(filename) == MeshFormat::kOther) {
            diag.warning_at_line(codes::URDF_MESH_FORMAT_UNSUPPORTED, visual_pointer, visual_row,
                                 "mesh '" + filename + "' is none of the formats import reads (" + kMeshFormatsRead +
                                     "): link '" + link.name + "' is drawn with its <collision> geometry");
          } else if (!resolve_mesh_path(filename, urdf_folder(), why)) {
            diag.warning_at_line(codes::URDF_MESH_NOT_FOUND, visual_pointer, visual_row,
                                 why + ": link '" + link.name + "' is drawn with its <collision> geometry");
          }
        }
        if (!unread.empty()) continue;
        unread = "<visual> " + std::to_string(i + 1);
        if (degenerate) unread += " (a shape of size 0)";
        if (g && g->type == urdf::Geometry::MESH) unread += " ('" + static_cast<const urdf::Mesh&>(*g).filename + "')";
      }
      diag.info(codes::URDF_COLLISION_AS_VISUAL, link_pointer(link.name),
                "link '" + link.name + "': import cannot read its " + unread +
                    " (it reads " + kMeshFormatsRead + " files that are there, and boxes, cylinders and spheres with a volume)" +
                    (mass_authored ? std::string(", nor any other <visual>")
                                   : std::string(", and the link's mass comes from its geometry")) +
                    ": its <collision> geometry is its mesh");
    } else if (!link.collision_array.empty() && !any_readable(link.visual_array) &&
               !any_readable(link.collision_array)) {
      // Nothing to show, and the collision geometry that would have stood in cannot either: say
      // why, or a missing collision mesh goes unmentioned (z1's gripper, a quadrotor's base).
      for (std::size_t i = 0; i < link.collision_array.size(); ++i) {
        const urdf::GeometrySharedPtr& g = link.collision_array[i]->geometry;
        if (!g || g->type != urdf::Geometry::MESH) continue;
        const std::string& filename = static_cast<const urdf::Mesh&>(*g).filename;
        std::string why = "is none of the formats import reads (" + std::string(kMeshFormatsRead) + ")";
        const bool missing = mesh_format(filename) != MeshFormat::kOther && !resolve_mesh_path(filename, urdf_folder(), why);
        if (missing) why = "cannot be read: " + why;
        diag.warning_at_line(missing ? codes::URDF_MESH_NOT_FOUND : codes::URDF_GEOMETRY_SKIPPED,
                             link_pointer(link.name) + "/collision[" + std::to_string(i + 1) + "]",
                             i < xml.collision_rows.size() ? xml.collision_rows[i] : xml.row,
                             "link '" + link.name + "' has no <visual> import can read, and its <collision> mesh '" +
                                 filename + "', which would stand in, " + why + ": the link has no geometry");
        break;
      }
    }
    std::vector<std::size_t> mesh_nodes;
    const std::size_t count = use_collision ? link.collision_array.size() : link.visual_array.size();
    for (std::size_t i = 0; i < count; ++i) {
      const urdf::GeometrySharedPtr& g = use_collision ? link.collision_array[i]->geometry : link.visual_array[i]->geometry;
      const urdf::Pose& origin = use_collision ? link.collision_array[i]->origin : link.visual_array[i]->origin;
      const std::string element = use_collision ? "collision" : "visual";
      const std::vector<int>& rows = use_collision ? xml.collision_rows : xml.visual_rows;
      const int row = i < rows.size() ? rows[i] : xml.row;
      const std::string pointer = link_pointer(link.name) + "/" + element + "[" + std::to_string(i + 1) + "]";
      if (!g) continue;
      Eigen::Vector3d scale;
      auto mesh = geometry(*g, pointer, row, mass_from, scale);
      if (!mesh) continue;
      triangles += mesh->mesh.triangles.size();
      if (triangles > options.convert.limits.max_triangles) {
        diag.error(codes::TOO_MANY_TRIANGLES, pointer, "more than " + std::to_string(options.convert.limits.max_triangles) + " triangles");
        ok = false;
        return std::nullopt;
      }
      std::string name = use_collision ? link.collision_array[i]->name : link.visual_array[i]->name;
      if (name.empty()) name = link.name + "_" + element + (count > 1 ? "_" + std::to_string(i + 1) : "");
      // A part in a colour of its own keeps it; the rest take the visual's <material> (RViz's
      // rule). A collision geometry standing in has no <material>. The visual's is written only
      // where a part takes it: a glTF material no primitive uses is clutter.
      const auto fallback = [&]() -> std::optional<std::size_t> {
        return use_collision ? std::nullopt : material_for(*link.visual_array[i]);
      };
      std::vector<GltfMeshWriter::Primitive> primitives;
      for (const MeshPart& part : mesh->parts) {
        const auto texture = part.material ? texture_for(*mesh, *part.material, pointer, row) : std::nullopt;
        primitives.push_back({part.first, part.count,
                              part.material ? std::optional(material_for(*part.material, texture)) : fallback(),
                              texture.has_value()});
      }
      const std::size_t mesh_index = writer.add_mesh(mesh->mesh, mesh->texcoords, name, primitives);
      Json node{{"name", name}, {"mesh", mesh_index}};
      Eigen::Isometry3d X = to_isometry(origin);
      X.linear() = C * X.linear();
      X.translation() = C * X.translation();
      set_transform(node, X);
      if (scale != Eigen::Vector3d::Ones()) node["scale"] = vector_to_json(scale);
      mesh_nodes.push_back(add_node(std::move(node), "mesh"));
    }
    if (mesh_nodes.empty()) return std::nullopt;
    return add_node(Json{{"name", link.name + "_visual"}, {"children", mesh_nodes}}, "visual");
  }

  Json joint_json(const urdf::Joint& joint, const XmlJoint& xml) {
    static const std::map<int, const char*> kinds{
        {urdf::Joint::FIXED, "fixed"},         {urdf::Joint::REVOLUTE, "revolute"},
        {urdf::Joint::CONTINUOUS, "continuous"}, {urdf::Joint::PRISMATIC, "prismatic"},
        {urdf::Joint::FLOATING, "floating"},   {urdf::Joint::PLANAR, "planar"}};
    Json out{{"type", kinds.at(joint.type)}};
    if (joint.type != urdf::Joint::FIXED && joint.type != urdf::Joint::FLOATING) {
      out["axis"] = vector_to_json(C * to_eigen(joint.axis));
    }
    // URDF reads lower and upper on revolute and prismatic joints only (a continuous joint turns
    // freely whatever its <limit> says: a wheel's <limit effort velocity/> is no range of motion),
    // and effort and velocity on the three that move.
    const bool bounded = joint.type == urdf::Joint::REVOLUTE || joint.type == urdf::Joint::PRISMATIC;
    if (joint.limits && (bounded || joint.type == urdf::Joint::CONTINUOUS)) {
      if (bounded) {
        out["lower"] = joint.limits->lower;
        out["upper"] = joint.limits->upper;
      }
      if (joint.limits->effort > 0) out["effort"] = joint.limits->effort;
      if (joint.limits->velocity > 0) out["velocity"] = joint.limits->velocity;
    }
    out["friction"] = joint.dynamics ? joint.dynamics->friction : 0.0;
    out["damping"] = joint.dynamics ? joint.dynamics->damping : 0.0;
    out["springStiffness"] = 0.0;
    // A mimic joint moves with another (a gripper's second finger): without the coupling it moves
    // on its own in every simulation, which the user must hear of. The other two change nothing
    // the dynamics see.
    if (joint.mimic) {
      diag.warning_at_line(codes::URDF_MIMIC_IGNORED, joint_pointer(joint.name) + "/mimic", xml.mimic_row,
                   "joint '" + joint.name + "' mimics joint '" + joint.mimic->joint_name + "' (multiplier " +
                       exact_number(joint.mimic->multiplier) + ", offset " + exact_number(joint.mimic->offset) +
                       "): RDTF has no coupled joints, so it is imported as a joint of its own that moves freely");
    }
    if (joint.safety || joint.calibration) {
      const std::string which = joint.safety && joint.calibration ? "<safety_controller> and <calibration>"
                                : joint.safety                    ? "<safety_controller>"
                                                                  : "<calibration>";
      diag.add_at_line(Severity::kInfo, codes::URDF_IGNORED, joint_pointer(joint.name), xml.ignored_row,
                "joint '" + joint.name + "': " + which + " has no RDTF equivalent and is not imported");
    }
    return out;
  }

  Json inertial_json(const urdf::Inertial& in) {
    Eigen::Matrix3d I;
    I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
    const Eigen::Matrix3d R = C * to_isometry(in.origin).linear();
    return Json{{"mass", in.mass},
                {"gravityCenter", vector_to_json(C * to_eigen(in.origin.position))},
                {"inertia", inertia_to_json(R * I * R.transpose())},
                {"frame", "link"}};
  }
};

// urdfdom's refusal, at the element its messages name ("... for joint [elbow]", "... for Link
// [arm]", "material 'red' is not unique") with that element's line, else at <robot>; its
// messages are included.
void report_urdfdom_failure(const XmlRobot& xml, const ConsoleMessages& messages, Diagnostics& diag) {
  std::map<std::string, int> link_rows, joint_rows;
  for (const XmlLink& link : xml.links) link_rows[link.name] = link.row;
  for (const XmlJoint& joint : xml.joints) joint_rows[joint.name] = joint.row;
  struct Marker {
    const char* text;  // Lower case, before the name.
    char close;        // After the name.
    const std::map<std::string, int>& rows;
    std::string (*pointer)(const std::string&);
  };
  const Marker markers[] = {
      {"joint [", ']', joint_rows, joint_pointer},
      {"joint  [", ']', joint_rows, joint_pointer},
      {"link [", ']', link_rows, link_pointer},
      {"material '", '\'', xml.material_rows,
       [](const std::string& name) { return "/robot/material[@name='" + name + "']"; }},
  };
  std::string pointer = "/robot";
  int row = xml.row;
  bool placed = false;
  for (const std::string& message : messages.errors) {
    std::string lower = message;
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    for (const Marker& marker : markers) {
      const auto found = lower.find(marker.text);
      if (found == std::string::npos) continue;
      const auto open = found + std::string(marker.text).size();
      const auto close = message.find(marker.close, open);
      if (close == std::string::npos) continue;
      const std::string name = message.substr(open, close - open);
      if (const auto known = marker.rows.find(name); known != marker.rows.end()) {
        pointer = marker.pointer(name);
        row = known->second;
        placed = true;
        break;
      }
    }
    if (placed) break;
  }
  std::string said;
  for (const std::string& message : messages.errors) said += (said.empty() ? "" : "; ") + message;
  if (said.empty()) said = "it gives no reason";
  diag.error_at_line(codes::URDF_PARSE_FAILED, pointer, row, "urdfdom cannot read it: " + said);
}

// The first bytes of a file (at most n) and its size, read without blocking on a FIFO and only from
// a regular file: enough to tell what it is before reading a large one whole. Empty when it cannot
// be read; read_text then says why.
struct FileHead {
  std::string bytes;
  std::uint64_t size = 0;
};
FileHead head_of(const fs::path& path, std::size_t n) {
  FileHead head;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) return head;
  struct stat info {};
  if (::fstat(fd, &info) == 0 && S_ISREG(info.st_mode)) {
    head.size = static_cast<std::uint64_t>(info.st_size);
    head.bytes.resize(std::min<std::uint64_t>(n, head.size));
    std::size_t got = 0;
    while (got < head.bytes.size()) {
      const ssize_t r = ::read(fd, head.bytes.data() + got, head.bytes.size() - got);
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) break;
      got += static_cast<std::size_t>(r);
    }
    head.bytes.resize(got);
  }
  ::close(fd);
  return head;
}

// The first bytes as the user would recognise them: the text up to the line's end when printable,
// else the bytes in hex.
std::string quoted_start(std::string_view text) {
  const std::string_view line = text.substr(0, std::min<std::size_t>(text.find_first_of("\r\n"), 40));
  const bool printable = std::all_of(line.begin(), line.end(), [](char c) {
    return static_cast<unsigned char>(c) >= 0x20 && static_cast<unsigned char>(c) < 0x7F;
  });
  if (printable && !line.empty()) return "'" + std::string(line) + "'";
  std::string hex = "the bytes";
  for (std::size_t i = 0; i < std::min<std::size_t>(text.size(), 8); ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    hex += std::string(" 0x") + "0123456789ABCDEF"[byte >> 4] + "0123456789ABCDEF"[byte & 0xF];
  }
  return hex;
}

// Which UTF-16 the file is in, when its first bytes say so (a byte order mark, or '<' beside a
// zero byte): XML, in an encoding URDF names (glTF names) cannot keep. TinyXML said "line 0: Error
// document empty" of a big-endian one.
std::optional<std::string> utf16_order(const FileHead& head) {
  const std::string_view text = head.bytes;
  if (text.starts_with("\xFF\xFE") || text.starts_with(std::string_view("<\0", 2))) return "little-endian";
  if (text.starts_with("\xFE\xFF") || text.starts_with(std::string_view("\0<", 2))) return "big-endian";
  return std::nullopt;
}

// What a file given as a URDF is instead, when its first bytes say so: a GLB, JSON (a .gltf), an
// STL mesh, or no XML at all. TinyXML reported each as "line 0: Error document empty" or a byte that
// is not UTF-8, and only after reading the whole file (2.3 s and 400 MB for a 200 MB mesh).
std::optional<std::string> other_kind_of_file(const FileHead& head) {
  const std::string kNotUrdf = "not a URDF (an XML <robot> element)";
  const std::string kNamesMeshes = ": a URDF names its meshes in <mesh filename=\"...\"/>";
  const std::string_view text = head.bytes;
  if (text.starts_with("glTF")) return "a GLB (binary glTF) file, " + kNotUrdf + ": rdtf convert reads it";
  // A binary STL is an 80-byte header, a count, and 50 bytes a triangle: its size says so.
  if (text.size() >= 84) {
    std::uint32_t triangles = 0;
    std::memcpy(&triangles, text.data() + 80, sizeof triangles);
    if (head.size == 84 + 50 * std::uint64_t{triangles}) {
      return "a binary STL mesh, " + kNotUrdf + kNamesMeshes;
    }
  }
  if (utf16_order(head)) return std::nullopt;  // XML in another encoding: said by its caller.
  std::size_t first = text.starts_with("\xEF\xBB\xBF") ? 3 : 0;
  first = text.find_first_not_of(" \t\r\n", first);
  if (first == std::string_view::npos) return std::nullopt;  // Empty or blank: said after reading it.
  const std::string_view rest = text.substr(first);
  if (rest[0] == '{' || rest[0] == '[') {
    return rest.find("\"asset\"") != std::string_view::npos ? "a glTF file (JSON), " + kNotUrdf + ": rdtf convert reads it"
                                                             : "JSON, " + kNotUrdf;
  }
  if (rest.starts_with("solid")) {
    return "an STL mesh (ASCII), " + kNotUrdf + kNamesMeshes;
  }
  if (rest[0] != '<') {
    return "not XML: it starts with " + quoted_start(rest) + " where a URDF (an XML <robot> element) starts with '<'";
  }
  return std::nullopt;
}

}  // namespace

std::optional<Conversion> import_urdf(const fs::path& urdf, const UrdfImportOptions& options,
                                      Diagnostics& diag) {
  diag.set_file(urdf.string());
  // Told from the first bytes, before a large file is read whole.
  const FileHead head = head_of(urdf, 4096);
  if (const auto order = utf16_order(head)) {
    diag.error(codes::URDF_NOT_UTF8, "",
               "the file is XML in UTF-16 (" + *order +
                   "), which is not UTF-8 (URDF names become glTF names, which must be UTF-8): save it as UTF-8");
    return std::nullopt;
  }
  if (const auto kind = other_kind_of_file(head)) {
    diag.error(codes::URDF_NOT_A_ROBOT, "", "this is " + *kind);
    return std::nullopt;
  }
  const auto file_text = read_text(urdf, options.convert.limits.max_file_bytes, diag);
  if (!file_text) return std::nullopt;
  const auto text = urdf_text_as_utf8(*file_text, diag);
  if (!text) return std::nullopt;
  const auto xml = scan_urdf_xml(*text, diag);
  if (!xml) return std::nullopt;
  urdf::ModelInterfaceSharedPtr model;
  const urdf_internal::FlatRelease flat_release(model);
  const ConsoleMessages messages = capture_console([&] { model = urdf::parseURDF(*text); });
  // urdfdom 3.0 keeps a link whose <inertial>, <visual> or <collision> it could not read (without
  // it): that is a failure too. The scan above catches what we know of first.
  const bool link_incomplete = std::any_of(messages.errors.begin(), messages.errors.end(), [](const std::string& m) {
    return m.find("for Link [") != std::string::npos;
  });
  if (!model || link_incomplete) {
    report_urdfdom_failure(*xml, messages, diag);
    return std::nullopt;
  }

  Builder b(urdf, options, diag,
            options.z_up ? Eigen::Matrix3d::Identity() : Eigen::Matrix3d(y_up_to_z_up().transpose()));

  // The scan and urdfdom must agree on every name (they read the same UTF-8 text); should they
  // ever not, that is an error here rather than a lookup of something urdfdom never made.
  bool agreed = true;
  for (const XmlLink& link : xml->links) {
    if (model->getLink(link.name)) continue;
    diag.error_at_line(codes::URDF_PARSE_FAILED, link_pointer(link.name), link.row,
                       "urdfdom reads no link named '" + link.name + "'");
    agreed = false;
  }
  for (const XmlJoint& joint : xml->joints) {
    if (model->getJoint(joint.name)) continue;
    diag.error_at_line(codes::URDF_PARSE_FAILED, joint_pointer(joint.name), joint.row,
                       "urdfdom reads no joint named '" + joint.name + "'");
    agreed = false;
  }
  if (!agreed) return std::nullopt;

  // Links depth first from the root, children in document order.
  std::map<std::string, std::size_t> xml_link;
  for (std::size_t i = 0; i < xml->links.size(); ++i) xml_link[xml->links[i].name] = i;
  std::map<std::string, std::vector<std::size_t>> child_joints;
  for (std::size_t j = 0; j < xml->joints.size(); ++j) child_joints[xml->joints[j].parent].push_back(j);

  // Links joined by fixed joints move as one body. Where a link of that body has an <inertial>
  // with mass, a link of it without one is massless, as URDF reads it, whether it is the root or
  // moves on a joint: the body has its mass (Clearpath's Husky keeps base_link's in an
  // inertial_link fixed to it, and its geometry's mass would have added 126 kg to the robot).
  std::vector<std::size_t> weld(xml->links.size());
  for (std::size_t i = 0; i < weld.size(); ++i) weld[i] = i;
  const auto group = [&](std::size_t i) {
    while (weld[i] != i) i = weld[i] = weld[weld[i]];
    return i;
  };
  for (const XmlJoint& joint : xml->joints) {
    if (model->getJoint(joint.name)->type == urdf::Joint::FIXED) weld[group(xml_link.at(joint.parent))] = group(xml_link.at(joint.child));
  }
  std::map<std::size_t, std::string> carried_by;  // Body -> its first link with a mass, in document order.
  for (std::size_t i = 0; i < xml->links.size(); ++i) {
    const urdf::LinkConstSharedPtr link = model->getLink(xml->links[i].name);
    if (link->inertial && link->inertial->mass > 0) carried_by.try_emplace(group(i), xml->links[i].name);
  }

  std::map<std::string, std::size_t> link_node;
  std::vector<std::pair<std::size_t, std::string>> joint_children;  // (joint node, child link)
  std::vector<std::pair<std::string, const XmlJoint*>> stack{{xml->links[xml->root].name, nullptr}};
  while (!stack.empty()) {
    const auto [name, via] = stack.back();
    stack.pop_back();
    urdf::LinkConstSharedPtr link = model->getLink(name);
    Json node{{"name", name}};
    if (via != nullptr) set_transform(node, conjugate(b.C, to_isometry(model->getJoint(via->name)->parent_to_joint_origin_transform)));
    const std::size_t index = b.add_node(std::move(node), "link");
    link_node[name] = index;
    Json children = Json::array();
    // A link without <inertial> on a fixed joint, or fixed to links that carry its body's mass, is
    // massless (below), so its geometry is looks only.
    const bool fixed_massless = !link->inertial && via != nullptr && model->getJoint(via->name)->type == urdf::Joint::FIXED;
    const auto carrier = carried_by.find(group(xml_link.at(name)));
    const bool body_massive = !link->inertial && !fixed_massless && carrier != carried_by.end();
    const char* mass_from = link->inertial    ? "the link's mass is its <inertial>"
                            : fixed_massless ? "the link has no <inertial> and is massless on its fixed joint"
                            : body_massive   ? "the link has no <inertial>, and the links fixed to it carry its body's mass"
                                             : nullptr;
    if (const auto visual = b.visuals(*link, xml->links[xml_link.at(name)], mass_from)) {
      children.push_back(*visual);
    }
    const auto& joints = child_joints[name];
    for (std::size_t j : joints) {
      const XmlJoint& joint = xml->joints[j];
      const std::size_t joint_node = b.add_node(Json{{"name", joint.name}}, "joint", b.joint_json(*model->getJoint(joint.name), joint));
      children.push_back(joint_node);
      joint_children.emplace_back(joint_node, joint.child);
    }
    for (auto it = joints.rbegin(); it != joints.rend(); ++it) stack.emplace_back(xml->joints[*it].child, &xml->joints[*it]);
    if (link->inertial) {  // Checked in the XML: a finite mass of 0 or more, a finite tensor.
      children.push_back(b.add_node(Json{{"name", name + "_inertial"}}, "inertial", b.inertial_json(*link->inertial)));
    } else if (body_massive) {
      children.push_back(b.add_node(Json{{"name", name + "_inertial"}}, "inertial", b.inertial_json(urdf::Inertial())));
      diag.info(codes::URDF_NO_INERTIAL, link_pointer(name),
                std::string(via == nullptr ? "root link '" : "link '") + name + "' has no <inertial>, and link '" +
                    carrier->second + "', fixed to it, carries the mass of the body they make: it is massless, as "
                    "URDF reads it");
    } else if (fixed_massless) {
      // URDF reads a link without <inertial> as massless. On a fixed joint (a sensor or tool
      // frame, a collision helper) that is what it is: it adds nothing to the body it is fixed to,
      // as in urdfdom, Gazebo and Drake. Its geometry must not make up mass the robot lacks.
      children.push_back(b.add_node(Json{{"name", name + "_inertial"}}, "inertial", b.inertial_json(urdf::Inertial())));
      diag.info(codes::URDF_NO_INERTIAL, link_pointer(name),
                "link '" + name + "' has no <inertial> and is fixed to '" + via->parent + "' by joint '" + via->name +
                    "': it is massless, as URDF reads it");
    } else if (via == nullptr) {
      diag.info(codes::URDF_NO_INERTIAL, link_pointer(name),
                "root link '" + name + "' has no <inertial>: rdtf computes it from the link's geometry");
    } else {
      // Massless, as URDF reads it, a link could not move on its joint: its geometry's mass is the
      // best guess, and a guess the robot's author did not make, so say so.
      diag.warning(codes::URDF_NO_INERTIAL, link_pointer(name),
                   "link '" + name + "' has no <inertial>, which URDF reads as massless, and moves on joint '" +
                       via->name + "': rdtf computes its mass from its geometry at the density (--density); "
                       "add an <inertial> with the real mass");
    }
    if (!children.empty()) b.document["nodes"][index]["children"] = std::move(children);
  }
  if (!b.ok) return std::nullopt;
  for (const auto& [joint_node, child] : joint_children) {
    b.document["nodes"][joint_node]["children"] = Json::array({link_node.at(child)});
  }
  b.document["scene"] = 0;
  b.document["scenes"] = Json::array({Json{{"nodes", Json::array({link_node.at(xml->links[xml->root].name)})}}});
  const std::vector<std::uint8_t> bin = b.writer.take_buffer();
  if (!bin.empty()) b.document["buffers"] = Json::array({Json{{"byteLength", bin.size()}}});
  b.document["extras"] = Json{{"RDTF", {{"version", "1.0"}, {"name", model->getName()}, {"nodes", b.entries}}}};

  // Through the loader, as any model: the generated glTF is validated like input.
  const std::string display = urdf.string() + " (as glTF)";
  diag.set_file(display);
  const auto glb = make_glb(b.document.dump(), bin);
  auto asset = load_gltf_from_memory(glb, display, fs::path(), options.convert.limits, diag);
  if (!asset) return std::nullopt;
  return convert(std::move(*asset), options.convert, diag);
}

}  // namespace rdtf
