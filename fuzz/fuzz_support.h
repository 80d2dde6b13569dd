// What every libFuzzer target shares: a fixed temp folder per process (made once, so that a run
// does no per-input directory work) and a hard stop when the bad-input contract breaks.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace rdtf::fuzz {

// A closed tetrahedron (outward winding), the mesh a URDF seed refers to.
inline constexpr const char* kTetraStl =
    "solid tetra\n"
    "facet normal 0 0 -1 outer loop vertex 0 0 0 vertex 0 1 0 vertex 1 0 0 endloop endfacet\n"
    "facet normal 0 -1 0 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 0 1 endloop endfacet\n"
    "facet normal -1 0 0 outer loop vertex 0 0 0 vertex 0 0 1 vertex 0 1 0 endloop endfacet\n"
    "facet normal 1 1 1 outer loop vertex 1 0 0 vertex 0 1 0 vertex 0 0 1 endloop endfacet\n"
    "endsolid tetra\n";

// $TMPDIR/rdtf-fuzz-<target>-<pid>, holding copies of the test models' external buffers so that
// seeds with a .bin beside them load, and tetra.stl for URDF meshes; every URI stays confined to
// it.
inline const std::filesystem::path& work_dir(const char* target) {
  static const std::filesystem::path dir = [target] {
    namespace fs = std::filesystem;
    const fs::path made = fs::temp_directory_path() /
                          ("rdtf-fuzz-" + std::string(target) + "-" + std::to_string(getpid()));
    fs::create_directories(made);
    for (const auto& entry : fs::directory_iterator(fs::path(RDTF_FUZZ_DATA_DIR) / "blender")) {
      if (entry.path().extension() == ".bin") {
        fs::copy_file(entry.path(), made / entry.path().filename(),
                      fs::copy_options::overwrite_existing);
      }
    }
    std::ofstream(made / "tetra.stl") << kTetraStl;
    return made;
  }();
  return dir;
}

// A broken contract is a finding: print it and abort, which libFuzzer reports as a crash.
inline void require(const std::string& violation) {
  if (violation.empty()) return;
  std::fprintf(stderr, "rdtf fuzz: %s\n", violation.c_str());
  std::abort();
}

}  // namespace rdtf::fuzz
