// Geometry for URDF import: generated primitives, mesh file lookup, and the glTF buffer.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numbers>
#include <utility>

#include <urdf_model/link.h>

#include "import_internal.h"
#include "rdtf/mass_properties.h"

namespace rdtf::urdf_internal {
namespace {

std::uint32_t add_vertex(TriangleMesh& mesh, const Eigen::Vector3d& p) {
  mesh.positions.push_back(p);
  return static_cast<std::uint32_t>(mesh.positions.size() - 1);
}

void scale_to_volume(TriangleMesh& mesh, double volume) {
  const double have = integrate_solid(std::span<const TriangleMesh>(&mesh, 1), Eigen::Affine3d::Identity()).volume;
  const double factor = std::cbrt(volume / have);
  for (Eigen::Vector3d& p : mesh.positions) p *= factor;
}

std::string size_text(double value) { return format_number(value); }

}  // namespace

std::optional<std::string> degenerate_shape(const urdf::Geometry& geometry) {
  const auto none = [](const std::string& shape, const std::string& what) {
    return "<" + shape + "> has " + what + ": it has no volume (MuJoCo refuses such a shape; Drake and Gazebo load it)";
  };
  switch (geometry.type) {
    case urdf::Geometry::BOX: {
      const urdf::Vector3& d = static_cast<const urdf::Box&>(geometry).dim;
      if (d.x > 0 && d.y > 0 && d.z > 0) return std::nullopt;
      return none("box", "size \"" + size_text(d.x) + " " + size_text(d.y) + " " + size_text(d.z) + "\", a side of 0");
    }
    case urdf::Geometry::CYLINDER: {
      const auto& cylinder = static_cast<const urdf::Cylinder&>(geometry);
      if (!(cylinder.radius > 0)) return none("cylinder", "radius " + size_text(cylinder.radius));
      if (!(cylinder.length > 0)) return none("cylinder", "length " + size_text(cylinder.length));
      return std::nullopt;
    }
    case urdf::Geometry::SPHERE: {
      const double radius = static_cast<const urdf::Sphere&>(geometry).radius;
      if (radius > 0) return std::nullopt;
      return none("sphere", "radius " + size_text(radius));
    }
    default:
      return std::nullopt;
  }
}

TriangleMesh box_mesh(const Eigen::Vector3d& size) {
  TriangleMesh mesh;
  const Eigen::Vector3d h = size / 2;
  for (int i = 0; i < 8; ++i) {
    add_vertex(mesh, {(i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z()});
  }
  // Two outward triangles per face (corner index bits: x = 1, y = 2, z = 4).
  mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return mesh;
}

TriangleMesh cylinder_mesh(double radius, double length, int segments) {
  TriangleMesh mesh;
  const double step = 2 * std::numbers::pi / segments;
  // The polygon's area N/2 r'^2 sin(2 pi / N) equals the circle's pi r^2.
  const double r = radius * std::sqrt(2 * std::numbers::pi / (segments * std::sin(step)));
  const double z = length / 2;
  const std::uint32_t bottom = add_vertex(mesh, {0, 0, -z});
  const std::uint32_t top = add_vertex(mesh, {0, 0, z});
  const auto first = static_cast<std::uint32_t>(mesh.positions.size());
  for (int i = 0; i < segments; ++i) {
    const double c = std::cos(step * i), s = std::sin(step * i);
    add_vertex(mesh, {r * c, r * s, -z});
    add_vertex(mesh, {r * c, r * s, z});
  }
  for (int i = 0; i < segments; ++i) {
    const std::uint32_t b0 = first + 2 * i, t0 = b0 + 1;
    const std::uint32_t b1 = first + 2 * ((i + 1) % segments), t1 = b1 + 1;
    mesh.triangles.push_back({bottom, b1, b0});
    mesh.triangles.push_back({top, t0, t1});
    mesh.triangles.push_back({b0, b1, t1});
    mesh.triangles.push_back({b0, t1, t0});
  }
  return mesh;
}

TriangleMesh sphere_mesh(double radius, int subdivisions) {
  // An icosahedron, each triangle split in four `subdivisions` times and the new vertices pushed out
  // to the sphere. Its symmetry group is the icosahedron's, so its second moment is a multiple of
  // the identity (as a ball's): scaled to the ball's volume, 3 subdivisions (642 vertices, 1,280
  // triangles) give 2/5 m r^2 to 3.2e-6. A 16 x 32 UV sphere was anisotropic, its moments 1.1e-3
  // over and 2.1e-3 under about its poles (s101gate D7).
  TriangleMesh mesh;
  const double t = (1 + std::sqrt(5.0)) / 2;
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(-1, t, 0), Eigen::Vector3d(1, t, 0), Eigen::Vector3d(-1, -t, 0),
                                   Eigen::Vector3d(1, -t, 0), Eigen::Vector3d(0, -1, t), Eigen::Vector3d(0, 1, t),
                                   Eigen::Vector3d(0, -1, -t), Eigen::Vector3d(0, 1, -t), Eigen::Vector3d(t, 0, -1),
                                   Eigen::Vector3d(t, 0, 1), Eigen::Vector3d(-t, 0, -1), Eigen::Vector3d(-t, 0, 1)}) {
    add_vertex(mesh, p.normalized());
  }
  mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                    {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middles;
    const auto middle = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto found = middles.find(key);
      if (found != middles.end()) return found->second;
      const Eigen::Vector3d p = (mesh.positions[a] + mesh.positions[b]).normalized();
      const std::uint32_t index = add_vertex(mesh, p);
      middles.emplace(key, index);
      return index;
    };
    std::vector<std::array<std::uint32_t, 3>> split;
    split.reserve(4 * mesh.triangles.size());
    for (const auto& [a, b, c] : mesh.triangles) {
      const std::uint32_t ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
      split.push_back({a, ab, ca});
      split.push_back({b, bc, ab});
      split.push_back({c, ca, bc});
      split.push_back({ab, bc, ca});
    }
    mesh.triangles = std::move(split);
  }
  scale_to_volume(mesh, 4.0 / 3.0 * std::numbers::pi * radius * radius * radius);
  return mesh;
}

std::string percent_decoded(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto hex = [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) != 0; };
    if (text[i] == '%' && i + 2 < text.size() && hex(text[i + 1]) && hex(text[i + 2])) {
      out += static_cast<char>(std::stoi(text.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += text[i];
    }
  }
  return out;
}

std::optional<std::filesystem::path> resolve_mesh_path(const std::string& filename,
                                                       const std::filesystem::path& urdf_folder,
                                                       std::string& why, const char* what) {
  namespace fs = std::filesystem;
  std::vector<fs::path> candidates;
  // "$(find my_pkg)/meshes/base.stl" is xacro's, left unexpanded; no file is named so.
  if (filename.find("$(") != std::string::npos || filename.find("${") != std::string::npos) {
    why = std::string(what) + " '" + filename +
          "' holds a xacro expression: expand the file with xacro first (xacro robot.urdf.xacro > robot.urdf)";
    return std::nullopt;
  }
  const std::string package = "package://";
  if (filename.rfind(package, 0) == 0) {
    const std::string rest = filename.substr(package.size());
    const auto slash = rest.find('/');
    if (slash == std::string::npos || slash == 0) {
      why = "'" + filename + "' is not package://NAME/path";
      return std::nullopt;
    }
    const std::string name = rest.substr(0, slash);
    const fs::path inside = rest.substr(slash + 1);
    // From the folder's absolute path: a relative one ("" or "urdf", `cd my_pkg/urdf && rdtf
    // import robot.urdf`) ran out at the working folder before reaching the package (s90urdf D1).
    std::error_code ec;
    fs::path start = fs::absolute(urdf_folder.empty() ? fs::path(".") : urdf_folder, ec).lexically_normal();
    if (ec) start = urdf_folder;
    if (!start.has_filename() && start.has_parent_path() && start != start.root_path()) start = start.parent_path();
    for (fs::path dir = start;; dir = dir.parent_path()) {
      if (dir.filename() == name) candidates.push_back(dir / inside);
      candidates.push_back(dir / name / inside);
      if (dir == dir.parent_path() || dir.empty()) break;
    }
  } else if (filename.rfind("file:", 0) == 0) {
    // A URI (RFC 8089): file:///path, file://localhost/path (any case), or file:/path; the path
    // percent-encoded ("my%20dir"). It was read as a raw path, so file://localhost/abs was looked
    // for under the working folder and %20 was not a space (s90urdf D9, s90rev R6).
    std::string rest = filename.substr(5);
    std::string host;
    if (rest.rfind("//", 0) == 0) {
      rest = rest.substr(2);
      host = rest.substr(0, rest.find('/'));
      for (char& c : host) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      rest = rest.substr(host.size());
    }
    if ((!host.empty() && host != "localhost") || rest.empty() || rest[0] != '/') {
      why = "'" + filename + "' is not a file URI of this machine: only file:///path, file://localhost/path and "
            "file:/path are read";
      return std::nullopt;
    }
    candidates.push_back(fs::path(percent_decoded(rest)));
  } else if (filename.find("://") != std::string::npos) {
    why = "'" + filename + "': only relative paths, absolute paths, file:// and package:// are read";
    return std::nullopt;
  } else {
    const fs::path path(filename);
    candidates.push_back(path.is_absolute() ? path : urdf_folder / path);
  }
  // A candidate that is there but is no file (a FIFO would block the read, a folder has no
  // bytes) is named as what it is, not as missing.
  std::string not_a_file;
  for (const fs::path& candidate : candidates) {
    std::error_code error;
    const fs::file_status status = fs::status(candidate, error);
    if (fs::is_regular_file(status)) return candidate;
    if (!not_a_file.empty() || error || !fs::exists(status)) continue;
    const fs::file_type type = status.type();
    not_a_file = type == fs::file_type::directory ? "a folder"
                 : type == fs::file_type::fifo    ? "a FIFO (named pipe)"
                 : type == fs::file_type::socket  ? "a socket"
                 : type == fs::file_type::block || type == fs::file_type::character ? "a device"
                                                                                     : "not a regular file";
    not_a_file = candidate.string() + " is " + not_a_file;
  }
  if (!not_a_file.empty()) {
    why = std::string(what) + " '" + filename + "': " + not_a_file + ", not a file rdtf reads";
    return std::nullopt;
  }
  // Every place looked in, so that the user sees which folder to put it in (or which to pass).
  std::vector<std::string> shown;
  for (const fs::path& candidate : candidates) {
    std::error_code error;
    const fs::path absolute = fs::absolute(candidate, error);
    const std::string text = (error ? candidate : absolute.lexically_normal()).string();
    if (std::find(shown.begin(), shown.end(), text) == shown.end()) shown.push_back(text);
  }
  std::string places;
  for (std::size_t i = 0; i < shown.size(); ++i) {
    places += (i == 0 ? "" : i + 1 == shown.size() ? " and " : ", ") + shown[i];
  }
  why = std::string(what) + " '" + filename + "' not found (looked for " + places + ")";
  return std::nullopt;
}

std::size_t GltfMeshWriter::add_view(std::size_t offset, std::size_t length, int target) {
  document_["bufferViews"].push_back(
      Json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}, {"target", target}});
  return document_["bufferViews"].size() - 1;
}

std::size_t GltfMeshWriter::add_texture(const std::string& bytes, const char* mime_type, const std::string& name) {
  const std::size_t offset = bin_.size();
  bin_.insert(bin_.end(), bytes.begin(), bytes.end());
  document_["bufferViews"].push_back(Json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes.size()}});
  while (bin_.size() % 4 != 0) bin_.push_back(0);  // The next accessor's view starts aligned.
  document_["images"].push_back(
      Json{{"name", name}, {"bufferView", document_["bufferViews"].size() - 1}, {"mimeType", mime_type}});
  document_["textures"].push_back(Json{{"source", document_["images"].size() - 1}});
  return document_["textures"].size() - 1;
}

std::size_t GltfMeshWriter::add_mesh(const TriangleMesh& mesh, const std::vector<std::array<float, 2>>& texcoords,
                                     const std::string& name, const std::vector<Primitive>& primitives) {
  // Positions (float32 VEC3), then each primitive's indices (uint32): all 4-byte aligned.
  const std::size_t position_offset = bin_.size();
  std::array<float, 3> low{}, high{};
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    for (int i = 0; i < 3; ++i) {
      const float f = static_cast<float>(mesh.positions[v][i]);
      if (v == 0 || f < low[i]) low[i] = f;
      if (v == 0 || f > high[i]) high[i] = f;
      std::uint8_t bytes[4];
      std::memcpy(bytes, &f, 4);
      bin_.insert(bin_.end(), bytes, bytes + 4);
    }
  }
  const std::size_t position_view = add_view(position_offset, bin_.size() - position_offset, 34962);
  Json& accessors = document_["accessors"];
  accessors.push_back(Json{{"bufferView", position_view}, {"componentType", 5126},
                           {"count", mesh.positions.size()}, {"type", "VEC3"},
                           {"min", Json::array({low[0], low[1], low[2]})},
                           {"max", Json::array({high[0], high[1], high[2]})}});
  const std::size_t position_accessor = accessors.size() - 1;
  std::optional<std::size_t> texcoord_accessor;
  if (!texcoords.empty() && texcoords.size() == mesh.positions.size()) {
    const std::size_t texcoord_offset = bin_.size();
    for (const auto& uv : texcoords) {
      std::uint8_t bytes[8];
      std::memcpy(bytes, uv.data(), 8);
      bin_.insert(bin_.end(), bytes, bytes + 8);
    }
    accessors.push_back(Json{{"bufferView", add_view(texcoord_offset, bin_.size() - texcoord_offset, 34962)},
                             {"componentType", 5126}, {"count", texcoords.size()}, {"type", "VEC2"}});
    texcoord_accessor = accessors.size() - 1;
  }
  Json out = Json::array();
  for (const Primitive& part : primitives) {
    const std::size_t index_offset = bin_.size();
    for (std::size_t t = part.first; t < part.first + part.count; ++t) {
      for (std::uint32_t i : mesh.triangles[t]) {
        std::uint8_t bytes[4];
        std::memcpy(bytes, &i, 4);
        bin_.insert(bin_.end(), bytes, bytes + 4);
      }
    }
    const std::size_t index_view = add_view(index_offset, bin_.size() - index_offset, 34963);
    accessors.push_back(Json{{"bufferView", index_view}, {"componentType", 5125},
                             {"count", part.count * 3}, {"type", "SCALAR"}});
    Json primitive{{"attributes", {{"POSITION", position_accessor}}}, {"indices", accessors.size() - 1}, {"mode", 4}};
    if (part.textured && texcoord_accessor) primitive["attributes"]["TEXCOORD_0"] = *texcoord_accessor;
    if (part.material) primitive["material"] = *part.material;
    out.push_back(std::move(primitive));
  }
  document_["meshes"].push_back(Json{{"name", name}, {"primitives", std::move(out)}});
  return document_["meshes"].size() - 1;
}

std::vector<std::uint8_t> GltfMeshWriter::take_buffer() { return std::move(bin_); }

}  // namespace rdtf::urdf_internal
