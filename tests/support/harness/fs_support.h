// Helpers of the filesystem tests (filesystem_itest.cc, config_reload_itest.cc, faults_itest.cc): a
// small disk in the test's own mount namespace, file pages, a model's referenced files.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "support/harness/basics.h"

namespace rdtf::itest {

// A tmpfs of `bytes` over `folder` for the test's life (its mount namespace is private:
// tests/support/in_netns.sh makes one).
class Tmpfs {
 public:
  Tmpfs(const fs::path& folder, std::size_t bytes);
  ~Tmpfs();
  Tmpfs(const Tmpfs&) = delete;
  Tmpfs& operator=(const Tmpfs&) = delete;
  bool mounted() const { return mounted_; }

  // Writes `file` until the disk is full; returns the bytes written.
  std::size_t fill(const fs::path& file) const;

  // Fills the disk with `file`, then gives back `free_pages` pages of 4 KiB: exactly that much
  // room is left for whatever is written next.
  void fill_leaving(const fs::path& file, std::size_t free_pages) const;

 private:
  fs::path folder_;
  bool mounted_ = false;
};

// Pages of 4 KiB a file of `bytes` takes on tmpfs.
inline std::size_t pages(std::uintmax_t bytes) { return static_cast<std::size_t>((bytes + 4095) / 4096); }

// The file names a published glTF document refers to (buffers and images).
std::vector<std::string> uris_of(const std::string& json);

// The mesh files a URDF names (filename="..."), as written: "meshes/<link>.<digest>.stl".
std::vector<std::string> meshes_of(const std::string& urdf);

inline int run_shell(const std::string& command) { return std::system(command.c_str()); }

}  // namespace rdtf::itest
