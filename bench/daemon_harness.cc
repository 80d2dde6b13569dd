#include "daemon_harness.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace rdtf::bench {
namespace {

constexpr const char* kNamespaceMarker = "RDTF_BENCH_IN_OWN_NETNS";
// LCM's default group and port (what rdtfd uses), with a receive buffer of net.core.rmem_max.
constexpr const char* kSubscriberUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

// The interfaces of this process's network namespace (/proc/self/net/dev; /sys/class/net shows
// the namespace that mounted sysfs, not ours).
std::vector<std::string> visible_interfaces() {
  std::ifstream in("/proc/self/net/dev");
  std::vector<std::string> names;
  std::string line;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const auto start = line.find_first_not_of(' ');
    names.push_back(line.substr(start, colon - start));
  }
  return names;
}

std::string base64(const std::string& bytes) {
  static const char* const kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) | static_cast<unsigned char>(bytes[i + 2]);
    for (int shift : {18, 12, 6, 0}) out += kTable[v >> shift & 63];
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kTable[v >> 18 & 63];
    out += kTable[v >> 12 & 63];
    out += i + 1 < bytes.size() ? kTable[v >> 6 & 63] : '=';
    out += '=';
  }
  return out;
}

}  // namespace

void run_in_own_network_namespace(int argc, char** argv) {
  if (std::getenv(kNamespaceMarker) == nullptr) {
    ::setenv(kNamespaceMarker, "1", 1);
    std::vector<std::string> args = {RDTF_IN_NETNS, fs::read_symlink("/proc/self/exe").string()};
    for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
    std::vector<char*> raw;
    for (auto& arg : args) raw.push_back(arg.data());
    raw.push_back(nullptr);
    ::execv(raw[0], raw.data());
    std::cerr << "cannot run " << RDTF_IN_NETNS << ": " << std::strerror(errno) << "\n";
    std::exit(2);
  }
  // Never multicast on a real network: only loopback may be visible.
  for (const auto& name : visible_interfaces()) {
    if (name != "lo") {
      std::cerr << "refusing to run: interface '" << name << "' is visible (not in an own network namespace)\n";
      std::exit(2);
    }
  }
}

TempFolder::TempFolder() {
  std::random_device random;
  path_ = fs::temp_directory_path() / ("rdtf-bench-" + std::to_string(::getpid()) + "-" + std::to_string(random()));
  fs::create_directories(path_);
}

TempFolder::~TempFolder() {
  std::error_code ignored;
  fs::remove_all(path_, ignored);
}

Clock::time_point write_in_place(const fs::path& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("open " + path.string());
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) throw std::runtime_error("write " + path.string());
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
  return Clock::now();
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string small_box_gltf(const std::string& name) {
  // 8 corners (bit 0: +x, bit 1: +y, bit 2: +z), 12 triangles wound outwards.
  const float h = 0.05f;
  std::string bin;
  for (int c = 0; c < 8; ++c) {
    for (float f : {c & 1 ? h : -h, c & 2 ? h : -h, c & 4 ? h : -h}) bin.append(reinterpret_cast<const char*>(&f), 4);
  }
  const int quads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (const auto& q : quads) {
    for (int v : {q[0], q[1], q[2], q[0], q[2], q[3]}) {
      const auto index = static_cast<std::uint16_t>(v);
      bin.append(reinterpret_cast<const char*>(&index), 2);
    }
  }
  const Json document = {
      {"asset", {{"version", "2.0"}, {"generator", "rdtf bench"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"name", name}, {"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"},
         {"min", {-h, -h, -h}}, {"max", {h, h, h}}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}, {"target", 34962}},
        {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 72}, {"target", 34963}}}},
      {"buffers", {{{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}}}};
  return document.dump(1);
}

Daemon::Daemon(const fs::path& watch, const fs::path& output, const Json& config) {
  Json full = {{"status_period_ms", 200}, {"republish_period_ms", 0}};
  full.update(config);
  const fs::path config_path = files_ / "rdtfd.json";
  std::ofstream(config_path) << full.dump(2);
  const fs::path log_path = files_ / "rdtfd.log";
  std::vector<std::string> args = {RDTFD_PATH, "--config", config_path.string(), "--watch", watch.string(),
                                   "--output", output.string()};
  std::vector<char*> argv;
  for (auto& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  const int error = posix_spawn(&pid_, RDTFD_PATH, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) throw std::runtime_error(std::string("cannot start rdtfd: ") + std::strerror(error));
}

Daemon::~Daemon() {
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    int status = 0;
    ::waitpid(pid_, &status, 0);
  }
}

std::string Daemon::log() const { return read_file(files_ / "rdtfd.log"); }

bool Daemon::stop() {
  if (pid_ <= 0) return true;
  ::kill(pid_, SIGTERM);
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  int status = 0;
  while (Clock::now() < deadline) {
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));  // Polling a child's exit.
  }
  return false;
}

Memory process_memory(pid_t pid) {
  Memory memory;
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) memory.rss_kib = std::stol(line.substr(6));
    if (line.rfind("VmHWM:", 0) == 0) memory.hwm_kib = std::stol(line.substr(6));
  }
  return memory;
}

UdpCounters udp_counters() {
  // Two "Udp:" lines: the field names, then the values.
  std::ifstream in("/proc/net/snmp");
  std::string line;
  std::vector<std::string> names, values;
  while (std::getline(in, line)) {
    if (line.rfind("Udp: ", 0) != 0) continue;
    std::istringstream fields(line.substr(5));
    std::vector<std::string>& into = names.empty() ? names : values;
    for (std::string field; fields >> field;) into.push_back(field);
  }
  UdpCounters counters;
  for (std::size_t i = 0; i < names.size() && i < values.size(); ++i) {
    if (names[i] == "InDatagrams") counters.in_datagrams = std::stoll(values[i]);
    if (names[i] == "RcvbufErrors") counters.receive_buffer_errors = std::stoll(values[i]);
    if (names[i] == "InErrors") counters.in_errors = std::stoll(values[i]);
  }
  return counters;
}

Subscriber::Subscriber(const std::string& prefix, Handler handler) : handler_(std::move(handler)), lcm_(kSubscriberUrl) {
  if (!lcm_.good()) throw std::runtime_error("cannot open LCM");
  auto* subscription = lcm_.subscribe(prefix + "/.*", &Subscriber::on_message, this);
  subscription->setQueueCapacity(1000000);
  thread_ = std::thread([this] {
    for (;;) {
      {
        std::lock_guard lock(mutex_);
        if (stop_) return;
      }
      lcm_.handleTimeout(20);
    }
  });
}

Subscriber::~Subscriber() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  thread_.join();
}

void Subscriber::on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  const auto received = Clock::now();
  {
    std::lock_guard lock(mutex_);
    handler_(channel, *buffer, received);
  }
  changed_.notify_all();
}

bool Subscriber::wait(const std::function<bool()>& done, Clock::duration timeout) {
  std::unique_lock lock(mutex_);
  return changed_.wait_for(lock, timeout, done);
}

void Subscriber::locked(const std::function<void()>& f) {
  std::lock_guard lock(mutex_);
  f();
}

std::string kind_of(const std::string& channel) { return channel.substr(channel.rfind('/') + 1); }

std::string model_id_of(const std::string& channel) {
  const auto first = channel.find('/');
  const auto last = channel.rfind('/');
  return first == last ? "" : channel.substr(first + 1, last - first - 1);
}

double quantile(std::vector<double> samples, double q) {
  if (samples.empty()) return NAN;
  std::sort(samples.begin(), samples.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(samples.size())));
  return samples[std::clamp<std::size_t>(rank, 1, samples.size()) - 1];
}

double mean(const std::vector<double>& samples) {
  if (samples.empty()) return NAN;
  return std::accumulate(samples.begin(), samples.end(), 0.0) / static_cast<double>(samples.size());
}

double ms_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

}  // namespace rdtf::bench
