// What the daemon benchmarks share, built on the tests' harness library (rdtf_itest_harness,
// tests/support/harness/): rdtfd runs as a child with a config file the benchmark writes, a
// subscriber on real LCM (UDP multicast) is up before the daemon starts, and every wait is on a
// message, never a sleep.
//
// Network: these programs multicast, so they only run inside a network namespace of their own.
// main() calls run_in_own_network_namespace() first: it re-executes the program under
// tests/support/in_netns.sh (unshare -n -m: loopback only, multicast on, route for 224.0.0.0/4)
// and refuses to go on if any interface other than lo is visible.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "support/harness/lcm_listener.h"
#include "support/harness/process.h"

namespace rdtf::bench {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;

// Re-executes the program inside its own network namespace (once); exits on failure.
void run_in_own_network_namespace(int argc, char** argv);

// A fresh folder under the system temp dir, removed with everything in it by the destructor.
using TempFolder = rdtf::testing::TempDir;

// Writes in place (open with O_TRUNC, write, close), as Blender saves. Returns the time right
// after close(): the moment of the last write.
Clock::time_point write_in_place(const fs::path& path, const std::string& bytes);
using rdtf::testing::read_file;

// A one-link model: a box of half-size 0.05 m, its buffer embedded (about 1 KB), its node named
// `name` so that each name gives other content.
std::string small_box_gltf(const std::string& name);

// rdtfd as a child (the tests' DaemonProcess): `config` over {"status_period_ms": 200,
// "republish_period_ms": 0}, the watched and output folders on the command line, rdtfd's own
// settle time, its log in a file. Killed by the destructor.
class Daemon {
 public:
  Daemon(const fs::path& watch, const fs::path& output, const Json& config);
  pid_t pid() const { return process_.pid(); }
  std::string log() const { return process_.log(); }
  bool stop() { return process_.stop(std::chrono::seconds(5)).has_value(); }  // SIGTERM; true when it exited within 5 s.

 private:
  itest::DaemonProcess process_;
};

// VmRSS and VmHWM of a process, in KiB, from /proc/<pid>/status.
struct Memory {
  long rss_kib = -1;
  long hwm_kib = -1;
};
Memory process_memory(pid_t pid);

// UDP counters of this network namespace (/proc/net/snmp): datagrams delivered to sockets, and
// datagrams dropped because a socket's receive buffer was full.
struct UdpCounters {
  long long in_datagrams = 0;
  long long receive_buffer_errors = 0;
  long long in_errors = 0;
};
UdpCounters udp_counters();

// An LCM subscriber on every channel under `prefix`, on its own thread, with a 4 MiB kernel receive
// buffer and a deep queue. Each message goes to the handler (under the lock, with its arrival
// time); wait() blocks until a predicate over the caller's state holds.
class Subscriber : public itest::LcmListener {
 public:
  Subscriber(const std::string& prefix, Handler handler);
};

// "<prefix>/<model_id>/<KIND>" -> KIND and model_id.
using itest::kind_of;
using itest::model_id_of;

// Quantile q (0..1) of `samples` (nearest rank), and the mean.
double quantile(std::vector<double> samples, double q);
double mean(const std::vector<double>& samples);

double ms_between(Clock::time_point from, Clock::time_point to);

}  // namespace rdtf::bench
