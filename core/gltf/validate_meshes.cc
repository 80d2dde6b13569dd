// Meshes: primitives, their attributes, indices and morph targets. See document_check.h.
#include <algorithm>

#include "document_check.h"
#include "validate_util.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/geometry.h"

namespace rdtf::internal {
namespace {

// "POSITION", "TEXCOORD_0", "_CUSTOM": the attribute names glTF allows, split into semantic and
// set index (-1 for none). Morph targets allow fewer.
std::optional<std::pair<std::string, long>> parse_semantic(const std::string& name, bool target) {
  if (name.size() > 1 && name[0] == '_') return std::pair{name, -1L};
  if (name == "POSITION" || name == "NORMAL" || name == "TANGENT") return std::pair{name, -1L};
  const auto underscore = name.rfind('_');
  if (underscore == std::string::npos) return std::nullopt;
  const std::string base = name.substr(0, underscore);
  const std::string digits = name.substr(underscore + 1);
  const bool indexed =
      base == "TEXCOORD" || base == "COLOR" || (!target && (base == "JOINTS" || base == "WEIGHTS"));
  if (!indexed || digits.empty() || digits.size() > 6 || (digits.size() > 1 && digits[0] == '0') ||
      digits.find_first_not_of("0123456789") != std::string::npos) {
    return std::nullopt;
  }
  return std::pair{base, std::stol(digits)};
}

std::string format_name(const AccessorFacts& accessor) {
  return accessor.type + " of component type " + std::to_string(accessor.component_type) +
         (accessor.normalized ? " (normalized)" : "");
}

}  // namespace

void DocumentCheck::check_meshes() {
  const auto& meshes = entries_["meshes"];
  meshes_.resize(meshes.size());
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    if (meshes[m] != nullptr) check_mesh(*meshes[m], json_pointer("/meshes", m), meshes_[m]);
  }
}

void DocumentCheck::check_mesh(const Json& mesh, const std::string& pointer, MeshFacts& facts) {
  const Json* primitives = read_array(mesh, "primitives", pointer, true);
  const auto weights = read_numbers(mesh, "weights", pointer, 0);
  if (primitives == nullptr) return;
  facts.valid = true;
  for (std::size_t p = 0; p < primitives->size(); ++p) {
    const std::string here = json_pointer(pointer + "/primitives", p);
    const Json* primitive = object_at(*primitives, p, pointer + "/primitives");
    if (primitive == nullptr || !check_primitive(*primitive, here, facts)) {
      facts.valid = false;
      continue;
    }
    const std::size_t targets = primitive->contains("targets") ? (*primitive)["targets"].size() : 0;
    if (p == 0) facts.targets = targets;
    if (targets != facts.targets) {
      diag_.error(codes::MESH_PRIMITIVES_UNEQUAL_TARGETS_COUNT, here + (targets != 0 ? "/targets" : ""),
                  "the primitive has " + std::to_string(targets) +
                      " morph targets but the first has " + std::to_string(facts.targets) +
                      "; all primitives of a mesh must have as many");
    }
  }
  if (weights && facts.valid && weights->size() != facts.targets) {
    diag_.error(codes::MESH_INVALID_WEIGHTS_COUNT, pointer + "/weights",
                "the mesh has " + std::to_string(weights->size()) + " weights for " +
                    std::to_string(facts.targets) + " morph targets");
  }
}

// True when the primitive has no error; adds its triangles to the mesh's.
bool DocumentCheck::check_primitive(const Json& primitive, const std::string& pointer,
                                    MeshFacts& mesh) {
  const std::size_t errors = diag_.error_count();
  const Json* attributes = read_object(primitive, "attributes", pointer, true);
  std::map<std::string, std::size_t> accessors;  // The attributes with a valid accessor.
  if (attributes != nullptr)
    accessors = check_attributes(*attributes, pointer + "/attributes", false);
  const std::size_t indices = read_ref(primitive, "indices", pointer, "accessors");
  // An accessor that failed its own checks is still checked for what it is (its type and
  // component type, read before they failed): FLOAT indices, or a byteStride on an index view,
  // were said only as the layout error they lead to, ACCESSOR_TOO_LONG, whose fix is another
  // (s100err D2); the validator says both.
  if (indices != kNone && (accessors_[indices].valid || !accessors_[indices].type.empty())) {
    check_indices(indices, pointer + "/indices");
  }
  const auto mode = read_uint(primitive, "mode", pointer).value_or(4);
  if (mode > 6) {
    diag_.error(codes::VALUE_NOT_IN_RANGE, pointer + "/mode",
                "mode " + std::to_string(mode) +
                    " is not a glTF primitive mode (0 POINTS .. 6 TRIANGLE_FAN)");
  }
  read_ref(primitive, "material", pointer, "materials");
  if (const Json* targets = read_array(primitive, "targets", pointer)) {
    for (std::size_t t = 0; t < targets->size(); ++t) {
      const Json* target = object_at(*targets, t, pointer + "/targets");
      if (target != nullptr)
        check_target(*target, json_pointer(pointer + "/targets", t), accessors);
    }
  }
  // By the attribute's presence: a JOINTS_0 whose accessor was refused (and so is not in
  // `accessors`) is still one, and the node's skin is no second error (s80rev R5).
  mesh.skinned |= accessors.count("JOINTS_0") > 0 ||
                  (primitive.contains("attributes") && primitive["attributes"].is_object() &&
                   primitive["attributes"].contains("JOINTS_0"));
  const auto position = accessors.find("POSITION");
  const std::uint64_t vertices = indices != kNone              ? accessors_[indices].count
                                 : position != accessors.end() ? accessors_[position->second].count
                                                               : 0;
  // Only triangles are morphed (read_primitive_triangles): points and lines cost nothing more.
  if (mode >= 4 && position != accessors.end() && primitive.contains("targets") && primitive["targets"].is_array()) {
    const Json& targets = primitive["targets"];
    if (mesh.target_vertices.size() < targets.size()) mesh.target_vertices.resize(targets.size(), 0);
    for (std::size_t t = 0; t < targets.size(); ++t) {
      if (!targets[t].is_object() || !targets[t].contains("POSITION")) continue;
      mesh.target_vertices[t] = saturating_add(mesh.target_vertices[t], accessors_[position->second].count);
    }
  }
  if (mode == 4) mesh.triangles = saturating_add(mesh.triangles, vertices / 3);
  if ((mode == 5 || mode == 6) && vertices >= 3) {
    mesh.triangles = saturating_add(mesh.triangles, vertices - 2);
  }
  return diag_.error_count() == errors;
}

// Names, references and formats of a primitive's attributes (or of a morph target's); returns
// those with a valid accessor.
std::map<std::string, std::size_t> DocumentCheck::check_attributes(const Json& attributes,
                                                                   const std::string& pointer,
                                                                   bool target) {
  std::map<std::string, std::size_t> resolved;
  std::map<std::string, std::vector<long>> sets;  // "TEXCOORD" -> {0, 1}
  std::uint64_t count = 0;
  for (const auto& [name, value] : attributes.items()) {
    const std::string here = json_pointer(pointer, name);
    const auto semantic = parse_semantic(name, target);
    if (!semantic) {
      diag_.error(codes::MESH_PRIMITIVE_INVALID_ATTRIBUTE, here,
                  "'" + quote(name) + "' is not a glTF attribute name");
    }
    const std::size_t accessor = reference(value, here, "accessors");
    if (accessor == kNone) continue;
    // Its format whatever its name, as the validator does (TEXCOORD_01 is checked as a TEXCOORD).
    if (!accessors_[accessor].type.empty()) check_attribute_format(name, accessor, here, target);
    if (!semantic) continue;
    if (semantic->second >= 0) sets[semantic->first].push_back(semantic->second);
    if (!accessors_[accessor].valid) continue;
    resolved[name] = accessor;
    check_attribute_alignment(name, accessor, here);
    if (count != 0 && accessors_[accessor].count != count) {
      diag_.error(codes::MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT, here,
                  "has " + std::to_string(accessors_[accessor].count) +
                      " elements but another attribute has " + std::to_string(count) +
                      "; all attributes of a primitive must have the same count");
    }
    count = accessors_[accessor].count;
  }
  for (auto& [base, numbers] : sets) {
    std::sort(numbers.begin(), numbers.end());
    if (numbers.back() + 1 != static_cast<long>(numbers.size())) {
      diag_.error(codes::MESH_PRIMITIVE_INDEXED_SEMANTIC_CONTINUITY, pointer,
                  base + "_n attributes must be numbered 0, 1, 2... without gaps; found " +
                      std::to_string(numbers.size()) + " up to " + base + "_" +
                      std::to_string(numbers.back()));
    }
  }
  if (!target && sets["JOINTS"].size() != sets["WEIGHTS"].size()) {
    diag_.error(codes::MESH_PRIMITIVE_JOINTS_WEIGHTS_MISMATCH, pointer,
                std::to_string(sets["JOINTS"].size()) + " JOINTS_n attributes but " +
                    std::to_string(sets["WEIGHTS"].size()) + " WEIGHTS_n; they come in pairs");
  }
  return resolved;
}

// glTF 2.0 (3.6.2.4): each element of a vertex attribute starts at a multiple of 4 bytes, so the
// accessor's start in its buffer and its stride (byteStride, else the element's size) are
// multiples of 4. A file that breaks it is refused: its data would be read right, but the output,
// which keeps the layout, would be no valid glTF (the Khronos validator's error of this name).
void DocumentCheck::check_attribute_alignment(const std::string& name, std::size_t accessor, const std::string& pointer) {
  const AccessorFacts& facts = accessors_[accessor];
  if (facts.view == kNone || facts.view >= views_.size() || !views_[facts.view].valid) return;  // Sparse only: no layout.
  const ViewFacts& view = views_[facts.view];
  const Json& json = doc_["accessors"][accessor];
  const std::uint64_t offset =
      json.contains("byteOffset") && json["byteOffset"].is_number_unsigned() ? json["byteOffset"].get<std::uint64_t>() : 0;
  const std::uint64_t start = view.byte_offset + offset;
  // (Vertex attributes are SCALAR or VECn: no matrix padding.)
  const std::uint64_t stride = view.byte_stride != 0
                                   ? view.byte_stride
                                   : static_cast<std::uint64_t>(std::max(component_count(facts.type), 0)) *
                                         component_size(facts.component_type);
  if (start % 4 == 0 && stride % 4 == 0) return;
  diag_.error(codes::MESH_PRIMITIVE_ACCESSOR_UNALIGNED, pointer,
              "attribute " + name + " reads accessor " + std::to_string(accessor) + ", whose elements " +
                  (start % 4 != 0 ? "start at byte " + std::to_string(start) + " of its buffer"
                                  : std::string("are ") + std::to_string(stride) + " bytes apart (" + facts.type +
                                        " of " + std::to_string(component_size(facts.component_type)) +
                                        "-byte components, no byteStride)") +
                  ": glTF requires every vertex attribute element to start at a multiple of 4 bytes. Give the "
                  "buffer view a byteStride that is a multiple of 4 (8 for 16-bit VEC3), as gltfpack and Blender "
                  "write them");
}

void DocumentCheck::check_indices(std::size_t accessor, const std::string& pointer) {
  const AccessorFacts& facts = accessors_[accessor];
  const std::uint64_t type = facts.component_type;
  if (facts.type != "SCALAR" || facts.normalized ||
      (type != kUnsignedByte && type != kUnsignedShort && type != kUnsignedInt)) {
    diag_.error(codes::MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT, pointer,
                "indices must be SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT, not " +
                    format_name(facts));
  }
  if (facts.view != kNone && views_[facts.view].byte_stride != 0) {
    diag_.error(codes::MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE, pointer,
                "buffer view " + std::to_string(facts.view) +
                    " holds indices, so it must not have a byteStride");
  }
}

void DocumentCheck::check_target(const Json& target, const std::string& pointer,
                                 const std::map<std::string, std::size_t>& base) {
  const auto attributes = check_attributes(target, pointer, true);
  for (const auto& [name, value] : target.items()) {
    if (base.count(name) != 0) continue;
    diag_.error(codes::MESH_PRIMITIVE_MORPH_TARGET_NO_BASE_ACCESSOR, json_pointer(pointer, name),
                "the morph target moves " + quote(name) + ", which the primitive does not have");
  }
  for (const auto& [name, accessor] : attributes) {
    const auto found = base.find(name);
    if (found == base.end() || accessors_[found->second].count == accessors_[accessor].count) {
      continue;
    }
    diag_.error(codes::MESH_PRIMITIVE_MORPH_TARGET_INVALID_ATTRIBUTE_COUNT, json_pointer(pointer, name),
                "has " + std::to_string(accessors_[accessor].count) +
                    " elements but the primitive's " + name + " has " +
                    std::to_string(accessors_[found->second].count));
  }
}

}  // namespace rdtf::internal
