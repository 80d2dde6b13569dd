// Reading the files a model names, once per load: the daemon hashes these bytes and the loader
// converts the same bytes (tinygltf is served them from memory).
#include "confined_files.h"
#include "rdtf/gltf.h"
#include "rdtf/shortage.h"

namespace rdtf {

void read_confined(const std::filesystem::path& folder, const std::filesystem::path& path, std::uint64_t max_bytes,
                   SourceFile& file) {
  int error = 0;
  file.size = internal::read_confined_file_within(folder, path, max_bytes, file.bytes, file.why, &error);
  file.unavailable = !file.size && is_shortage(error);
}

SourceFiles read_source_files(const std::vector<std::filesystem::path>& files,
                              const std::filesystem::path& folder, const LoadLimits& limits,
                              const ConfinedReader& reader) {
  SourceFiles read;
  for (const auto& path : files) {
    if (read.count(path) > 0) continue;  // Named again: the bytes already read.
    SourceFile& file = read[path];
    (reader ? reader : read_confined)(folder, path, limits.max_file_bytes, file);
    if (!file.size) file.bytes.clear();
  }
  return read;
}

}  // namespace rdtf
