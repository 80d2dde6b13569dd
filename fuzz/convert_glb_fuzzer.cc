// The whole convert pipeline from .glb bytes (container, JSON chunk, BIN chunk), output
// converted once more with its buffer in the binary chunk.
#include "fuzz_pipeline.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rdtf::fuzz;
  std::vector<std::uint8_t> bytes(data, data + size);
  if (!rdtf::looks_like_glb(bytes)) return -1;  // JSON input is the .gltf target's.
  std::string reconvert_failure;
  const RunResult run = convert_and_reconvert(bytes, work_dir("convert_glb"), reconvert_failure);
  require(contract_violation(run));
  require(reconvert_failure);
  return 0;
}
