// extras.RDTF and node extras (fuzz_pipeline.h: model_with_extras) put into tests/data's
// blender/arm3 model, a three-link arm with joint properties in its node extras, then converted
// (and its output converted again). Input that is not JSON is left alone.
// The work is fuzz_pipeline.h's run_target("extras", ...), which the regression tests replay.
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return rdtf::fuzz::fuzz_one("extras", data, size);
}
