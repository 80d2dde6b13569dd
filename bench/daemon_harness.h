// What the daemon benchmarks (issues 3 and 4) share, after the ideas of tests/daemon/harness.h:
// rdtfd runs as a child with a config file the benchmark writes, a subscriber on real LCM (UDP
// multicast) is up before the daemon starts, and every wait is on a message, never a sleep.
//
// Network: these programs multicast, so they only run inside a network namespace of their own.
// main() calls run_in_own_network_namespace() first: it re-executes the program under
// tests/support/in_netns.sh (unshare -n -m: loopback only, multicast on, route for 224.0.0.0/4)
// and refuses to go on if any interface other than lo is visible.
#pragma once

#include <sys/types.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

namespace rdtf::bench {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;

// Re-executes the program inside its own network namespace (once); exits on failure.
void run_in_own_network_namespace(int argc, char** argv);

// A fresh folder under the system temp dir, removed with everything in it by the destructor.
class TempFolder {
 public:
  TempFolder();
  ~TempFolder();
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

// Writes in place (open with O_TRUNC, write, close), as Blender saves. Returns the time right
// after close(): the moment of the last write.
Clock::time_point write_in_place(const fs::path& path, const std::string& bytes);
std::string read_file(const fs::path& path);

// A one-link model: a box of half-size 0.05 m, its buffer embedded (about 1 KB), its node named
// `name` so that each name gives other content.
std::string small_box_gltf(const std::string& name);

// rdtfd as a child: `config` over {"status_period_ms": 200, "republish_period_ms": 0}, the watched
// and output folders on the command line, its log in a file. Killed by the destructor.
class Daemon {
 public:
  Daemon(const fs::path& watch, const fs::path& output, const Json& config);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;
  pid_t pid() const { return pid_; }
  std::string log() const;
  bool stop();  // SIGTERM; true when it exited within 5 s.

 private:
  TempFolder files_;
  pid_t pid_ = -1;
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
// buffer and a deep queue. Each message goes to `handler` (under the lock, with its arrival time);
// wait() blocks until a predicate over the caller's state holds.
class Subscriber {
 public:
  using Handler = std::function<void(const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point received)>;
  Subscriber(const std::string& prefix, Handler handler);
  ~Subscriber();
  Subscriber(const Subscriber&) = delete;
  Subscriber& operator=(const Subscriber&) = delete;

  // Waits until `done()` (evaluated under the lock after each message) holds; false at the deadline.
  bool wait(const std::function<bool()>& done, Clock::duration timeout);
  // Runs `f` under the lock (to read what the handler recorded).
  void locked(const std::function<void()>& f);
  template <typename T>
  void publish(const std::string& channel, const T& message) {
    lcm_.publish(channel, &message);
  }

 private:
  void on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel);

  Handler handler_;
  lcm::LCM lcm_;
  bool stop_ = false;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::thread thread_;
};

// "<prefix>/<model_id>/<KIND>" -> KIND and model_id.
std::string kind_of(const std::string& channel);
std::string model_id_of(const std::string& channel);

// Quantile q (0..1) of `samples` (nearest rank), and the mean.
double quantile(std::vector<double> samples, double q);
double mean(const std::vector<double>& samples);

double ms_between(Clock::time_point from, Clock::time_point to);

}  // namespace rdtf::bench
