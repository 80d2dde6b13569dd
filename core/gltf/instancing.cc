#include "rdtf/instancing.h"

#include <cmath>
#include <string>

#include "rdtf/completion.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/geometry.h"
#include "validate_util.h"

namespace rdtf {
namespace {

constexpr const char* kInstancing = "EXT_mesh_gpu_instancing";

// The one attribute's accessor, checked against the formats the extension allows.
std::optional<std::size_t> attribute_accessor(const GltfAsset& asset, const Json& attributes,
                                              const char* name, const std::string& pointer,
                                              Diagnostics& diag) {
  const Json& document = asset.document;
  const Json& value = attributes[name];
  const std::string here = pointer + "/" + name;
  const auto index = internal::as_uint(value);
  const std::size_t accessors = document.contains("accessors") ? document["accessors"].size() : 0;
  if (!index || *index >= accessors) {
    diag.error(codes::INSTANCING_INVALID, here,
               std::string(name) + " must name an accessor (0 to " + std::to_string(accessors) +
                   " - 1), found " + internal::describe(value));
    return std::nullopt;
  }
  const Json& accessor = document["accessors"][*index];
  const std::string type = accessor["type"].get<std::string>();
  const auto component = accessor["componentType"].get<std::uint64_t>();
  const bool normalized = accessor.value("normalized", false);
  bool ok = false;
  std::string wanted;
  if (std::string(name) == "ROTATION") {
    ok = type == "VEC4" && (component == internal::kFloat ||
                            (normalized && (component == internal::kByte || component == internal::kShort)));
    wanted = "VEC4 of FLOAT, or of normalized BYTE or SHORT";
  } else {
    ok = type == "VEC3" && component == internal::kFloat;
    wanted = "VEC3 of FLOAT";
  }
  if (!ok) {
    diag.error(codes::INSTANCING_INVALID, here,
               std::string(name) + " must be " + wanted + "; accessor " + std::to_string(*index) +
                   " is " + type + " of component type " + std::to_string(component));
    return std::nullopt;
  }
  return static_cast<std::size_t>(*index);
}

}  // namespace

std::optional<std::vector<Eigen::Affine3d>> instance_transforms(const GltfAsset& asset, std::size_t node,
                                                                std::uint64_t max_instances,
                                                                Diagnostics& diag, std::size_t input_node) {
  const Json& node_json = asset.document["nodes"][node];
  if (!node_json.contains("extensions") || !node_json["extensions"].is_object() ||
      !node_json["extensions"].contains(kInstancing)) {
    return std::vector<Eigen::Affine3d>{Eigen::Affine3d::Identity()};
  }
  const std::string pointer = json_pointer("/nodes", input_node) + "/extensions/" + kInstancing + "/attributes";
  const Json& extension = node_json["extensions"][kInstancing];
  if (!extension.is_object() || !extension.contains("attributes") || !extension["attributes"].is_object() ||
      extension["attributes"].empty()) {
    diag.error(codes::INSTANCING_INVALID, pointer, node_label(asset.document, input_node) +
               ": the extension needs an 'attributes' object with TRANSLATION, ROTATION or SCALE");
    return std::nullopt;
  }
  const Json& attributes = extension["attributes"];
  std::vector<double> translation, rotation, scale;
  std::optional<std::size_t> count;
  double rotation_step = 0;  // of a normalized integer ROTATION: each component within half of it
  for (const char* name : {"TRANSLATION", "ROTATION", "SCALE"}) {
    if (!attributes.contains(name)) continue;
    const auto accessor = attribute_accessor(asset, attributes, name, pointer, diag);
    if (!accessor) return std::nullopt;
    const auto n = asset.document["accessors"][*accessor]["count"].get<std::size_t>();
    if (count && *count != n) {
      diag.error(codes::INSTANCING_INVALID, pointer + "/" + name,
                 std::string(name) + " has " + std::to_string(n) + " elements but another attribute has " +
                     std::to_string(*count) + ": every attribute needs one per instance");
      return std::nullopt;
    }
    count = n;
    if (n > max_instances) {
      diag.error(codes::LIMIT_EXCEEDED, pointer + "/" + name,
                 std::to_string(n) + " instances of " + node_label(asset.document, input_node) +
                     " exceed what the triangle limit allows for its mesh (" + std::to_string(max_instances) + ")");
      return std::nullopt;
    }
    if (std::string(name) == "ROTATION" && asset.document["accessors"][*accessor].value("normalized", false)) {
      rotation_step = asset.document["accessors"][*accessor]["componentType"].get<std::uint64_t>() == internal::kByte
                          ? 1.0 / 127
                          : 1.0 / 32767;
    }
    std::vector<double> values = read_accessor(asset, *accessor);
    for (std::size_t k = 0; k < values.size(); ++k) {
      if (!std::isfinite(values[k])) {
        diag.error(codes::INSTANCING_INVALID, pointer + "/" + name,
                   std::string(name) + " element " + std::to_string(k / (values.size() / n)) + " is not finite");
        return std::nullopt;
      }
    }
    (std::string(name) == "TRANSLATION" ? translation : std::string(name) == "ROTATION" ? rotation : scale) =
        std::move(values);
  }
  std::vector<Eigen::Affine3d> instances;
  instances.reserve(count.value_or(0));
  for (std::size_t i = 0; i < count.value_or(0); ++i) {
    Eigen::Affine3d X_NI = Eigen::Affine3d::Identity();
    if (!translation.empty()) X_NI.translate(Eigen::Vector3d(translation[3 * i], translation[3 * i + 1], translation[3 * i + 2]));
    if (!rotation.empty()) {
      // glTF quaternions are x, y, z, w; quantized ones are only near unit: normalized here.
      Eigen::Quaterniond q(rotation[4 * i + 3], rotation[4 * i], rotation[4 * i + 1], rotation[4 * i + 2]);
      if (q.norm() < 1e-6) {
        diag.error(codes::INSTANCING_INVALID, pointer + "/ROTATION",
                   "ROTATION element " + std::to_string(i) + " is not a rotation (a zero quaternion)");
        return std::nullopt;
      }
      // A unit quaternion within the tolerance the Khronos validator gives a node's rotation
      // (0.00769 of length), plus what quantization allows: four components each within half a
      // step change the length by at most one step. A quaternion of length 2 is no rotation the
      // exporter meant, and normalizing it would place the instance silently.
      if (!(std::abs(q.norm() - 1) <= 0.00769 + rotation_step)) {
        diag.error(codes::INSTANCING_INVALID, pointer + "/ROTATION",
                   "ROTATION element " + std::to_string(i) + " has length " + format_number(q.norm()) +
                       "; each must be a unit quaternion (x, y, z, w)");
        return std::nullopt;
      }
      X_NI.rotate(q.normalized().toRotationMatrix());
    }
    if (!scale.empty()) X_NI.scale(Eigen::Vector3d(scale[3 * i], scale[3 * i + 1], scale[3 * i + 2]));
    instances.push_back(X_NI);
  }
  return instances;
}

}  // namespace rdtf
