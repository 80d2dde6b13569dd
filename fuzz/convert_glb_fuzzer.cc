// The whole convert pipeline from .glb bytes (container, JSON chunk, BIN chunk), output
// converted once more with its buffer in the binary chunk. JSON input is left to convert_gltf.
// The work is fuzz_pipeline.h's run_target("convert_glb", ...), which the regression tests replay.
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return rdtf::fuzz::fuzz_one("convert_glb", data, size);
}
