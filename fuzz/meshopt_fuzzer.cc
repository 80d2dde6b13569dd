// The meshopt decoder (libmeshoptimizer), its input the compressed bytes of a GLB's one mesh (decoder_models.h).
// The work is fuzz_pipeline.h's run_target("meshopt", ...), which the regression tests replay.
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return rdtf::fuzz::fuzz_one("meshopt", data, size);
}
