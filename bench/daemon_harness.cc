#include "daemon_harness.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <numeric>
#include <sstream>

#include "support/harness/files.h"
#include "support/harness/models.h"

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

Clock::time_point write_in_place(const fs::path& path, const std::string& bytes) {
  itest::write_in_place(path, bytes);
  return Clock::now();
}

std::string small_box_gltf(const std::string& name) { return itest::box_model(name, 0.05).gltf; }

namespace {

itest::DaemonOptions bench_options(const fs::path& watch, const fs::path& output, const Json& config) {
  itest::DaemonOptions options;
  options.watch = {watch};
  options.output = output;
  options.settle_ms = std::nullopt;     // rdtfd's own.
  options.republish_ms = std::nullopt;  // The config's: off.
  options.defaults = {{"status_period_ms", 200}, {"republish_period_ms", 0}};
  options.config = config;
  return options;
}

}  // namespace

Daemon::Daemon(const fs::path& watch, const fs::path& output, const Json& config)
    : process_(bench_options(watch, output, config)) {}

Memory process_memory(pid_t pid) {
  return {itest::status_kb(pid, "VmRSS"), itest::status_kb(pid, "VmHWM")};
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

Subscriber::Subscriber(const std::string& prefix, Handler handler)
    : LcmListener(prefix + "/.*", kSubscriberUrl, 1000000, std::move(handler)) {}

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
