// The whole convert pipeline from .gltf (JSON) bytes: load confined to a temp folder, type,
// complete, mass properties, RDTF JSON in memory, and the output converted once more. GLB input
// is left to convert_glb.
// The work is fuzz_pipeline.h's run_target("convert_gltf", ...), which the regression tests replay.
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return rdtf::fuzz::fuzz_one("convert_gltf", data, size);
}
