// The checks behind validate_document (rdtf/validate.h), one class split over files by what
// they check: validate_document.cc (reading properties; asset, extensions, images, animations,
// limits), validate_accessors.cc (buffers, buffer views, accessors), validate_meshes.cc (meshes)
// validate_nodes.cc (nodes, the node graph, skins, scenes), validate_usage.cc (what each accessor
// and buffer view is used for) and validate_materials.cc (materials, textures, samplers, every
// object's extensions: what rdtf writes out unread).
//
// The document is untrusted and may be fuzzed: every property is type-checked before it is read
// (nlohmann::json throws on a wrong-type access), and offsets and lengths are unsigned 64-bit
// values combined only through overflow-checked arithmetic. Each top-level entry is first reduced
// to the few facts later checks need, so a check never reads a value an earlier one found broken,
// and a broken entry is reported once, not again by everything that uses it. Every pass is linear
// in the size of the document: a hostile file must not make validation slow.
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"

namespace rdtf::internal {

inline constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

struct BufferFacts {
  bool valid = false;
  std::uint64_t byte_length = 0;
};

// What an accessor or a buffer view is used for, named as the Khronos validator names them
// (validate_usage.cc).
enum class AccessorUsage : std::uint8_t {
  kUnused, kVertexAttribute, kPrimitiveIndices, kIbm, kAnimationInput, kAnimationOutput
};
enum class ViewUsage : std::uint8_t { kUnused, kVertexBuffer, kIndexBuffer, kIbm, kImage, kOther };

struct ViewFacts {
  bool valid = false;
  std::uint64_t byte_offset = 0, byte_length = 0, byte_stride = 0;  // stride 0: not given
  ViewUsage usage = ViewUsage::kUnused;  // Its target, else its first use (validate_usage.cc).
};

struct AccessorFacts {
  bool valid = false;
  std::size_t view = kNone;
  std::string type;
  std::uint64_t component_type = 0, count = 0;
  bool normalized = false;
};

struct MeshFacts {
  bool valid = false;
  std::size_t targets = 0;
  bool skinned = false;  // A primitive has JOINTS_0.
  std::uint64_t triangles = 0;
  // For each morph target, the vertices its POSITION moves, over all primitives: what a node
  // whose weight for it is not 0 makes the converter displace (check_triangle_limit).
  std::vector<std::uint64_t> target_vertices;
};

struct NodeFacts {
  std::vector<std::size_t> children;
  std::size_t mesh = kNone, skin = kNone;
};

class DocumentCheck {
 public:
  DocumentCheck(const Json& document, const LoadLimits& limits, Diagnostics& diag)
      : doc_(document), limits_(limits), diag_(diag) {}
  void run();

 private:
  // validate_document.cc: reading properties, each reporting what is wrong with it.
  std::vector<const Json*> top_level(const char* key);
  const Json* object_at(const Json& array, std::size_t i, const std::string& pointer);
  const Json* find(const Json& object, const char* key, const std::string& pointer, bool required);
  const Json* read_typed(const Json& object, const char* key, const std::string& pointer,
                         bool required, bool (Json::*is_type)() const noexcept, const char* type);
  const Json* read_array(const Json& object, const char* key, const std::string& pointer,
                         bool required = false);
  const Json* read_object(const Json& object, const char* key, const std::string& pointer,
                          bool required = false);
  std::optional<std::string> read_string(const Json& object, const char* key,
                                         const std::string& pointer, bool required = false);
  std::optional<bool> read_bool(const Json& object, const char* key, const std::string& pointer);
  std::optional<std::uint64_t> uint_value(const Json& value, const std::string& pointer);
  std::optional<std::uint64_t> read_uint(const Json& object, const char* key,
                                         const std::string& pointer, bool required = false,
                                         std::uint64_t minimum = 0);
  std::size_t reference(const Json& value, const std::string& pointer, const char* array);
  std::size_t read_ref(const Json& object, const char* key, const std::string& pointer,
                       const char* array, bool required = false);
  std::vector<std::size_t> read_refs(const Json& object, const char* key,
                                     const std::string& pointer, const char* array,
                                     bool required = false);
  std::optional<std::vector<double>> read_numbers(const Json& object, const char* key,
                                                  const std::string& pointer, std::size_t length);

  // validate_document.cc: the document as a whole.
  std::optional<std::pair<int, int>> read_version(const Json& asset, const char* key,
                                                  bool required);
  void check_asset();
  void check_extensions();
  bool integer_bounds_fit(const std::vector<double>& bounds, std::uint64_t component_type, const std::string& pointer);
  void check_images_and_animations();
  // validate_materials.cc: what rdtf passes through unread.
  void read_unit_number(const Json& object, const char* key, const std::string& pointer, double low,
                        double high);
  void read_factor(const Json& object, const char* key, const std::string& pointer, std::size_t length);
  void check_texture_info(const Json& object, const char* key, const std::string& pointer);
  void check_materials();
  void check_textures();
  void check_material_texcoords();
  void check_extension_objects(const Json& value, const std::string& pointer, int depth);
  // validate_extensions.cc: KHR_lights_punctual and KHR_materials_variants, also passed through
  // unread, and where each extension the validator knows may be.
  struct Bound {
    double value;
    bool inclusive;
  };
  std::optional<double> read_bounded(const Json& object, const char* key, const std::string& pointer,
                                     double fallback, Bound low, Bound high);
  bool extension_is_object(const Json& extension, const std::string& pointer, const char* required);
  const Json* read_objects(const Json& object, const char* key, const std::string& pointer);
  void check_lights();
  void check_variants();
  void check_extension_place(const std::string& name, const std::string& object_pointer);
  void check_animation(const Json& animation, const std::string& pointer);
  void check_triangle_limit();

  // validate_accessors.cc
  void check_buffers();
  bool check_data_uri(const std::string& uri, std::optional<std::uint64_t> length,
                      const std::string& pointer);
  void check_buffer_views();
  std::optional<std::uint64_t> read_stride(const Json& view, const std::string& pointer,
                                           std::uint64_t length);
  bool fits_view(std::size_t view, std::uint64_t offset, std::uint64_t count, std::uint64_t stride,
                 std::uint64_t size, const std::string& pointer);
  void check_accessors();
  bool check_accessor(const Json& accessor, const std::string& pointer, AccessorFacts& facts);
  bool check_accessor_layout(const AccessorFacts& facts, std::uint64_t offset,
                             const std::string& pointer);
  bool check_sparse(const Json& accessor, const AccessorFacts& facts, const std::string& pointer);
  bool check_sparse_part(const Json& part, const std::string& pointer, std::uint64_t count,
                         std::uint64_t size);

  // validate_meshes.cc
  void check_meshes();
  void check_mesh(const Json& mesh, const std::string& pointer, MeshFacts& facts);
  bool check_primitive(const Json& primitive, const std::string& pointer, MeshFacts& mesh);
  std::map<std::string, std::size_t> check_attributes(const Json& attributes,
                                                      const std::string& pointer, bool target);
  void check_attribute_alignment(const std::string& name, std::size_t accessor, const std::string& pointer);
  void check_attribute_format(const std::string& name, std::size_t accessor, const std::string& pointer,
                              bool target);  // validate_attribute_formats.cc
  void check_indices(std::size_t accessor, const std::string& pointer);
  void check_target(const Json& target, const std::string& pointer,
                    const std::map<std::string, std::size_t>& base);

  // validate_usage.cc
  void check_usages();
  std::size_t index_at(const Json& object, const char* key, const char* array);
  void use_accessor(std::size_t accessor, AccessorUsage usage, const std::string& pointer);
  void use_view(std::size_t view, ViewUsage usage, const std::string& pointer);

  // validate_nodes.cc
  void check_nodes();
  void check_node(const Json& node, std::size_t index, const std::string& pointer, NodeFacts& facts);
  void check_transform(const Json& node, std::size_t index, const std::string& pointer);
  void check_node_graph();
  void report_loops();
  void order_trees();
  bool is_ancestor_or_self(std::size_t ancestor, std::size_t node) const;
  void check_skins();
  void check_inverse_bind_matrices(std::size_t accessor, std::size_t joints,
                                   const std::string& pointer);
  void check_scenes();
  void check_skins_in_scenes(const std::vector<std::vector<std::size_t>>& scene_roots);

  const Json& doc_;
  const LoadLimits& limits_;
  Diagnostics& diag_;
  std::map<std::string, std::vector<const Json*>> entries_;  // Top-level arrays; null: no object.
  bool quantization_ = false;                                // KHR_mesh_quantization is used.
  std::unordered_set<std::string> used_extensions_;          // The names extensionsUsed lists.
  std::vector<BufferFacts> buffers_;
  std::vector<ViewFacts> views_;
  std::vector<AccessorFacts> accessors_;
  std::vector<AccessorUsage> accessor_usage_;  // check_usages
  std::vector<MeshFacts> meshes_;
  std::vector<NodeFacts> nodes_;
  std::vector<std::size_t> parents_;
  bool forest_ = false;  // No node has two parents and none is its own ancestor.
  // When forest_: each node's tree root, and when depth-first order enters and leaves it.
  std::vector<std::size_t> root_, enter_, leave_;
  std::vector<std::size_t> skin_tree_;  // Per skin: the root of its joints' tree, or kNone.
};

}  // namespace rdtf::internal
