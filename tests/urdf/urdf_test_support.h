// Shared pieces of the URDF tests: small glTF models built inline, exports written to a folder,
// urdfdom's parser and check_urdf run on them, and the Y-up -> Z-up change of axes.
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <urdf_parser/urdf_parser.h>

#include "rdtf/convert.h"
#include "rdtf/glb.h"
#include "rdtf/urdf.h"
#include "support/test_support.h"

namespace rdtf::urdf_test {

using testing::TempDir;

// The export's change of axes, written out here (not taken from the code under test):
// (x, y, z) of glTF is (x, -z, y) in the URDF.
inline Eigen::Matrix3d gltf_to_urdf_axes() {
  Eigen::Matrix3d C;
  C << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  return C;
}

// A glTF built in memory: box meshes (float32 corners, two outward triangles per face) on nodes.
class GltfBuilder {
 public:
  GltfBuilder() {
    document_ = Json{{"asset", {{"version", "2.0"}}}, {"nodes", Json::array()}, {"scene", 0},
                     {"scenes", Json::array({Json{{"nodes", Json::array()}}})}};
  }

  // A box mesh with edges `size` centred at `center` (in the node's frame); returns the mesh.
  int box_mesh(const Eigen::Vector3f& size, const Eigen::Vector3f& center = Eigen::Vector3f::Zero()) {
    const std::size_t positions = bin_.size();
    Eigen::Vector3f low = center - size / 2, high = center + size / 2;
    for (int i = 0; i < 8; ++i) {
      const float p[3] = {(i & 1) ? high.x() : low.x(), (i & 2) ? high.y() : low.y(),
                          (i & 4) ? high.z() : low.z()};
      append(p, sizeof p);
    }
    const std::size_t indices = bin_.size();
    const std::uint32_t triangles[36] = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                         2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
    append(triangles, sizeof triangles);
    Json& views = document_["bufferViews"];
    views.push_back(Json{{"buffer", 0}, {"byteOffset", positions}, {"byteLength", indices - positions}});
    views.push_back(Json{{"buffer", 0}, {"byteOffset", indices}, {"byteLength", sizeof triangles}});
    Json& accessors = document_["accessors"];
    accessors.push_back(Json{{"bufferView", views.size() - 2}, {"componentType", 5126}, {"count", 8},
                             {"type", "VEC3"},
                             {"min", {low.x(), low.y(), low.z()}},
                             {"max", {high.x(), high.y(), high.z()}}});
    accessors.push_back(Json{{"bufferView", views.size() - 1}, {"componentType", 5125}, {"count", 36},
                             {"type", "SCALAR"}});
    document_["meshes"].push_back(Json{
        {"primitives", Json::array({Json{{"attributes", {{"POSITION", accessors.size() - 2}}},
                                         {"indices", accessors.size() - 1}}})}});
    return static_cast<int>(document_["meshes"].size()) - 1;
  }

  // A node (name, then any glTF keys); `parent` < 0 makes it a scene root. Returns its index.
  int node(const std::string& name, int parent, Json keys = Json::object()) {
    keys["name"] = name;
    document_["nodes"].push_back(std::move(keys));
    const int index = static_cast<int>(document_["nodes"].size()) - 1;
    if (parent < 0) {
      document_["scenes"][0]["nodes"].push_back(index);
    } else {
      document_["nodes"][parent]["children"].push_back(index);
    }
    return index;
  }

  // A link under a joint node: an empty node (Algorithm 3 makes it a link) holding the mesh on a
  // child node "<name>_geom". (A mesh node under a node without mesh would be a mesh of the
  // parent link.) Returns the link node.
  int link_with_mesh(const std::string& name, int parent, int mesh, Json keys = Json::object()) {
    const int link = node(name, parent, std::move(keys));
    node(name + "_geom", link, Json{{"mesh", mesh}});
    return link;
  }

  // An entry of extras.RDTF.nodes (an authored type, joint or inertial).
  void rdtf_entry(Json entry) { document_["extras"]["RDTF"]["nodes"].push_back(std::move(entry)); }

  Json& document() { return document_; }

  // The model as a GLB file's bytes.
  std::vector<std::uint8_t> glb() const {
    Json document = document_;
    document["buffers"] = Json::array({Json{{"byteLength", bin_.size()}}});
    return make_glb(document.dump(), bin_);
  }

  // Loads and converts the model as `rdtf convert` would; fails the test on any error.
  Conversion convert(Diagnostics& diag, const std::string& name = "model.glb") const {
    auto asset = load_gltf_from_memory(glb(), name, {}, LoadLimits{}, diag);
    if (!asset) throw std::runtime_error(name + " did not load: " + first_error(diag));
    auto conversion = rdtf::convert(std::move(*asset), ConvertOptions{}, diag);
    if (!conversion) throw std::runtime_error(name + " did not convert: " + first_error(diag));
    return std::move(*conversion);
  }

 private:
  static std::string first_error(const Diagnostics& diag) {
    for (const Diagnostic& d : diag.all()) {
      if (d.severity == Severity::kError) return format(d);
    }
    return "(no error)";
  }
  void append(const void* data, std::size_t size) {
    const auto* bytes = static_cast<const std::uint8_t*>(data);
    bin_.insert(bin_.end(), bytes, bytes + size);
  }
  Json document_;
  std::vector<std::uint8_t> bin_;
};

// import_urdf that must succeed: throws, with every diagnostic, when it does not.
inline Conversion import_ok(const std::filesystem::path& urdf, Diagnostics& diag, const UrdfImportOptions& options = {}) {
  auto conversion = import_urdf(urdf, options, diag);
  std::string all;
  for (const Diagnostic& d : diag.all()) all += format(d) + "\n";
  if (!conversion) throw std::runtime_error(urdf.string() + " not imported:\n" + all);
  return std::move(*conversion);
}

// The first diagnostic with `code`, or null.
inline const Diagnostic* find_code(const Diagnostics& diag, const std::string& code) {
  for (const Diagnostic& d : diag.all()) {
    if (d.code == code) return &d;
  }
  return nullptr;
}

inline Conversion convert_fixture(const std::string& name) {
  Diagnostics diag;
  auto conversion = convert_file(testing::data_dir() / "blender" / name, ConvertOptions{}, diag);
  if (!conversion) throw std::runtime_error(name + " did not convert");
  return std::move(*conversion);
}

// write_urdf into `dir`; fails the test (and throws) when it refuses.
inline std::string export_to(const Conversion& conversion, const std::filesystem::path& dir,
                             const UrdfOptions& options = {}) {
  Diagnostics diag;
  std::string text;
  if (!write_urdf(conversion, dir, options, diag, &text)) {
    std::string all;
    for (const Diagnostic& d : diag.all()) all += format(d) + "\n";
    ADD_FAILURE() << "export refused:\n" << all;
    throw std::runtime_error("export refused");
  }
  return text;
}

// urdfdom's own parser on a text (what ROS tools use).
inline urdf::ModelInterfaceSharedPtr parse_with_urdfdom(const std::string& text) {
  auto model = urdf::parseURDF(text);
  if (!model) throw std::runtime_error("urdfdom cannot parse the URDF");
  return model;
}

// check_urdf (liburdfdom-tools) on a file: exit 0 and its success line.
inline void expect_check_urdf_passes(const std::filesystem::path& urdf) {
  const testing::CommandResult run = testing::run_command("check_urdf '" + urdf.string() + "'");
  EXPECT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("Successfully Parsed XML"), std::string::npos) << run.out << run.err;
}

inline Eigen::Matrix3d tensor_of(const urdf::Inertial& in) {
  Eigen::Matrix3d I;
  I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  return I;
}

inline Eigen::Matrix3d rotation_of(const urdf::Rotation& q) {
  return Eigen::Quaterniond(q.w, q.x, q.y, q.z).toRotationMatrix();
}

inline Eigen::Vector3d vector_of(const urdf::Vector3& v) { return {v.x, v.y, v.z}; }

// Largest |a - b| over the largest |b| (the relative error of a matrix or vector).
template <typename A, typename B>
double relative_error(const A& a, const B& b) {
  const double scale = b.cwiseAbs().maxCoeff();
  return (a - b).cwiseAbs().maxCoeff() / (scale > 0 ? scale : 1.0);
}

}  // namespace rdtf::urdf_test
