// URDF import (urdfdom parse, geometry, the glTF it builds, its conversion) from bytes written to
// one fixed file per process.
#include "fuzz_pipeline.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rdtf::fuzz;
  const std::vector<std::uint8_t> bytes(data, data + size);
  const RunResult run = import_urdf_bytes(bytes, work_dir("urdf_import"));
  require(contract_violation(run));
  return 0;
}
