// `rdtf convert` and `rdtf inspect` as users meet them: whole processes, each started fresh,
// timed against a tinygltf peer doing the least comparable work (tinygltf_peer.cc: load + write
// GLB, and load), on a closed UV sphere GLB generated here (default 1.3M triangles, 24 MB).
//
//   whole_process_bench [--pairs N] [--triangles N] [--csv FILE] [--baseline OLD_RDTF] RDTF TINYGLTF_PEER
//
// With --baseline, two more comparisons time RDTF against OLD_RDTF (say, main's build) the same
// way, pair by pair: a change's before and after as users meet it.
//
// The machine is shared, so the method (docs/benchmarks.md, "Whole processes") leans on pairs:
// each round runs, per comparison, rdtf and its peer back to back, in alternating order (A B, then
// B A in the next round), and the ratio rdtf / peer is taken within each pair, two runs next to
// each other in time, so that slow drift of the machine's load cancels. The summary of a
// comparison is the median of its per-pair ratios with an order-statistics 95 % confidence
// interval (whole_process_bench_stats.h); the goal is met with that confidence when the whole
// interval lies at or below it. Beside wall time: CPU time (user and system apart, from wait4),
// minor page faults and involuntary context switches (preemption by other processes), which
// explain most outliers; runs slower than Q3 + 3 IQR of their program are listed, not dropped.
// One warm-up round (the model and the programs into the page cache) is not counted.
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
#include "whole_process_bench_stats.h"

extern char** environ;

namespace {

using rdtf::bench::median_of;

struct Sample {
  double wall_ms = 0;
  double user_ms = 0;
  double sys_ms = 0;
  double minor_faults = 0;
  double involuntary_switches = 0;
  double max_rss_mib = 0;
  double cpu_ms() const { return user_ms + sys_ms; }
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
  sample.user_ms = ms(usage.ru_utime);
  sample.sys_ms = ms(usage.ru_stime);
  sample.minor_faults = static_cast<double>(usage.ru_minflt);
  sample.involuntary_switches = static_cast<double>(usage.ru_nivcsw);
  sample.max_rss_mib = static_cast<double>(usage.ru_maxrss) / 1024.0;
  return sample;
}

// Ticks of every core since boot from /proc/stat's first line: busy (user, nice, system, irq,
// softirq, steal: the hypervisor running someone else counts as taken) and all.
struct CpuTicks {
  double busy = 0, all = 0;
};

CpuTicks cpu_ticks() {
  CpuTicks ticks;
  std::ifstream stat("/proc/stat");
  std::string label;
  double user = 0, nice = 0, system = 0, idle = 0, iowait = 0, irq = 0, softirq = 0, steal = 0;
  if (stat >> label >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal && label == "cpu") {
    ticks.busy = user + nice + system + irq + softirq + steal;
    ticks.all = ticks.busy + idle + iowait;
  }
  return ticks;
}

// The share of the machine's cores that other processes kept busy while a pair ran: the busy
// ticks of the interval less the pair's own CPU time, over the interval's ticks (10 ms ticks:
// about +-0.02 for a pair of 400 ms on two cores).
double others_busy(const CpuTicks& before, const CpuTicks& after, double own_cpu_ms) {
  const double tick_ms = 1000.0 / static_cast<double>(sysconf(_SC_CLK_TCK));
  const double all = after.all - before.all;
  if (all <= 0) return 0;
  return std::clamp((after.busy - before.busy - own_cpu_ms / tick_ms) / all, 0.0, 1.0);
}

struct Side {
  std::string name;
  std::vector<std::string> command;
  std::vector<Sample> samples;
  // The file the command writes, removed before each run (not timed): every run writes a fresh
  // output, as a first convert does. (Over an output with the very same bytes, `rdtf convert`
  // leaves the file as it is, unsynced and not renamed, which the peer's write cannot.)
  std::filesystem::path output;
  std::vector<double> values(double (*field)(const Sample&)) const {
    std::vector<double> out;
    for (const auto& s : samples) out.push_back(field(s));
    return out;
  }
};

double wall(const Sample& s) { return s.wall_ms; }
double cpu(const Sample& s) { return s.cpu_ms(); }
double user(const Sample& s) { return s.user_ms; }
double sys(const Sample& s) { return s.sys_ms; }
double faults(const Sample& s) { return s.minor_faults; }
double switches(const Sample& s) { return s.involuntary_switches; }

struct Comparison {
  std::string name;
  double goal;  // Largest ratio rdtf / peer (wall) the goal allows; 0: none (a before/after).
  Side rdtf, peer;
  std::vector<double> others;  // Per pair: others_busy during it.
  std::vector<double> ratios(double (*field)(const Sample&)) const {
    std::vector<double> out;
    for (std::size_t i = 0; i < rdtf.samples.size(); ++i) out.push_back(field(rdtf.samples[i]) / field(peer.samples[i]));
    return out;
  }
  // The per-pair ratios of the pairs whose others_busy lies in [low, high).
  std::vector<double> ratios_when(double (*field)(const Sample&), double low, double high) const {
    const auto all = ratios(field);
    std::vector<double> out;
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (others[i] >= low && others[i] < high) out.push_back(all[i]);
    }
    return out;
  }
};

void print_side(const Side& side) {
  double rss = 0;
  for (const auto& s : side.samples) rss = std::max(rss, s.max_rss_mib);
  std::printf("| %s | %.1f | %.1f | %.1f | %.1f | %.0f | %.0f | %.0f |\n", side.name.c_str(),
              median_of(side.values(wall)), median_of(side.values(cpu)), median_of(side.values(user)),
              median_of(side.values(sys)), median_of(side.values(faults)), median_of(side.values(switches)), rss);
}

std::string interval_text(const std::vector<double>& ratios) {
  const auto interval = rdtf::bench::median_interval(ratios, 0.95);
  char text[128];
  if (!interval) {
    std::snprintf(text, sizeof(text), "%.3fx (too few pairs for an interval)", median_of(ratios));
  } else {
    std::snprintf(text, sizeof(text), "%.3fx [%.3f, %.3f]", interval->median, interval->low, interval->high);
  }
  return text;
}

std::string verdict(const std::vector<double>& ratios, double goal) {
  if (goal == 0) return "-";
  const auto interval = rdtf::bench::median_interval(ratios, 0.95);
  if (!interval) return "too few pairs to say";
  char text[160];
  if (interval->high <= goal) {
    std::snprintf(text, sizeof(text), "**met** (95 %% interval at or below %.2fx)", goal);
  } else if (interval->low > goal) {
    std::snprintf(text, sizeof(text), "**not met** (95 %% interval above %.2fx)", goal);
  } else {
    std::snprintf(text, sizeof(text), "**not shown** (95 %% interval straddles %.2fx)", goal);
  }
  return text;
}

// Every run slower than its program's far-out limit, with what explains it.
void print_outliers(const std::vector<Comparison>& comparisons) {
  std::printf("\nOutliers (wall time above Q3 + 3 IQR of the program's runs; kept in every statistic):\n\n");
  std::printf("| program | pair | wall ms | user ms | sys ms | minor faults | invol. switches | others' share | pair's wall ratio |\n"
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  int count = 0;
  for (const auto& comparison : comparisons) {
    const auto ratios = comparison.ratios(wall);
    for (const Side* side : {&comparison.rdtf, &comparison.peer}) {
      const double limit = rdtf::bench::far_out_limit(side->values(wall));
      for (std::size_t i = 0; i < side->samples.size(); ++i) {
        const Sample& s = side->samples[i];
        if (s.wall_ms <= limit) continue;
        ++count;
        std::printf("| %s | %zu | %.1f | %.1f | %.1f | %.0f | %.0f | %.2f | %.3fx |\n", side->name.c_str(), i,
                    s.wall_ms, s.user_ms, s.sys_ms, s.minor_faults, s.involuntary_switches, comparison.others[i],
                    ratios[i]);
      }
    }
  }
  if (count == 0) std::printf("| (none) | | | | | | | | |\n");
}

void write_csv(const std::string& path, const std::vector<Comparison>& comparisons) {
  std::ofstream out(path);
  out << "comparison,program,pair,wall_ms,user_ms,sys_ms,minor_faults,involuntary_switches,max_rss_mib,others_busy\n";
  for (const auto& comparison : comparisons) {
    for (const Side* side : {&comparison.rdtf, &comparison.peer}) {
      for (std::size_t i = 0; i < side->samples.size(); ++i) {
        const Sample& s = side->samples[i];
        out << comparison.name << ',' << side->name << ',' << i << ',' << s.wall_ms << ',' << s.user_ms << ','
            << s.sys_ms << ',' << s.minor_faults << ',' << s.involuntary_switches << ',' << s.max_rss_mib << ','
            << comparison.others[i] << '\n';
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  int rounds = 41;
  std::size_t triangles = 1'300'000;
  std::string csv;
  std::string baseline;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if ((arg == "--pairs" || arg == "--runs") && i + 1 < argc) {
      rounds = std::atoi(argv[++i]);
    } else if (arg == "--triangles" && i + 1 < argc) {
      triangles = static_cast<std::size_t>(std::atoll(argv[++i]));
    } else if (arg == "--csv" && i + 1 < argc) {
      csv = argv[++i];
    } else if (arg == "--baseline" && i + 1 < argc) {
      baseline = std::filesystem::absolute(argv[++i]);
    } else {
      positional.push_back(arg);
    }
  }
  if (positional.size() != 2 || rounds < 1) {
    std::fprintf(stderr,
                 "usage: whole_process_bench [--pairs N] [--triangles N] [--csv FILE] [--baseline OLD_RDTF] RDTF "
                 "TINYGLTF_PEER\n");
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

  std::vector<Comparison> comparisons = {
      {"convert (write GLB)", 1.2,
       {"rdtf convert --glb", {rdtf, "convert", model, "-o", (folder / "rdtf_out.glb").string()}, {}, folder / "rdtf_out.glb"},
       {"tinygltf load + write GLB", {peer, "write", model, (folder / "peer_out.glb").string()}, {}, folder / "peer_out.glb"},
       {}},
      {"inspect", 1.3,
       {"rdtf inspect", {rdtf, "inspect", model}, {}, {}},
       {"tinygltf load", {peer, "load", model}, {}, {}},
       {}},
  };
  if (!baseline.empty()) {
    comparisons.push_back({"convert, new / old rdtf", 0,
                           {"rdtf convert --glb", comparisons[0].rdtf.command, {}, comparisons[0].rdtf.output},
                           {"old rdtf convert --glb", {baseline, "convert", model, "-o", (folder / "old_out.glb").string()}, {},
                            folder / "old_out.glb"},
                           {}});
    comparisons.push_back({"inspect, new / old rdtf", 0,
                           {"rdtf inspect", comparisons[1].rdtf.command, {}, {}},
                           {"old rdtf inspect", {baseline, "inspect", model}, {}, {}},
                           {}});
  }
  const auto started = std::chrono::steady_clock::now();
  try {
    for (int round = -1; round < rounds; ++round) {  // round -1: warm-up, not counted
      for (auto& comparison : comparisons) {
        const bool rdtf_first = round % 2 == 0;
        Side& first = rdtf_first ? comparison.rdtf : comparison.peer;
        Side& second = rdtf_first ? comparison.peer : comparison.rdtf;
        std::error_code ignored;
        if (!first.output.empty()) std::filesystem::remove(first.output, ignored);
        if (!second.output.empty()) std::filesystem::remove(second.output, ignored);
        const CpuTicks before = cpu_ticks();
        const Sample a = run(first.command);
        const Sample b = run(second.command);
        const CpuTicks after = cpu_ticks();
        if (round >= 0) {
          first.samples.push_back(a);
          second.samples.push_back(b);
          comparison.others.push_back(others_busy(before, after, a.cpu_ms() + b.cpu_ms()));
        }
      }
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "whole_process_bench: %s\n", error.what());
    return 1;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::printf("load average after: %s (%.0f s)\n\n", rdtf::bench::load_average().c_str(), seconds);
  if (!csv.empty()) write_csv(csv, comparisons);

  std::printf("Medians over %d pairs (after one warm-up round):\n\n", rounds);
  std::printf("| program | wall ms | CPU ms | user ms | sys ms | minor faults | invol. switches | max RSS MiB |\n"
              "| --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (const auto& comparison : comparisons) {
    print_side(comparison.rdtf);
    print_side(comparison.peer);
  }
  std::printf("\nPer-pair ratios rdtf / tinygltf: median [95 %% order-statistics interval]\n\n"
              "| comparison | wall | CPU (user+sys) | user | wall, ratio of medians | goal (wall) |\n"
              "| --- | --- | --- | --- | --- | --- |\n");
  for (const auto& comparison : comparisons) {
    const auto walls = comparison.ratios(wall);
    const double of_medians = median_of(comparison.rdtf.values(wall)) / median_of(comparison.peer.values(wall));
    char goal[32] = "none";
    if (comparison.goal > 0) std::snprintf(goal, sizeof(goal), "<= %.1fx", comparison.goal);
    std::printf("| %s | %s | %s | %s | %.3fx | %s: %s |\n", comparison.name.c_str(), interval_text(walls).c_str(),
                interval_text(comparison.ratios(cpu)).c_str(), interval_text(comparison.ratios(user)).c_str(),
                of_medians, goal, verdict(walls, comparison.goal).c_str());
  }
  // The ratio depends on how busy the machine is (the peer's many small page faults and rdtf's
  // cache-bound surface check suffer differently), so the pairs are also split by the share of
  // the cores other processes took while they ran: quiet below 0.25 (on two cores, other work
  // of at most half a core), busy above.
  std::printf("\nBy how busy other processes kept the cores during the pair (share of all cores):\n\n"
              "| comparison | others' share, median [min, max] | quiet pairs (< 0.25): n, wall ratio | busy pairs (>= 0.25): n, wall ratio | goal, quiet pairs |\n"
              "| --- | --- | --- | --- | --- |\n");
  for (const auto& comparison : comparisons) {
    const auto quiet = comparison.ratios_when(wall, 0.0, 0.25);
    const auto busy = comparison.ratios_when(wall, 0.25, 2.0);
    const auto [lo, hi] = std::minmax_element(comparison.others.begin(), comparison.others.end());
    std::printf("| %s | %.2f [%.2f, %.2f] | %zu, %s | %zu, %s | %s |\n", comparison.name.c_str(),
                median_of(comparison.others), *lo, *hi, quiet.size(),
                quiet.empty() ? "-" : interval_text(quiet).c_str(), busy.size(),
                busy.empty() ? "-" : interval_text(busy).c_str(), verdict(quiet, comparison.goal).c_str());
  }
  print_outliers(comparisons);
  return 0;
}
