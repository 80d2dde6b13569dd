// Helpers of the filesystem tests (filesystem_itest.cc, config_reload_itest.cc, faults_itest.cc): a small disk in
// the test's own mount namespace, file pages, process memory, a model's referenced files.
#pragma once

#include <sys/mount.h>

#include "daemon/harness.h"

namespace rdtf::itest {

// A tmpfs of `bytes` over `folder` for the test's life (its mount namespace is private:
// tests/support/in_netns.sh makes one).
class Tmpfs {
 public:
  Tmpfs(const fs::path& folder, std::size_t bytes) : folder_(folder) {
    const std::string options = "size=" + std::to_string(bytes);
    mounted_ = ::mount("tmpfs", folder.c_str(), "tmpfs", 0, options.c_str()) == 0;
  }
  ~Tmpfs() {
    if (mounted_) ::umount2(folder_.c_str(), MNT_DETACH);
  }
  Tmpfs(const Tmpfs&) = delete;
  Tmpfs& operator=(const Tmpfs&) = delete;
  bool mounted() const { return mounted_; }

  // Writes `file` until the disk is full; returns the bytes written.
  std::size_t fill(const fs::path& file) const {
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

  // Fills the disk with `file`, then gives back `free_pages` pages of 4 KiB: exactly that much
  // room is left for whatever is written next.
  void fill_leaving(const fs::path& file, std::size_t free_pages) const {
    const std::size_t total = fill(file);
    const std::size_t keep = total > free_pages * 4096 ? total - free_pages * 4096 : 0;
    if (::truncate(file.c_str(), static_cast<off_t>(keep)) != 0) throw std::runtime_error("truncate " + file.string());
  }

 private:
  fs::path folder_;
  bool mounted_ = false;
};

// Pages of 4 KiB a file of `bytes` takes on tmpfs.
inline std::size_t pages(std::uintmax_t bytes) { return static_cast<std::size_t>((bytes + 4095) / 4096); }

// A field of /proc/<pid>/status in kB (VmHWM: the peak resident set), or -1.
inline long status_kb(pid_t pid, const std::string& field) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(field + ":", 0) == 0) return std::stol(line.substr(field.size() + 1));
  }
  return -1;
}

// The file names a published glTF document refers to (buffers and images).
inline std::vector<std::string> uris_of(const std::string& json) {
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

// The mesh files a URDF names (filename="..."), as written: "meshes/<link>.<digest>.stl".
inline std::vector<std::string> meshes_of(const std::string& urdf) {
  std::vector<std::string> files;
  static const std::regex kFilename(R"re(filename="([^"]+)")re");
  for (std::sregex_iterator it(urdf.begin(), urdf.end(), kFilename), end; it != end; ++it) {
    files.push_back((*it)[1].str());
  }
  return files;
}

inline int run_shell(const std::string& command) { return std::system(command.c_str()); }

}  // namespace rdtf::itest
