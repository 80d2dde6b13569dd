// Console output as usual, plus the comparisons issue 6 asks for, computed from the runs of this
// one process: ratios measured side by side, never against numbers from another run.
//
// The machine these run on is shared (other builds on the same two cores), so each benchmark is
// best run with repetitions (--benchmark_repetitions=N): a run can only be slowed by the others,
// never sped up, so the fastest repetition is the best estimate of its own cost. Both clocks are
// kept: CPU time (this process's time on a core, which excludes waiting for the core and the
// hypervisor's steal time) and wall time.
#pragma once

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace rdtf::bench {

class SideBySide : public benchmark::ConsoleReporter {
 public:
  struct Best {
    double cpu_seconds = std::numeric_limits<double>::infinity();   // Per iteration.
    double real_seconds = std::numeric_limits<double>::infinity();  // Per iteration.
    int repetitions = 0;
    std::map<std::string, double> counters;  // Of the last repetition (they do not vary).
    bool found() const { return repetitions > 0; }
  };

  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.run_type != Run::RT_Iteration || run.error_occurred) continue;
      // Keyed by name without the "/repeats:N" suffix, so callers name benchmarks as declared.
      std::string name = run.benchmark_name();
      if (const auto at = name.find("/repeats:"); at != std::string::npos) name.erase(at);
      Best& best = best_[name];
      const double unit = benchmark::GetTimeUnitMultiplier(run.time_unit);
      best.cpu_seconds = std::min(best.cpu_seconds, run.GetAdjustedCPUTime() / unit);
      best.real_seconds = std::min(best.real_seconds, run.GetAdjustedRealTime() / unit);
      ++best.repetitions;
      for (const auto& [key, counter] : run.counters) best.counters[key] = counter.value;
    }
  }

  const Best& best(const std::string& name) const {
    static const Best none;
    const auto found = best_.find(name);
    return found == best_.end() ? none : found->second;
  }

 private:
  std::map<std::string, Best> best_;
};

// The load average, which says how busy the shared machine was during the run.
inline std::string load_average() {
  std::FILE* f = std::fopen("/proc/loadavg", "r");
  if (f == nullptr) return "unknown";
  char text[128] = {};
  const bool read = std::fgets(text, sizeof(text), f) != nullptr;
  std::fclose(f);
  std::string s = read ? text : "unknown";
  while (!s.empty() && s.back() == '\n') s.pop_back();
  return s;
}

}  // namespace rdtf::bench
