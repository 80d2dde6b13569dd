// What every libFuzzer target shares: one workspace per process (fuzz_pipeline.h: make_workspace,
// made once so that a run does no per-input directory work, in $TMPDIR/rdtf-fuzz-<target>-<pid>)
// and a hard stop when the bad-input contract breaks.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "fuzz_pipeline.h"

namespace rdtf::fuzz {

// A broken contract is a finding: print it and abort, which libFuzzer reports as a crash.
inline void require(const std::string& violation) {
  if (violation.empty()) return;
  std::fprintf(stderr, "rdtf fuzz: %s\n", violation.c_str());
  std::abort();
}

// The body of every LLVMFuzzerTestOneInput: run_target on the input, in the process's workspace.
inline int fuzz_one(const char* target, const std::uint8_t* data, std::size_t size) {
  static const Workspace workspace = make_workspace(
      std::filesystem::temp_directory_path() /
          ("rdtf-fuzz-" + std::string(target) + "-" + std::to_string(getpid())),
      RDTF_FUZZ_DATA_DIR);
  const TargetRun result = run_target(target, std::vector<std::uint8_t>(data, data + size), workspace);
  if (result.not_for_target) return -1;
  require(result.violation);
  return 0;
}

}  // namespace rdtf::fuzz
