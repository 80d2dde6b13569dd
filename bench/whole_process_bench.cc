// `rdtf convert` and `rdtf inspect` as users meet them: whole processes, each started fresh,
// timed against a tinygltf peer doing the least comparable work (tinygltf_peer.cc: load + write
// GLB, and load), on a closed UV sphere GLB generated here (default 1.3M triangles, 24 MB).
//
//   whole_process_bench [--runs N] [--triangles N] RDTF TINYGLTF_PEER
//
// Each round runs the four programs once, the two of each pair back to back, in alternating
// order (A B, then B A in the next round) so that drift of the shared machine's load hits both
// sides alike; one warm-up round (the model and the programs into the page cache) is not counted.
// Per program: the median over the rounds of wall time, CPU time (user + system, from wait4) and
// minor page faults, and the largest resident set. Ratios: of the medians, and the median of the
// per-round ratios (each taken between two runs next to each other in time).
#include <sys/resource.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <spawn.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "side_by_side.h"
#include "synthetic_models.h"

extern char** environ;

namespace {

struct Sample {
  double wall_ms = 0;
  double cpu_ms = 0;
  double minor_faults = 0;
  double max_rss_mib = 0;
};

double ms(const timeval& t) { return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_usec) * 1e-3; }

// Runs argv as a fresh process (stdout and stderr to /dev/null) and measures it; throws when it
// does not exit 0.
Sample run(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const auto& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  const auto start = std::chrono::steady_clock::now();
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw std::runtime_error("cannot start " + args[0]);
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid) throw std::runtime_error("wait4 failed for " + args[0]);
  const auto end = std::chrono::steady_clock::now();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string command;
    for (const auto& arg : args) command += arg + " ";
    throw std::runtime_error("failed (status " + std::to_string(status) + "): " + command);
  }
  Sample sample;
  sample.wall_ms = std::chrono::duration<double, std::milli>(end - start).count();
  sample.cpu_ms = ms(usage.ru_utime) + ms(usage.ru_stime);
  sample.minor_faults = static_cast<double>(usage.ru_minflt);
  sample.max_rss_mib = static_cast<double>(usage.ru_maxrss) / 1024.0;
  return sample;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

struct Side {
  std::string name;
  std::vector<std::string> command;
  std::vector<Sample> samples;
  double median_of(double Sample::*field) const {
    std::vector<double> values;
    for (const auto& s : samples) values.push_back(s.*field);
    return median(values);
  }
};

struct Pair {
  std::string name;
  double goal;  // largest ratio (rdtf / peer, wall medians) the goal allows
  Side rdtf, peer;
};

double per_round_ratio(const Pair& pair, double Sample::*field) {
  std::vector<double> ratios;
  for (std::size_t i = 0; i < pair.rdtf.samples.size(); ++i) {
    ratios.push_back(pair.rdtf.samples[i].*field / pair.peer.samples[i].*field);
  }
  return median(ratios);
}

void print_side(const Side& side) {
  double rss = 0;
  for (const auto& s : side.samples) rss = std::max(rss, s.max_rss_mib);
  std::printf("| %s | %.1f | %.1f | %.0f | %.0f |\n", side.name.c_str(), side.median_of(&Sample::wall_ms),
              side.median_of(&Sample::cpu_ms), side.median_of(&Sample::minor_faults), rss);
}

}  // namespace

int main(int argc, char** argv) {
  int rounds = 11;
  std::size_t triangles = 1'300'000;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--runs" && i + 1 < argc) {
      rounds = std::atoi(argv[++i]);
    } else if (arg == "--triangles" && i + 1 < argc) {
      triangles = static_cast<std::size_t>(std::atoll(argv[++i]));
    } else {
      positional.push_back(arg);
    }
  }
  if (positional.size() != 2 || rounds < 1) {
    std::fprintf(stderr, "usage: whole_process_bench [--runs N] [--triangles N] RDTF TINYGLTF_PEER\n");
    return 2;
  }
  const std::string rdtf = std::filesystem::absolute(positional[0]);
  const std::string peer = std::filesystem::absolute(positional[1]);

  const auto folder = std::filesystem::temp_directory_path() / "rdtf-whole-process-bench";
  std::filesystem::create_directories(folder);
  const std::string model = (folder / "sphere.glb").string();
  // The model is made in a child process: a spawned program's ru_maxrss starts from the peak
  // resident set of the process that spawned it (posix_spawn shares its memory until exec), so
  // this process never holds the model.
  const pid_t maker = fork();
  if (maker == 0) {
    const auto mesh = rdtf::bench::uv_sphere(triangles, 0.5);
    const auto glb = rdtf::bench::mesh_glb(mesh);
    std::ofstream(model, std::ios::binary).write(reinterpret_cast<const char*>(glb.data()),
                                                static_cast<std::streamsize>(glb.size()));
    std::printf("model: %s, %zu triangles, %.1f MB\n", model.c_str(), mesh.triangles.size(),
                static_cast<double>(glb.size()) / 1e6);
    std::fflush(stdout);
    _exit(0);
  }
  int maker_status = 0;
  if (maker < 0 || waitpid(maker, &maker_status, 0) != maker || maker_status != 0) {
    std::fprintf(stderr, "whole_process_bench: could not make the model\n");
    return 1;
  }
  std::printf("load average before: %s\n", rdtf::bench::load_average().c_str());

  std::vector<Pair> pairs = {
      {"convert (write GLB)", 1.2,
       {"rdtf convert --glb", {rdtf, "convert", model, "-o", (folder / "rdtf_out.glb").string()}, {}},
       {"tinygltf load + write GLB", {peer, "write", model, (folder / "peer_out.glb").string()}, {}}},
      {"inspect", 1.3,
       {"rdtf inspect", {rdtf, "inspect", model}, {}},
       {"tinygltf load", {peer, "load", model}, {}}},
  };
  try {
    for (int round = -1; round < rounds; ++round) {  // round -1: warm-up, not counted
      for (auto& pair : pairs) {
        const bool rdtf_first = round % 2 == 0;
        Side& first = rdtf_first ? pair.rdtf : pair.peer;
        Side& second = rdtf_first ? pair.peer : pair.rdtf;
        const Sample a = run(first.command);
        const Sample b = run(second.command);
        if (round >= 0) {
          first.samples.push_back(a);
          second.samples.push_back(b);
        }
      }
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "whole_process_bench: %s\n", error.what());
    return 1;
  }
  std::printf("load average after: %s\n\n", rdtf::bench::load_average().c_str());

  std::printf("Medians of %d alternating rounds (after one warm-up round):\n\n", rounds);
  std::printf("| program | wall ms | CPU ms (user+sys) | minor faults | max RSS MiB |\n| --- | --- | --- | --- | --- |\n");
  for (const auto& pair : pairs) {
    print_side(pair.rdtf);
    print_side(pair.peer);
  }
  std::printf("\n| rdtf / tinygltf | wall, of medians | wall, median per round | CPU, of medians | goal (wall) |\n"
              "| --- | --- | --- | --- | --- |\n");
  for (const auto& pair : pairs) {
    const double wall = pair.rdtf.median_of(&Sample::wall_ms) / pair.peer.median_of(&Sample::wall_ms);
    const double cpu = pair.rdtf.median_of(&Sample::cpu_ms) / pair.peer.median_of(&Sample::cpu_ms);
    std::printf("| %s | %.2fx | %.2fx | %.2fx | <= %.1fx: %s |\n", pair.name.c_str(), wall,
                per_round_ratio(pair, &Sample::wall_ms), cpu, pair.goal, wall <= pair.goal ? "met" : "not met");
  }
  return 0;
}
