// The GLB container parser alone, with make_glb as its inverse.
#include "fuzz_pipeline.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rdtf::fuzz;
  const std::vector<std::uint8_t> bytes(data, data + size);
  std::string roundtrip_failure;
  const RunResult run = parse_glb_bytes(bytes, roundtrip_failure);
  require(contract_violation(run));
  require(roundtrip_failure);
  return 0;
}
