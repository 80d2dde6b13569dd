#include "support/harness/files.h"

#include <unistd.h>

#include <stdexcept>

#include "support/harness/hashes.h"

namespace rdtf::itest {

void write_in_place(const fs::path& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("open " + path.string());
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) {
      ::close(fd);
      throw std::runtime_error("write " + path.string());
    }
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
}

void write_by_rename(const fs::path& path, const std::string& bytes, const std::string& temp_name) {
  const fs::path temp = path.parent_path() / temp_name;
  write_in_place(temp, bytes);
  fs::rename(temp, path);
}

OpenFile::OpenFile(const fs::path& path, int flags) : fd_(::open(path.c_str(), flags | O_CLOEXEC, 0644)) {
  if (fd_ < 0) throw std::runtime_error("open " + path.string());
}

void OpenFile::write(const std::string& bytes) {
  if (::write(fd_, bytes.data(), bytes.size()) != static_cast<ssize_t>(bytes.size())) {
    throw std::runtime_error("short write");
  }
}

void OpenFile::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

std::map<std::string, std::string> snapshot(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (auto it = fs::recursive_directory_iterator(folder); it != fs::recursive_directory_iterator(); ++it) {
    if (it->is_directory() && it->path().filename() == ".rdtfd-state") {
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file()) files[fs::relative(it->path(), folder).string()] = read(it->path());
  }
  return files;
}

fs::path copy_fixture(const fs::path& folder, const std::string& stem, const std::string& as) {
  const fs::path source = testing::data_dir() / "blender";
  const std::string name = as.empty() ? stem : as;
  // The .bin keeps its name: the .gltf refers to it.
  fs::copy_file(source / (stem + ".bin"), folder / (stem + ".bin"), fs::copy_options::overwrite_existing);
  fs::copy_file(source / (stem + ".gltf"), folder / (name + ".gltf"), fs::copy_options::overwrite_existing);
  fs::permissions(folder / (name + ".gltf"), fs::perms::owner_write, fs::perm_options::add);
  fs::permissions(folder / (stem + ".bin"), fs::perms::owner_write, fs::perm_options::add);
  return folder / (name + ".gltf");
}

std::string fixture_hash(const std::string& stem) {
  const fs::path source = testing::data_dir() / "blender";
  return content_hash(read(source / (stem + ".gltf")), {read(source / (stem + ".bin"))});
}

Json inspect(const fs::path& model, const std::string& options) {
  const auto run = testing::run_command("'" + testing::cli_path() + "' inspect --json " + options + " '" +
                                        model.string() + "'");
  if (run.exit_code != 0) throw std::runtime_error("rdtf inspect failed on " + model.string() + ": " + run.err);
  return Json::parse(run.out);
}

}  // namespace rdtf::itest
