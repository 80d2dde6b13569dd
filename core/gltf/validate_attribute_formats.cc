// The formats (type, componentType, normalized) a vertex attribute's accessor may have, on a
// primitive and on a morph target, as glTF 2.0 (3.7.2.1, 3.7.2.2) and KHR_mesh_quantization list
// them and the Khronos validator checks them. rdtf reads only POSITION, JOINTS_n and WEIGHTS_n, but
// it writes every attribute into its output: a NORMAL of MAT4 passed on would be an output the
// validator refuses, so each is checked here, with the validator's codes at its places.
#include <string>
#include <vector>

#include "document_check.h"
#include "rdtf/diagnostic_codes.h"
#include "validate_util.h"

namespace rdtf::internal {
namespace {

struct Format {
  const char* type;
  std::uint64_t component;
  bool normalized;
};

struct Rule {
  const char* semantic;           // The name up to its first '_': "TEXCOORD" for TEXCOORD_3.
  bool target;                    // On a morph target, not the primitive itself.
  std::vector<Format> core;       // glTF 2.0.
  std::vector<Format> quantized;  // Added by KHR_mesh_quantization.
};

constexpr bool kNorm = true, kRaw = false;

// gltf-validator 2.0.0-dev.3.10's tables, read from its code (the map built in its context's
// constructor, and what the extension's initialiser adds to it).
const std::vector<Rule>& rules() {
  static const std::vector<Rule> table = {
      {"POSITION", false, {{"VEC3", kFloat, kRaw}},
       {{"VEC3", kByte, kRaw}, {"VEC3", kByte, kNorm}, {"VEC3", kUnsignedByte, kRaw},
        {"VEC3", kUnsignedByte, kNorm}, {"VEC3", kShort, kRaw}, {"VEC3", kShort, kNorm},
        {"VEC3", kUnsignedShort, kRaw}, {"VEC3", kUnsignedShort, kNorm}}},
      {"NORMAL", false, {{"VEC3", kFloat, kRaw}}, {{"VEC3", kByte, kNorm}, {"VEC3", kShort, kNorm}}},
      {"TANGENT", false, {{"VEC4", kFloat, kRaw}}, {{"VEC4", kByte, kNorm}, {"VEC4", kShort, kNorm}}},
      {"TEXCOORD", false,
       {{"VEC2", kFloat, kRaw}, {"VEC2", kUnsignedByte, kNorm}, {"VEC2", kUnsignedShort, kNorm}},
       {{"VEC2", kByte, kRaw}, {"VEC2", kByte, kNorm}, {"VEC2", kUnsignedByte, kRaw}, {"VEC2", kShort, kRaw},
        {"VEC2", kShort, kNorm}, {"VEC2", kUnsignedShort, kRaw}}},
      {"COLOR", false,
       {{"VEC3", kFloat, kRaw}, {"VEC3", kUnsignedByte, kNorm}, {"VEC3", kUnsignedShort, kNorm},
        {"VEC4", kFloat, kRaw}, {"VEC4", kUnsignedByte, kNorm}, {"VEC4", kUnsignedShort, kNorm}},
       {}},
      {"JOINTS", false, {{"VEC4", kUnsignedByte, kRaw}, {"VEC4", kUnsignedShort, kRaw}}, {}},
      {"WEIGHTS", false,
       {{"VEC4", kFloat, kRaw}, {"VEC4", kUnsignedByte, kNorm}, {"VEC4", kUnsignedShort, kNorm}}, {}},
      // A morph target holds displacements: signed, and TANGENT without its handedness.
      {"POSITION", true, {{"VEC3", kFloat, kRaw}},
       {{"VEC3", kByte, kRaw}, {"VEC3", kByte, kNorm}, {"VEC3", kShort, kRaw}, {"VEC3", kShort, kNorm}}},
      {"NORMAL", true, {{"VEC3", kFloat, kRaw}}, {{"VEC3", kByte, kNorm}, {"VEC3", kShort, kNorm}}},
      {"TANGENT", true, {{"VEC3", kFloat, kRaw}}, {{"VEC3", kByte, kNorm}, {"VEC3", kShort, kNorm}}},
      {"TEXCOORD", true,
       {{"VEC2", kFloat, kRaw}, {"VEC2", kByte, kNorm}, {"VEC2", kUnsignedByte, kNorm}, {"VEC2", kShort, kNorm},
        {"VEC2", kUnsignedShort, kNorm}},
       {{"VEC2", kByte, kRaw}, {"VEC2", kShort, kRaw}}},
      {"COLOR", true,
       {{"VEC3", kFloat, kRaw}, {"VEC3", kByte, kNorm}, {"VEC3", kUnsignedByte, kNorm}, {"VEC3", kShort, kNorm},
        {"VEC3", kUnsignedShort, kNorm}, {"VEC4", kFloat, kRaw}, {"VEC4", kByte, kNorm},
        {"VEC4", kUnsignedByte, kNorm}, {"VEC4", kShort, kNorm}, {"VEC4", kUnsignedShort, kNorm}},
       {}},
  };
  return table;
}

std::string component_name(std::uint64_t component) {
  switch (component) {
    case kByte: return "BYTE";
    case kUnsignedByte: return "UNSIGNED_BYTE";
    case kShort: return "SHORT";
    case kUnsignedShort: return "UNSIGNED_SHORT";
    case kUnsignedInt: return "UNSIGNED_INT";
    case kFloat: return "FLOAT";
    default: return "component type " + std::to_string(component);
  }
}

std::string text(const Format& format) {
  return std::string(format.type) + " of " + (format.normalized ? "normalized " : "") + component_name(format.component);
}

std::string list(const std::vector<Format>& formats) {
  std::string out;
  for (std::size_t i = 0; i < formats.size(); ++i) {
    if (i != 0) out += i + 1 == formats.size() ? " or " : ", ";
    out += text(formats[i]);
  }
  return out;
}

bool listed(const std::vector<Format>& formats, const AccessorFacts& facts) {
  for (const Format& format : formats) {
    if (facts.type == format.type && facts.component_type == format.component && facts.normalized == format.normalized) {
      return true;
    }
  }
  return false;
}

}  // namespace

void DocumentCheck::check_attribute_format(const std::string& name, std::size_t accessor, const std::string& pointer,
                                           bool target) {
  const AccessorFacts& facts = accessors_[accessor];
  const std::string semantic = name.substr(0, name.find('_'));
  const Rule* rule = nullptr;
  for (const Rule& r : rules()) {
    if (semantic == r.semantic && target == r.target) rule = &r;
  }
  if (rule == nullptr) {
    // Application data (_NAME), or a name that is no glTF attribute (refused for its name
    // already): any format but UNSIGNED_INT, which no graphics API takes as a vertex attribute.
    if (!target && facts.component_type == kUnsignedInt) {
      diag_.error(codes::MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_UNSIGNED_INT, pointer,
                  "attribute " + name + " reads accessor " + std::to_string(accessor) +
                      " of UNSIGNED_INT components, which glTF does not allow for a vertex attribute; store it as "
                      "FLOAT, or as UNSIGNED_SHORT or smaller");
    }
  } else if (!listed(rule->core, facts) && !(quantization_ && listed(rule->quantized, facts))) {
    std::vector<Format> allowed = rule->core;
    if (quantization_) allowed.insert(allowed.end(), rule->quantized.begin(), rule->quantized.end());
    const bool needs_quantization = !quantization_ && listed(rule->quantized, facts);
    diag_.error(codes::MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT, pointer,
                "accessor " + std::to_string(accessor) + " is " +
                    text({facts.type.c_str(), facts.component_type, facts.normalized}) + "; " + name +
                    (target ? " of a morph target" : "") + " must be " + list(allowed) +
                    (needs_quantization ? " (" + text({facts.type.c_str(), facts.component_type, facts.normalized}) +
                                              " needs KHR_mesh_quantization in extensionsUsed and extensionsRequired)"
                                        : ""));
  }
  // The validator asks a POSITION for its bounds whatever its format.
  const Json& json = *entries_["accessors"][accessor];
  if (name == "POSITION" && (!json.contains("min") || !json.contains("max"))) {
    diag_.error(codes::MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS, pointer,
                "a POSITION accessor must declare min and max (its bounding box)");
  }
}

}  // namespace rdtf::internal
