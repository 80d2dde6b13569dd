#include "support/harness/fs_support.h"

#include <fcntl.h>
#include <sys/mount.h>
#include <unistd.h>

#include <regex>
#include <stdexcept>

namespace rdtf::itest {

Tmpfs::Tmpfs(const fs::path& folder, std::size_t bytes) : folder_(folder) {
  const std::string options = "size=" + std::to_string(bytes);
  mounted_ = ::mount("tmpfs", folder.c_str(), "tmpfs", 0, options.c_str()) == 0;
}

Tmpfs::~Tmpfs() {
  if (mounted_) ::umount2(folder_.c_str(), MNT_DETACH);
}

std::size_t Tmpfs::fill(const fs::path& file) const {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("open " + file.string());
  const std::string block(4096, 'x');
  std::size_t total = 0;
  for (;;) {
    const ssize_t n = ::write(fd, block.data(), block.size());
    if (n <= 0) break;
    total += static_cast<std::size_t>(n);
  }
  ::close(fd);
  return total;
}

void Tmpfs::fill_leaving(const fs::path& file, std::size_t free_pages) const {
  const std::size_t total = fill(file);
  const std::size_t keep = total > free_pages * 4096 ? total - free_pages * 4096 : 0;
  if (::truncate(file.c_str(), static_cast<off_t>(keep)) != 0) throw std::runtime_error("truncate " + file.string());
}

std::vector<std::string> uris_of(const std::string& json) {
  std::vector<std::string> uris;
  const Json document = Json::parse(json);
  for (const char* array : {"buffers", "images"}) {
    if (!document.contains(array)) continue;
    for (const auto& item : document[array]) {
      if (item.contains("uri") && item["uri"].get<std::string>().rfind("data:", 0) != 0) {
        uris.push_back(item["uri"].get<std::string>());
      }
    }
  }
  return uris;
}

std::vector<std::string> meshes_of(const std::string& urdf) {
  std::vector<std::string> files;
  static const std::regex kFilename(R"re(filename="([^"]+)")re");
  for (std::sregex_iterator it(urdf.begin(), urdf.end(), kFilename), end; it != end; ++it) {
    files.push_back((*it)[1].str());
  }
  return files;
}

}  // namespace rdtf::itest
