// Soak (label soak, not in the default run: see tests/CMakeLists.txt): edits at 10 Hz across 50
// models for RDTF_SOAK_SECONDS (default 600). The daemon's resident memory (VmRSS) is sampled
// once a second; after a warm-up (the first fifth of the run, at least 10 s) its least-squares
// slope is printed, and the growth of that line over the rest of the run must stay under
// max(4 MiB, 5% of the warm RSS). Every save is published exactly once: one DESCRIPTION per
// (model, content) and nothing else.
#include <numeric>
#include <set>

#include "daemon/harness.h"

namespace rdtf::itest {
namespace {

constexpr int kModels = 50;
constexpr auto kEditPeriod = 100ms;  // 10 Hz over all models: each model every 5 s.

std::optional<double> rss_kib(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6));
  }
  return std::nullopt;
}

// Least-squares slope of y over x.
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  const double mean_x = std::accumulate(x.begin(), x.end(), 0.0) / n;
  const double mean_y = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double sxy = 0;
  double sxx = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mean_x) * (y[i] - mean_y);
    sxx += (x[i] - mean_x) * (x[i] - mean_x);
  }
  return sxy / sxx;
}

std::string model_file(int index) { return "model_" + std::to_string(index) + ".gltf"; }

GeneratedModel edit(int index, int version) {
  return box_model("m" + std::to_string(index) + "_v" + std::to_string(version), 0.05 + 0.001 * (version % 50),
                   1 + index % 4, index % 2 == 0 ? "model_" + std::to_string(index) + ".bin" : "");
}

TEST(SoakDaemon, TenHertzEditsAcrossFiftyModelsKeepMemoryFlatAndPublishEachSaveOnce) {
  const char* configured = std::getenv("RDTF_SOAK_SECONDS");
  const double seconds = configured != nullptr ? std::atof(configured) : 600.0;
  Session s;
  std::map<std::pair<std::string, std::string>, int> saves;  // (model, hash) -> times saved.
  std::vector<int> version(kModels, 0);
  for (int i = 0; i < kModels; ++i) {
    const auto model = edit(i, 0);
    write_model(s.watch, model_file(i), model);
    ++saves[{model_file(i), content_hash(model)}];
  }
  s.start();
  const pid_t pid = s.daemon->pid();
  // Edits start once the initial scan has published every model: an edit during the scan may
  // replace a first version before rdtfd ever reads it, which is then rightly never published.
  ASSERT_TRUE(s.wait_for(
      [&](const auto& all) {
        std::set<std::string> seen;
        for (const auto& d : decoded<rdtf::description_t>(all, "DESCRIPTION")) seen.insert(d.model_id);
        return seen.size() == static_cast<std::size_t>(kModels);
      },
      30s));

  std::vector<double> times;
  std::vector<double> rss;
  const auto start = Clock::now();
  auto next_sample = start;
  for (int n = 0;; ++n) {
    const auto now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    if (elapsed >= seconds) break;
    if (now >= next_sample) {
      const auto kib = rss_kib(pid);
      ASSERT_TRUE(kib) << "rdtfd is gone";
      times.push_back(elapsed);
      rss.push_back(*kib);
      next_sample += 1s;
    }
    // A save of the next model, by rename as editors do: every save is a whole new content.
    const int i = n % kModels;
    const auto model = edit(i, ++version[i]);
    if (!model.bin_name.empty()) write_by_rename(s.watch / model.bin_name, model.bin, "." + model.bin_name + ".part");
    write_by_rename(s.watch / model_file(i), model.gltf, "." + model_file(i) + ".part");
    ++saves[{model_file(i), content_hash(model)}];
    std::this_thread::sleep_until(start + kEditPeriod * (n + 1));  // The 10 Hz pace is the test.
  }
  const auto idle = s.wait_idle(3, 30s);
  ASSERT_TRUE(idle);

  // Memory: slope after warm-up, and the growth it implies over the measured span.
  const double warm_up = std::max(10.0, seconds / 5);
  std::vector<double> x;
  std::vector<double> y;
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (times[k] >= warm_up) {
      x.push_back(times[k]);
      y.push_back(rss[k]);
    }
  }
  ASSERT_GE(x.size(), 10u) << "run longer than " << warm_up + 10 << " s (RDTF_SOAK_SECONDS)";
  const double kib_per_s = slope(x, y);
  const double growth = kib_per_s * (x.back() - x.front());
  const double bound = std::max(4096.0, 0.05 * y.front());
  std::cout << "soak: " << seconds << " s, " << std::accumulate(version.begin(), version.end(), 0) << " edits; VmRSS "
            << rss.front() << " KiB at start, " << y.front() << " KiB after warm-up (" << warm_up << " s), "
            << rss.back() << " KiB at the end, max " << *std::max_element(rss.begin(), rss.end())
            << " KiB; slope after warm-up " << kib_per_s * 60 << " KiB/min (" << growth
            << " KiB over the measured span; bound " << bound << " KiB)" << std::endl;
  EXPECT_LT(growth, bound);

  // Every save published exactly once, and nothing that was not saved.
  std::map<std::pair<std::string, std::string>, int> published;
  for (const auto& d : decoded<rdtf::description_t>(s.messages(), "DESCRIPTION")) ++published[{d.model_id, d.content_hash}];
  int missing = 0;
  int repeated = 0;
  for (const auto& [save, count] : saves) {
    const auto found = published.find(save);
    if (found == published.end()) {
      ++missing;
      std::cout << "soak: never published: " << save.first << " " << short_hash(save.second) << std::endl;
    } else if (found->second != 1) {
      ++repeated;
      std::cout << "soak: published " << found->second << " times: " << save.first << " " << short_hash(save.second)
                << std::endl;
    }
  }
  EXPECT_EQ(missing, 0) << "saves never published";
  EXPECT_EQ(repeated, 0) << "saves published more than once";
  EXPECT_EQ(published.size(), saves.size());
  EXPECT_EQ(idle->rejections, 0);
  EXPECT_EQ(idle->conversions, static_cast<std::int64_t>(saves.size()));
}

}  // namespace
}  // namespace rdtf::itest
