// What each accessor and buffer view is used for. glTF lets an accessor serve one purpose (vertex
// data, indices, inverse bind matrices, animation keys or values) and a buffer view hold one kind
// of data (vertices, indices, inverse bind matrices, an image, sparse or animation data): a GPU
// binds a buffer view as one target, and the Khronos validator refuses a file whose references
// give one two
// (ACCESSOR_USAGE_OVERRIDE, BUFFER_VIEW_TARGET_OVERRIDE). rdtf copies these references into its
// output as they are, so it refuses them too, or it would write a file the validator refuses.
//
// The first use sets the purpose, and every later one that differs is an error at the later
// reference, as the validator has it (version 2.0.0-dev.3.10): a view's target counts first,
// then references in the validator's fixed order: accessors' sparse parts, images, meshes
// (per primitive its attributes in the file's key order, its indices, its morph targets),
// skins, animations (per sampler its input, then its output).
#include <iterator>
#include <string>

#include "document_check.h"
#include "validate_util.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::internal {
namespace {

// Each usage's name as the validator prints it, and what it is in words; by enumerator.
struct UsageText {
  const char* name;
  const char* what;
};
constexpr UsageText kAccessorUsageText[] = {{"none", "nothing"},
                                            {"VertexAttribute", "vertex data"},
                                            {"PrimitiveIndices", "indices"},
                                            {"IBM", "inverse bind matrices"},
                                            {"AnimationInput", "animation key times"},
                                            {"AnimationOutput", "animation values"}};
constexpr UsageText kViewUsageText[] = {{"none", "nothing"},
                                        {"VertexBuffer", "vertices (target 34962, ARRAY_BUFFER)"},
                                        {"IndexBuffer", "indices (target 34963, ELEMENT_ARRAY_BUFFER)"},
                                        {"IBM", "inverse bind matrices"},
                                        {"Image", "an image"},
                                        {"Other", "sparse or animation data"}};
static_assert(std::size(kAccessorUsageText) == static_cast<std::size_t>(AccessorUsage::kAnimationOutput) + 1);
static_assert(std::size(kViewUsageText) == static_cast<std::size_t>(ViewUsage::kOther) + 1);

const UsageText& text_of(AccessorUsage usage) { return kAccessorUsageText[static_cast<std::size_t>(usage)]; }
const UsageText& text_of(ViewUsage usage) { return kViewUsageText[static_cast<std::size_t>(usage)]; }

// "vertex data ('VertexAttribute')"
template <typename Usage>
std::string described(Usage usage) {
  return std::string(text_of(usage).what) + " ('" + text_of(usage).name + "')";
}

ViewUsage view_usage_of(AccessorUsage usage) {
  switch (usage) {
    case AccessorUsage::kVertexAttribute: return ViewUsage::kVertexBuffer;
    case AccessorUsage::kPrimitiveIndices: return ViewUsage::kIndexBuffer;
    case AccessorUsage::kIbm: return ViewUsage::kIbm;
    case AccessorUsage::kAnimationInput:
    case AccessorUsage::kAnimationOutput: return ViewUsage::kOther;
    case AccessorUsage::kUnused: break;
  }
  return ViewUsage::kUnused;
}

}  // namespace

// Reads an index without reporting it: the checks that read these references have said what is
// wrong with one that does not resolve.
std::size_t DocumentCheck::index_at(const Json& object, const char* key, const char* array) {
  if (!object.is_object()) return kNone;
  const auto index = uint_at(object, key);
  if (!index || *index >= entries_[array].size()) return kNone;
  return static_cast<std::size_t>(*index);
}

void DocumentCheck::use_view(std::size_t view, ViewUsage usage, const std::string& pointer) {
  if (view == kNone || view >= views_.size()) return;
  ViewUsage& held = views_[view].usage;
  if (held == ViewUsage::kUnused) held = usage;
  if (held == usage) return;
  diag_.error(codes::BUFFER_VIEW_TARGET_OVERRIDE, pointer,
              "buffer view " + std::to_string(view) + " holds " + described(held) +
                  " by its target or first use, but is used here for " + described(usage) +
                  ": a buffer view holds one kind of data; give this one a buffer view of its own");
}

void DocumentCheck::use_accessor(std::size_t accessor, AccessorUsage usage, const std::string& pointer) {
  if (accessor == kNone || accessor >= accessors_.size()) return;
  AccessorUsage& held = accessor_usage_[accessor];
  if (held == AccessorUsage::kUnused) held = usage;
  if (held != usage) {
    diag_.error(codes::ACCESSOR_USAGE_OVERRIDE, pointer,
                "accessor " + std::to_string(accessor) + " is used first for " + described(held) +
                    " and here for " + described(usage) +
                    ": an accessor serves one purpose; give this use an accessor of its own");
  }
  use_view(accessors_[accessor].view, view_usage_of(usage), pointer);
}

void DocumentCheck::check_usages() {
  accessor_usage_.assign(accessors_.size(), AccessorUsage::kUnused);
  const auto& accessors = entries_["accessors"];
  for (std::size_t i = 0; i < accessors.size(); ++i) {
    if (accessors[i] == nullptr || !accessors[i]->contains("sparse")) continue;
    // The validator links an accessor's sparse parts only when its componentType, count and type
    // could be read (it skips them otherwise; VALUE_NOT_IN_LIST of a componentType is its warning).
    const Json& accessor = *accessors[i];
    const auto component_type = uint_at(accessor, "componentType");
    const auto count = uint_at(accessor, "count");
    if (!component_type || component_size(*component_type) == 0 || !count || *count < 1 ||
        !accessor.contains("type") || !accessor["type"].is_string()) {
      continue;
    }
    const Json& sparse = accessor["sparse"];
    if (!sparse.is_object()) continue;
    const std::string here = json_pointer("/accessors", i) + "/sparse";
    for (const char* part : {"indices", "values"}) {
      if (!sparse.contains(part)) continue;
      use_view(index_at(sparse[part], "bufferView", "bufferViews"), ViewUsage::kOther,
               here + "/" + part + "/bufferView");
    }
  }
  const auto& images = entries_["images"];
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (images[i] == nullptr) continue;
    use_view(index_at(*images[i], "bufferView", "bufferViews"), ViewUsage::kImage,
             json_pointer("/images", i) + "/bufferView");
  }
  const auto& meshes = entries_["meshes"];
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    if (meshes[m] == nullptr || !meshes[m]->contains("primitives")) continue;
    const Json& primitives = (*meshes[m])["primitives"];
    if (!primitives.is_array()) continue;
    for (std::size_t p = 0; p < primitives.size(); ++p) {
      const Json& primitive = primitives[p];
      if (!primitive.is_object()) continue;
      const std::string here = json_pointer(json_pointer("/meshes", m) + "/primitives", p);
      const auto use_attributes = [&](const Json& attributes, const std::string& pointer) {
        if (!attributes.is_object()) return;
        for (const auto& [name, value] : attributes.items()) {
          const auto index = as_uint(value);
          if (!index) continue;
          use_accessor(static_cast<std::size_t>(*index), AccessorUsage::kVertexAttribute,
                       json_pointer(pointer, name));
        }
      };
      if (primitive.contains("attributes")) use_attributes(primitive["attributes"], here + "/attributes");
      use_accessor(index_at(primitive, "indices", "accessors"), AccessorUsage::kPrimitiveIndices,
                   here + "/indices");
      if (primitive.contains("targets") && primitive["targets"].is_array()) {
        const Json& targets = primitive["targets"];
        for (std::size_t t = 0; t < targets.size(); ++t) {
          use_attributes(targets[t], json_pointer(here + "/targets", t));
        }
      }
    }
  }
  const auto& skins = entries_["skins"];
  for (std::size_t s = 0; s < skins.size(); ++s) {
    if (skins[s] == nullptr) continue;
    use_accessor(index_at(*skins[s], "inverseBindMatrices", "accessors"), AccessorUsage::kIbm,
                 json_pointer("/skins", s) + "/inverseBindMatrices");
  }
  const auto& animations = entries_["animations"];
  for (std::size_t a = 0; a < animations.size(); ++a) {
    if (animations[a] == nullptr || !animations[a]->contains("samplers")) continue;
    const Json& samplers = (*animations[a])["samplers"];
    if (!samplers.is_array()) continue;
    for (std::size_t i = 0; i < samplers.size(); ++i) {
      const std::string here = json_pointer(json_pointer("/animations", a) + "/samplers", i);
      use_accessor(index_at(samplers[i], "input", "accessors"), AccessorUsage::kAnimationInput, here + "/input");
      use_accessor(index_at(samplers[i], "output", "accessors"), AccessorUsage::kAnimationOutput,
                   here + "/output");
    }
  }
}

}  // namespace rdtf::internal
