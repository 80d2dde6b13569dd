// Issue 4, rdtfd's live simulation over real LCM (UDP multicast inside the program's own network
// namespace, see daemon_harness.h):
// - BM_JointStateStream: 20 copies of the arm3 fixture, simulate on, state_rate_hz 1000. Once every
//   model streams, a subscriber counts JOINT_STATE messages per model over a fixed window against
//   the 1000 per second asked for, and the kernel's UDP drop counters of the namespace tell states
//   lost in transport from states the daemon never sent.
// - BM_CommandToState: one arm3, a TORQUE command on the elbow (a new value each time, small and
//   of alternating sign so the arm stays near rest); the time from publishing the JOINT_COMMAND to
//   the first JOINT_STATE whose elbow effort equals the commanded value. p50 / p99.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include <rdtf/joint_command_t.hpp>
#include <rdtf/joint_state_t.hpp>

#include "daemon_harness.h"

namespace {

using namespace rdtf::bench;
using namespace std::chrono_literals;

// CPU time (user + system) rdtfd has used so far, s: fields 14 and 15 of /proc/<pid>/stat.
double process_cpu_seconds(pid_t pid) {
  std::ifstream file("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  std::istringstream fields(text.substr(text.rfind(')') + 2));  // after "pid (comm) "
  std::string field;
  double ticks = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i >= 14) ticks += std::stod(field);
  }
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

void copy_arm3(const fs::path& folder) {
  const fs::path source = fs::path(RDTF_BENCH_DATA_DIR) / "blender";
  fs::create_directories(folder);
  fs::copy_file(source / "arm3.bin", folder / "arm3.bin");
  fs::copy_file(source / "arm3.gltf", folder / "arm3.gltf");
}

Json live_config(double state_rate_hz) { return {{"simulate", true}, {"state_rate_hz", state_rate_hz}}; }

// ------------------------------------------------------------------------------------------------

struct StreamCounts {
  bool counting = false;
  std::map<std::string, long> first_seen;  // Models streaming (value unused).
  std::map<std::string, long> received;    // In the window.
  std::map<std::string, double> first_sim_time, last_sim_time;  // In the window.
  std::vector<double> sim_time_steps_ms;  // Simulated time between consecutive states of a model.
};

void BM_JointStateStream(benchmark::State& state) {
  const int models = static_cast<int>(state.range(0));
  const double rate_hz = 1000;
  const auto window = 5s;
  TempFolder root;
  const fs::path watch = root / "models", output = root / "out";
  for (int i = 0; i < models; ++i) copy_arm3(watch / ("m" + std::to_string(100 + i)));

  StreamCounts counts;
  Subscriber subscriber("RDTF", [&](const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point) {
    if (kind_of(channel) != "JOINT_STATE") return;
    const std::string id = model_id_of(channel);
    counts.first_seen.emplace(id, 0);
    if (!counts.counting) return;
    rdtf::joint_state_t message;
    if (message.decode(buffer.data, 0, static_cast<int>(buffer.data_size)) < 0) return;
    if (++counts.received[id] == 1) {
      counts.first_sim_time[id] = message.sim_time;
    } else {
      counts.sim_time_steps_ms.push_back(1e3 * (message.sim_time - counts.last_sim_time[id]));
    }
    counts.last_sim_time[id] = message.sim_time;
  });
  Daemon daemon(watch, output, live_config(rate_hz));
  if (!subscriber.wait([&] { return static_cast<int>(counts.first_seen.size()) == models; }, 60s)) {
    state.SkipWithError(("not every model streams; rdtfd log:\n" + daemon.log()).c_str());
    return;
  }
  for (auto _ : state) {
    const UdpCounters before = udp_counters();
    const double cpu_before = process_cpu_seconds(daemon.pid());
    subscriber.locked([&] { counts.counting = true; });
    const Clock::time_point start = Clock::now();
    std::this_thread::sleep_for(window);  // The measurement window itself, not a synchronisation.
    subscriber.locked([&] { counts.counting = false; });
    const double seconds = ms_between(start, Clock::now()) / 1e3;
    const UdpCounters after = udp_counters();
    // rdtfd's share of a core while it steps and publishes (the other threads are idle then).
    state.counters["rdtfd_cpu_per_wall_s"] = (process_cpu_seconds(daemon.pid()) - cpu_before) / seconds;
    state.SetIterationTime(seconds);

    const double expected = rate_hz * seconds;
    std::vector<double> ratios, sim_speed;
    long total = 0;
    std::vector<double> sim_steps;
    subscriber.locked([&] {
      sim_steps = counts.sim_time_steps_ms;
      for (const auto& [id, n] : counts.received) {
        ratios.push_back(static_cast<double>(n) / expected);
        sim_speed.push_back((counts.last_sim_time[id] - counts.first_sim_time[id]) / seconds);
        total += n;
      }
    });
    state.counters["models"] = models;
    state.counters["models_counted"] = static_cast<double>(ratios.size());
    state.counters["expected_per_model"] = expected;
    state.counters["received_per_s_per_model"] = static_cast<double>(total) / models / seconds;
    state.counters["min_received_ratio"] = ratios.empty() ? 0 : quantile(ratios, 0.0);
    state.counters["mean_received_ratio"] = mean(ratios);
    state.counters["max_received_ratio"] = ratios.empty() ? 0 : quantile(ratios, 1.0);
    state.counters["sim_s_per_wall_s"] = mean(sim_speed);
    // 1 ms apart when every step's state is sent; 2 ms: every other one.
    state.counters["p50_sim_ms_between_states"] = quantile(sim_steps, 0.5);
    state.counters["p99_sim_ms_between_states"] = quantile(sim_steps, 0.99);
    state.counters["udp_rcvbuf_drops"] = static_cast<double>(after.receive_buffer_errors - before.receive_buffer_errors);
    state.counters["udp_in_errors"] = static_cast<double>(after.in_errors - before.in_errors);
    state.counters["udp_datagrams_in"] = static_cast<double>(after.in_datagrams - before.in_datagrams);
  }
  const Memory memory = process_memory(daemon.pid());
  state.counters["rdtfd_VmRSS_MiB"] = static_cast<double>(memory.rss_kib) / 1024.0;
  daemon.stop();
}
BENCHMARK(BM_JointStateStream)->Arg(20)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

// ------------------------------------------------------------------------------------------------

struct LiveModel {
  std::string id;
  std::int64_t revision = 0;
  std::string content_hash;
  int elbow = -1;  // Index of the elbow in the state's joints.
  std::vector<std::pair<double, Clock::time_point>> elbow_efforts;  // Every state since the last command.
};

void BM_CommandToState(benchmark::State& state) {
  const double rate_hz = static_cast<double>(state.range(0));
  TempFolder root;
  const fs::path watch = root / "models", output = root / "out";
  copy_arm3(watch);

  LiveModel live;
  Subscriber subscriber("RDTF", [&](const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point at) {
    if (kind_of(channel) != "JOINT_STATE") return;
    rdtf::joint_state_t message;
    if (message.decode(buffer.data, 0, static_cast<int>(buffer.data_size)) < 0) return;
    if (live.elbow < 0) {
      for (int j = 0; j < message.num_joints; ++j) {
        if (message.name[j] == "elbow") live.elbow = j;
      }
      live.id = message.model_id;
      live.revision = message.revision;
      live.content_hash = message.content_hash;
    }
    if (live.elbow >= 0) live.elbow_efforts.emplace_back(message.effort[live.elbow], at);
  });
  Daemon daemon(watch, output, live_config(rate_hz));
  if (!subscriber.wait([&] { return live.elbow >= 0; }, 30s)) {
    state.SkipWithError(("no joint state with an elbow; rdtfd log:\n" + daemon.log()).c_str());
    return;
  }
  rdtf::joint_command_t command;
  command.model_id = live.id;
  command.revision = live.revision;
  command.content_hash = live.content_hash;
  command.num_joints = 1;
  command.name = {"elbow"};
  command.mode = {rdtf::joint_command_t::TORQUE};
  command.kp = {0.0};
  command.kd = {0.0};

  std::vector<double> latencies;
  int k = 0;
  for (auto _ : state) {
    ++k;
    const double torque = (k % 2 == 0 ? 1.0 : -1.0) * (0.01 + 1e-6 * k);  // N m, unique per command
    command.value = {torque};
    subscriber.locked([&] { live.elbow_efforts.clear(); });
    const Clock::time_point sent = Clock::now();
    command.utime = std::chrono::duration_cast<std::chrono::microseconds>(sent.time_since_epoch()).count();
    subscriber.publish("RDTF/" + live.id + "/JOINT_COMMAND", command);
    Clock::time_point seen;
    const bool reflected = subscriber.wait(
        [&] {
          for (const auto& [effort, at] : live.elbow_efforts) {
            if (effort == torque) {
              seen = at;
              return true;
            }
          }
          return false;
        },
        2s);
    if (!reflected) {
      state.SkipWithError(("command " + std::to_string(k) + " never reflected; rdtfd log:\n" + daemon.log()).c_str());
      break;
    }
    latencies.push_back(ms_between(sent, seen));
    state.SetIterationTime(latencies.back() / 1e3);
  }
  state.SetLabel("arm3, state_rate_hz " + std::to_string(static_cast<int>(rate_hz)));
  state.counters["p50_ms"] = quantile(latencies, 0.5);
  state.counters["p99_ms"] = quantile(latencies, 0.99);
  state.counters["max_ms"] = quantile(latencies, 1.0);
  state.counters["state_period_ms"] = 1000.0 / rate_hz;
  state.counters["samples"] = static_cast<double>(latencies.size());
  daemon.stop();
}
BENCHMARK(BM_CommandToState)->Arg(1000)->Arg(100)->Iterations(300)->UseManualTime()->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  run_in_own_network_namespace(argc, argv);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
