// STL, binary and ASCII: written for URDF export (binary), read for URDF import (both).
#include <cstring>
#include <sstream>

#include "import_internal.h"
#include "rdtf/urdf.h"

namespace rdtf {
namespace {

using urdf_internal::Welder;

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}

void put_f32(std::vector<std::uint8_t>& out, double value) {
  const float f = static_cast<float>(value);
  std::uint32_t bits;
  std::memcpy(&bits, &f, 4);
  put_u32(out, bits);
}

std::uint32_t get_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

float get_f32(const std::uint8_t* p) {
  const std::uint32_t bits = get_u32(p);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

std::optional<TriangleMesh> parse_binary(const std::vector<std::uint8_t>& bytes) {
  const std::uint32_t count = get_u32(bytes.data() + 80);
  Welder welder;
  for (std::uint32_t t = 0; t < count; ++t) {
    const std::uint8_t* facet = bytes.data() + 84 + 50 * static_cast<std::size_t>(t);
    for (int corner = 0; corner < 3; ++corner) {
      const std::uint8_t* v = facet + 12 + 12 * corner;
      welder.add_corner(Eigen::Vector3d(get_f32(v), get_f32(v + 4), get_f32(v + 8)));
    }
  }
  return welder.take();
}

std::optional<TriangleMesh> parse_ascii(const std::vector<std::uint8_t>& bytes, std::string& why) {
  std::istringstream in(std::string(bytes.begin(), bytes.end()));
  in.imbue(std::locale::classic());
  Welder welder;
  std::string word;
  std::size_t vertices = 0;
  while (in >> word) {
    if (word != "vertex") continue;
    Eigen::Vector3d p;
    if (!(in >> p.x() >> p.y() >> p.z()) || !p.allFinite()) {
      why = "ASCII STL: vertex " + std::to_string(vertices + 1) + " is not three finite numbers";
      return std::nullopt;
    }
    welder.add_corner(p);
    ++vertices;
  }
  if (vertices % 3 != 0) {
    why = "ASCII STL: " + std::to_string(vertices) + " vertices do not make whole triangles";
    return std::nullopt;
  }
  return welder.take();
}

}  // namespace

std::vector<std::uint8_t> stl_bytes(const TriangleMesh& mesh, const std::string& header) {
  std::vector<std::uint8_t> out(80, 0);
  // A binary STL header must not start with "solid" (readers would take it for ASCII).
  const std::string text = header.substr(0, 80);
  std::copy(text.begin(), text.end(), out.begin());
  put_u32(out, static_cast<std::uint32_t>(mesh.triangles.size()));
  out.reserve(84 + 50 * mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.positions[t[0]];
    const Eigen::Vector3d& b = mesh.positions[t[1]];
    const Eigen::Vector3d& c = mesh.positions[t[2]];
    Eigen::Vector3d normal = (b - a).cross(c - a);
    if (normal.norm() > 0) normal.normalize();
    for (int i = 0; i < 3; ++i) put_f32(out, normal[i]);
    for (const Eigen::Vector3d* p : {&a, &b, &c}) {
      for (int i = 0; i < 3; ++i) put_f32(out, (*p)[i]);
    }
    out.push_back(0);
    out.push_back(0);
  }
  return out;
}

std::optional<TriangleMesh> parse_stl(const std::vector<std::uint8_t>& bytes, std::string& why) {
  // Binary when the size matches the triangle count (a binary header may also begin "solid").
  if (bytes.size() >= 84) {
    const std::uint64_t count = get_u32(bytes.data() + 80);
    if (bytes.size() == 84 + 50 * count) {
      auto mesh = parse_binary(bytes);
      for (const Eigen::Vector3d& p : mesh->positions) {
        if (!p.allFinite()) {
          why = "binary STL has a vertex that is not finite";
          return std::nullopt;
        }
      }
      return mesh;
    }
  }
  const std::string start(bytes.begin(), bytes.begin() + std::min<std::size_t>(bytes.size(), 256));
  if (start.find_first_not_of(" \t\r\n") != std::string::npos &&
      start.compare(start.find_first_not_of(" \t\r\n"), 5, "solid") == 0) {
    return parse_ascii(bytes, why);
  }
  why = bytes.size() < 84 ? "file too short for an STL (" + std::to_string(bytes.size()) + " bytes)"
                          : "neither a binary STL (size does not match its triangle count) nor an "
                            "ASCII STL (does not begin with 'solid')";
  return std::nullopt;
}

}  // namespace rdtf
