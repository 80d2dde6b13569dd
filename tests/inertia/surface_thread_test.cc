// A large mesh's surface check runs on a thread of its own beside the mass kernel
// (link_inertia.cc, kSurfaceCheckThreadTriangles = 100,000 triangles). Whether it did must change
// nothing a user sees: the same counts, the same masses, and the diagnostics in the same order as
// when the check runs first, in place. The same model is converted with a sphere below and above
// the threshold, and each result is checked against what the sphere is known to be.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/glb.h"
#include "rdtf/gltf.h"

namespace rdtf {
namespace {

struct Sphere {
  std::vector<float> positions;
  std::vector<std::uint32_t> indices;
  std::size_t triangles() const { return indices.size() / 3; }
};

// A UV sphere of `rings` rings (4 rings (rings - 1) triangles), wound clockwise seen from outside
// (inside out), with its last triangle left out (open: exactly 3 boundary edges).
Sphere open_inside_out_sphere(int rings) {
  const int segments = 2 * rings;
  Sphere s;
  const auto add = [&](double x, double y, double z) {
    s.positions.insert(s.positions.end(), {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
  };
  add(0, 1, 0);
  for (int i = 1; i < rings; ++i) {
    const double theta = std::numbers::pi * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * std::numbers::pi * j / segments;
      add(std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi));
    }
  }
  add(0, -1, 0);
  const auto south = static_cast<std::uint32_t>(s.positions.size() / 3 - 1);
  const auto ring = [&](int i, int j) { return static_cast<std::uint32_t>(1 + (i - 1) * segments + j % segments); };
  // Counter-clockwise from outside is (a, b, c); each is written (a, c, b).
  const auto triangle = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    s.indices.insert(s.indices.end(), {a, c, b});
  };
  for (int j = 0; j < segments; ++j) triangle(0, ring(1, j), ring(1, j + 1));
  for (int i = 1; i + 1 < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      triangle(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1));
      triangle(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1));
    }
  }
  for (int j = 0; j < segments; ++j) triangle(ring(rings - 1, j), south, ring(rings - 1, j + 1));
  s.indices.resize(s.indices.size() - 3);
  return s;
}

// One link holding the sphere. With `bad_mass` its node asks for an impossible mass (rdtf_mass
// -1): an error found after the surface check's warnings and before the mass kernel's.
// With `mesh_on_link`, the link node carries the mesh itself (Blender's layout), so the
// conversion moves it to a node the input does not have.
std::vector<std::uint8_t> model_glb(const Sphere& sphere, bool bad_mass, bool mesh_on_link = false) {
  std::vector<std::uint8_t> bin(sphere.positions.size() * 4 + sphere.indices.size() * 4);
  std::memcpy(bin.data(), sphere.positions.data(), sphere.positions.size() * 4);
  std::memcpy(bin.data() + sphere.positions.size() * 4, sphere.indices.data(), sphere.indices.size() * 4);
  float lo[3] = {1e9f, 1e9f, 1e9f}, hi[3] = {-1e9f, -1e9f, -1e9f};
  for (std::size_t i = 0; i < sphere.positions.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], sphere.positions[i]);
    hi[i % 3] = std::max(hi[i % 3], sphere.positions[i]);
  }
  const Json document = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", mesh_on_link ? Json{{{"name", "shell"}, {"mesh", 0}}}
                             : Json{{{"name", "base"}, {"children", {1}}},
                                    bad_mass ? Json{{"name", "shell"}, {"mesh", 0}, {"extras", {{"rdtf_mass", -1.0}}}}
                                             : Json{{"name", "shell"}, {"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", sphere.positions.size() / 3}, {"type", "VEC3"},
         {"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}},
        {{"bufferView", 1}, {"componentType", 5125}, {"count", sphere.indices.size()}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteLength", sphere.positions.size() * 4}},
        {{"buffer", 0}, {"byteOffset", sphere.positions.size() * 4}, {"byteLength", sphere.indices.size() * 4}}}},
      {"buffers", {{{"byteLength", bin.size()}}}},
  };
  return make_glb(document.dump(), bin);
}

struct Outcome {
  std::vector<std::string> codes;  // Of the surface, the mass and the orientation, in order.
  std::string open_message;
  double volume = 0;
};

Outcome convert_sphere(int rings, bool bad_mass) {
  const Sphere sphere = open_inside_out_sphere(rings);
  Diagnostics diag("sphere.glb");
  auto asset = load_gltf_from_memory(model_glb(sphere, bad_mass), "sphere.glb", {}, LoadLimits{}, diag);
  EXPECT_TRUE(asset.has_value());
  Outcome outcome;
  if (!asset) return outcome;
  const auto conversion = convert(std::move(*asset), ConvertOptions{}, diag);
  for (const Diagnostic& d : diag.all()) {
    if (d.code == codes::MESH_OPEN || d.code == codes::MESH_INCONSISTENT_WINDING ||
        d.code == codes::RDTF_INVALID_VALUE || d.code == codes::MESH_INSIDE_OUT) {
      outcome.codes.push_back(d.code);
    }
    if (d.code == codes::MESH_OPEN) outcome.open_message = d.message;
  }
  if (conversion && !conversion->robot.links.empty() && !conversion->robot.links[0].meshes.empty()) {
    outcome.volume = conversion->robot.links[0].meshes[0].volume;
  }
  return outcome;
}

TEST(SurfaceCheckThread, LargeAndSmallMeshesReportAlikeInTheSameOrder) {
  for (const int rings : {20, 170}) {  // 1,519 and 114,919 triangles: below and above 100,000.
    SCOPED_TRACE("rings " + std::to_string(rings));
    const Outcome refused = convert_sphere(rings, /*bad_mass=*/true);
    EXPECT_EQ(refused.codes,
              (std::vector<std::string>{codes::MESH_OPEN, codes::RDTF_INVALID_VALUE, codes::MESH_INSIDE_OUT}));
    const Outcome converted = convert_sphere(rings, /*bad_mass=*/false);
    EXPECT_EQ(converted.codes, (std::vector<std::string>{codes::MESH_OPEN, codes::MESH_INSIDE_OUT}));
    // Exactly the three edges of the missing triangle, and no edge used twice one way.
    EXPECT_NE(converted.open_message.find("(3 boundary edges, 0 non-manifold edges)"), std::string::npos)
        << converted.open_message;
    // Turned right: positive, and below the sphere's 4/3 pi by the chords' share.
    EXPECT_GT(converted.volume, 0.95 * 4.0 / 3.0 * std::numbers::pi);
    EXPECT_LT(converted.volume, 4.0 / 3.0 * std::numbers::pi);
  }
}

// A link node that carries its own mesh (Blender's layout) has it moved to a new node of the
// output; what is wrong with the mesh is still reported on the node the input has, by its name.
TEST(SurfaceCheckThread, AMeshMovedOffItsLinkIsReportedOnTheInputsNode) {
  for (const int rings : {20, 170}) {  // in place and on the surface check's thread
    SCOPED_TRACE("rings " + std::to_string(rings));
    Diagnostics diag("shell.glb");
    auto asset = load_gltf_from_memory(model_glb(open_inside_out_sphere(rings), false, /*mesh_on_link=*/true),
                                       "shell.glb", {}, LoadLimits{}, diag);
    ASSERT_TRUE(asset);
    ASSERT_TRUE(convert(std::move(*asset), ConvertOptions{}, diag));
    int reported = 0;
    for (const Diagnostic& d : diag.all()) {
      if (d.code != codes::MESH_OPEN && d.code != codes::MESH_INSIDE_OUT) continue;
      ++reported;
      EXPECT_EQ(d.pointer, "/nodes/0") << format(d);
      EXPECT_NE(d.message.find("mesh of 'shell' "), std::string::npos) << format(d);
    }
    EXPECT_EQ(reported, 2);
  }
}

}  // namespace
}  // namespace rdtf
