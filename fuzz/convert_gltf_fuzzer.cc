// The whole convert pipeline from .gltf (JSON) bytes: load confined to a temp folder, type,
// complete, mass properties, RDTF JSON in memory, and the output converted once more.
#include "fuzz_pipeline.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rdtf::fuzz;
  std::vector<std::uint8_t> bytes(data, data + size);
  if (rdtf::looks_like_glb(bytes)) return -1;  // The GLB target's input; keep the corpus apart.
  std::string reconvert_failure;
  const RunResult run = convert_and_reconvert(bytes, work_dir("convert_gltf"), reconvert_failure);
  require(contract_violation(run));
  require(reconvert_failure);
  return 0;
}
