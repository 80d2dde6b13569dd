#include "support/test_support.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

namespace rdtf::testing {

std::filesystem::path data_dir() { return RDTF_TEST_DATA_DIR; }

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  std::random_device random;
  path_ = std::filesystem::temp_directory_path() /
          ("rdtf-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" +
           std::to_string(random()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

void write_file(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

CommandResult run_command(const std::string& command) {
  TempDir scratch;
  const auto out_path = scratch / "stdout";
  const auto err_path = scratch / "stderr";
  const std::string full =
      "(" + command + ") >'" + out_path.string() + "' 2>'" + err_path.string() + "' </dev/null";
  const int status = std::system(full.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = read_file(out_path);
  result.err = read_file(err_path);
  return result;
}

nlohmann::json khronos_report(const std::filesystem::path& model) {
  const CommandResult run =
      run_command("node '" + std::string(RDTF_VALIDATOR_SCRIPT) + "' '" + model.string() + "'");
  if (run.exit_code != 0 && run.exit_code != 3) {
    throw std::runtime_error("gltf-validator did not run on " + model.string() + ": " + run.err);
  }
  return nlohmann::json::parse(run.out);
}

std::string cli_path() { return RDTF_CLI_PATH; }

std::string base64(const std::vector<std::uint8_t>& bytes) {
  static const char* const kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t n = (std::uint32_t{bytes[i]} << 16) |
                            (i + 1 < bytes.size() ? std::uint32_t{bytes[i + 1]} << 8 : 0) |
                            (i + 2 < bytes.size() ? std::uint32_t{bytes[i + 2]} : 0);
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[n & 63] : '=';
  }
  return out;
}

DescriptorHeadroom::DescriptorHeadroom(int headroom) {
  int highest = 0;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd")) {
    highest = std::max(highest, std::stoi(entry.path().filename().string()));
  }
  for (;;) {
    const int fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (fd < 0) break;
    fillers_.push_back(fd);
    if (fd >= highest) break;
  }
  rlimit limit{};
  if (fillers_.empty() || ::getrlimit(RLIMIT_NOFILE, &limit) != 0) return;
  limit_before_ = limit.rlim_cur;
  limit.rlim_cur = static_cast<rlim_t>(fillers_.back()) + 1 + static_cast<rlim_t>(headroom);
  ok_ = ::setrlimit(RLIMIT_NOFILE, &limit) == 0;
}

DescriptorHeadroom::~DescriptorHeadroom() {
  if (ok_) {
    rlimit limit{};
    ::getrlimit(RLIMIT_NOFILE, &limit);
    limit.rlim_cur = static_cast<rlim_t>(limit_before_);
    ::setrlimit(RLIMIT_NOFILE, &limit);
  }
  for (const int fd : fillers_) ::close(fd);
}

}  // namespace rdtf::testing
