// The GLB container parser alone, with make_glb as its inverse.
// The work is fuzz_pipeline.h's run_target("glb", ...), which the regression tests replay.
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return rdtf::fuzz::fuzz_one("glb", data, size);
}
