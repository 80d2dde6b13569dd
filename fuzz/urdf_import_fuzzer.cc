// URDF import (urdfdom parse, geometry, the glTF it builds, its conversion) from bytes written to
// one fixed file per process.
// The work is fuzz_pipeline.h's run_target("urdf_import", ...), which the regression tests replay.
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return rdtf::fuzz::fuzz_one("urdf_import", data, size);
}
