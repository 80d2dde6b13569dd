// extras.RDTF and node extras (fuzz_pipeline.h: model_with_extras) put into tests/data's
// blender/arm3 model, a three-link arm with joint properties in its node extras, then converted.
#include "fuzz_pipeline.h"
#include "fuzz_support.h"

namespace {

const rdtf::Json& base_model() {
  static const rdtf::Json base = [] {
    const auto bytes = rdtf::fuzz::read_bytes(std::filesystem::path(RDTF_FUZZ_DATA_DIR) / "blender/arm3.gltf");
    return rdtf::Json::parse(bytes.begin(), bytes.end());
  }();
  return base;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rdtf::fuzz;
  const auto model = model_with_extras(base_model(), std::string(reinterpret_cast<const char*>(data), size));
  if (!model) return -1;
  std::string reconvert_failure;
  const RunResult run = convert_and_reconvert(*model, work_dir("extras"), reconvert_failure);
  require(contract_violation(run));
  require(reconvert_failure);
  return 0;
}
