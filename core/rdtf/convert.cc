#include "rdtf/convert.h"

#include <map>
#include <set>

#include "rdtf/completion.h"
#include "rdtf/geometry.h"
#include "rdtf/khr_physics.h"
#include "rdtf/link_inertia.h"
#include "rdtf/rdtf_extras.h"
#include "rdtf/typing.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

// extras.RDTF.name when the author set one, else the file's name without extensions.
std::string robot_name(const GltfAsset& asset) {
  const Json& document = asset.document;
  if (document.contains("extras") && document["extras"].is_object() &&
      document["extras"].contains("RDTF") && document["extras"]["RDTF"].is_object() &&
      document["extras"]["RDTF"].contains("name") && document["extras"]["RDTF"]["name"].is_string()) {
    return document["extras"]["RDTF"]["name"].get<std::string>();
  }
  std::string stem = asset.path.filename().string();
  stem = stem.substr(0, stem.find('.'));
  return stem.empty() ? std::string("robot") : stem;
}

// Old exporters (glTF-Sample-Models' Box among them) let several vertex accessors share a
// buffer view without byteStride, which glTF 2.0 forbids. When they all have one element size the
// stride is that size: add it, so the output validates. When they differ no stride serves them
// all, and the file is refused as the validator refuses it (it was copied into an output the
// validator refused).
void add_missing_strides(Json& document, Diagnostics& diag) {
  if (!document.contains("meshes") || !document.contains("bufferViews")) return;
  std::map<std::size_t, std::set<std::size_t>> accessors_of_view;
  std::map<std::size_t, std::string> attribute_of_view;  // The last attribute that reads it.
  for (std::size_t m = 0; m < document["meshes"].size(); ++m) {
    const Json& mesh = document["meshes"][m];
    for (std::size_t p = 0; p < mesh["primitives"].size(); ++p) {
      const Json& primitive = mesh["primitives"][p];
      const std::string at = json_pointer(json_pointer("/meshes", m) + "/primitives", p);
      std::vector<std::pair<const Json*, std::string>> attribute_sets{{&primitive["attributes"], at + "/attributes"}};
      if (primitive.contains("targets")) {
        for (std::size_t t = 0; t < primitive["targets"].size(); ++t) {
          attribute_sets.emplace_back(&primitive["targets"][t], json_pointer(at + "/targets", t));
        }
      }
      for (const auto& [attributes, pointer] : attribute_sets) {
        for (const auto& [name, index] : attributes->items()) {
          const Json& accessor = document["accessors"][index.get<std::size_t>()];
          if (accessor.contains("bufferView")) {
            const auto view = accessor["bufferView"].get<std::size_t>();
            accessors_of_view[view].insert(index.get<std::size_t>());
            attribute_of_view[view] = json_pointer(pointer, name);
          }
        }
      }
    }
  }
  for (const auto& [view, accessors] : accessors_of_view) {
    Json& buffer_view = document["bufferViews"][view];
    if (accessors.size() < 2 || buffer_view.contains("byteStride")) continue;
    std::set<std::size_t> sizes;
    for (std::size_t a : accessors) {
      const Json& accessor = document["accessors"][a];
      const int component = accessor["componentType"].get<int>();
      const std::size_t bytes = (component == 5120 || component == 5121) ? 1 : (component == 5122 || component == 5123) ? 2 : 4;
      sizes.insert(bytes * static_cast<std::size_t>(component_count(accessor["type"].get<std::string>())));
    }
    if (sizes.size() != 1) {
      diag.error(codes::MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE, attribute_of_view[view],
                 "buffer view " + std::to_string(view) + " is shared by " + std::to_string(accessors.size()) +
                     " vertex accessors of different element sizes and has no byteStride, which glTF 2.0 requires "
                     "there; give it one, or each accessor a view of its own (re-export the model)");
      continue;
    }
    if (*sizes.begin() % 4 != 0) continue;
    buffer_view["byteStride"] = *sizes.begin();
    diag.info(codes::BUFFER_VIEW_STRIDE_ADDED, json_pointer("/bufferViews", view),
              "buffer view shared by " + std::to_string(accessors.size()) +
                  " vertex accessors had no byteStride (glTF 2.0 requires one); set to " +
                  std::to_string(*sizes.begin()));
  }
}

}  // namespace

std::optional<Conversion> convert(GltfAsset asset, const ConvertOptions& options,
                                  Diagnostics& diag) {
  const auto scene = default_scene(asset.document, diag);
  if (!scene) return std::nullopt;
  auto types = type_nodes(asset.document, *scene, diag);
  if (diag.has_errors()) return std::nullopt;
  check_other_scenes(asset.document, *scene, types, diag);
  check_missing_properties(asset.document, types, diag);
  check_extras_keys(asset.document, diag);
  check_quantized_joint_origins(asset.document, types, diag);
  add_missing_strides(asset.document, diag);
  std::vector<int> carried_by;
  complete_nodes(asset.document, types, diag, &carried_by);
  Robot robot = build_robot(asset.document, types, *scene, diag);
  robot.name = robot_name(asset);
  LinkSolids solids;
  compute_link_inertia(asset, types, options.default_density, robot, diag, carried_by, &solids);
  if (diag.has_errors()) return std::nullopt;
  read_khr_physics(asset.document, types, robot, diag);
  if (!diag.has_errors()) report_part_overlaps(asset.document, robot, solids, diag);
  // After KHR motion, which may replace an inertial that overflowed or overflow one itself.
  if (diag.has_errors() || !check_finite_inertials(asset.document, robot, diag)) return std::nullopt;
  check_units(asset.document, robot, diag);
  check_animations(asset, diag);
  if (options.khr_physics) write_khr_physics(asset.document, types, robot, diag);
  if (!write_rdtf_extras(asset.document, types, robot, diag)) return std::nullopt;
  return Conversion{std::move(asset), std::move(robot)};
}

std::optional<Conversion> convert_file(const std::filesystem::path& path,
                                       const ConvertOptions& options, Diagnostics& diag) {
  auto asset = load_gltf(path, options.limits, diag);
  if (!asset) return std::nullopt;
  return convert(std::move(*asset), options, diag);
}

}  // namespace rdtf
