// A closed, consistently wound mesh that encloses nothing: every face with a twin wound the other
// way, as a double-sided export writes a mesh. Each edge is used as often one way as the other,
// so the surface check finds it closed, and its volume is 0: MESH_ENCLOSES_NO_VOLUME says so, and
// LINK_NO_VOLUME does not claim there is no closed mesh.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

// A one-node glTF of the unit cube [0,1]^3, its 12 outward triangles and, if `doubled`, each again
// wound the other way.
Json cube(bool doubled) {
  std::vector<float> positions;
  for (int v = 0; v < 8; ++v) {
    positions.insert(positions.end(), {static_cast<float>(v & 1), static_cast<float>((v >> 1) & 1),
                                       static_cast<float>((v >> 2) & 1)});
  }
  std::vector<std::uint16_t> indices{0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                     2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  if (doubled) {
    for (std::size_t t = 0; t < 12; ++t) indices.insert(indices.end(), {indices[3 * t], indices[3 * t + 2], indices[3 * t + 1]});
  }
  std::vector<std::uint8_t> bytes(positions.size() * 4 + indices.size() * 2);
  std::memcpy(bytes.data(), positions.data(), positions.size() * 4);
  std::memcpy(bytes.data() + positions.size() * 4, indices.data(), indices.size() * 2);
  const std::size_t index_offset = positions.size() * 4;
  return {{"asset", {{"version", "2.0"}}},
          {"scene", 0},
          {"scenes", {{{"nodes", {0}}}}},
          {"nodes", {{{"name", "shell"}, {"mesh", 0}}}},
          {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
          {"buffers", {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + testing::base64(bytes)}}}},
          {"bufferViews",
           {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", index_offset}},
            {{"buffer", 0}, {"byteOffset", index_offset}, {"byteLength", indices.size() * 2}}}},
          {"accessors",
           {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1, 1, 1}}},
            {{"bufferView", 1}, {"componentType", 5123}, {"count", indices.size()}, {"type", "SCALAR"}}}}};
}

std::vector<Diagnostic> convert_cube(bool doubled) {
  testing::TempDir dir;
  testing::write_file(dir / "cube.gltf", cube(doubled).dump());
  Diagnostics diag;
  EXPECT_TRUE(convert_file(dir / "cube.gltf", {}, diag).has_value());
  return diag.all();
}

TEST(NoVolume, ADoubleSidedMeshIsNamedAsEnclosingNothing) {
  bool named = false, link = false;
  for (const Diagnostic& d : convert_cube(true)) {
    if (d.code == codes::MESH_ENCLOSES_NO_VOLUME) {
      named = true;
      EXPECT_EQ(d.severity, Severity::kWarning);
      EXPECT_EQ(d.pointer, "/nodes/0");
      EXPECT_EQ(d.message.rfind("mesh of 'shell' is closed but encloses no volume (0 m^3 across 1.73 m): every face has a "
                                "twin wound the other way (a mesh exported double-sided)",
                                0),
                0u)
          << d.message;
    }
    if (d.code == codes::LINK_NO_VOLUME) {
      link = true;
      EXPECT_NE(d.message.find("its closed meshes enclose none"), std::string::npos) << d.message;
    }
    EXPECT_NE(d.code, codes::MESH_OPEN) << d.message;  // every edge is used twice each way: closed
  }
  EXPECT_TRUE(named);
  EXPECT_TRUE(link);
}

TEST(NoVolume, TheSingleSidedCubeIsSilent) {
  for (const Diagnostic& d : convert_cube(false)) {
    EXPECT_NE(d.code, codes::MESH_ENCLOSES_NO_VOLUME) << d.message;
    EXPECT_NE(d.code, codes::LINK_NO_VOLUME) << d.message;
  }
}

}  // namespace
}  // namespace rdtf
