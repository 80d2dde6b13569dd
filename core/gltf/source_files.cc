// Reading the files a model names, once per load: the daemon hashes these bytes and the loader
// converts the same bytes (tinygltf is served them from memory).
#include "confined_files.h"
#include "rdtf/gltf.h"

namespace rdtf {

SourceFiles read_source_files(const std::vector<std::filesystem::path>& files,
                              const std::filesystem::path& folder, const LoadLimits& limits,
                              const ConfinedReader& reader) {
  SourceFiles read;
  for (const auto& path : files) {
    if (read.count(path) > 0) continue;  // Named again: the bytes already read.
    SourceFile& file = read[path];
    file.size = reader ? reader(folder, path, limits.max_file_bytes, file.bytes, file.why)
                       : internal::read_confined_file_within(folder, path, limits.max_file_bytes,
                                                             file.bytes, file.why);
    if (!file.size) file.bytes.clear();
  }
  return read;
}

}  // namespace rdtf
