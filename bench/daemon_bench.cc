// Issue 3, rdtfd end to end over real LCM (UDP multicast inside the program's own network
// namespace, see daemon_harness.h):
// - BM_SaveToPublish: from the close() of an in-place save to the DESCRIPTION of that revision at a
//   subscriber (and to its last DESCRIPTION_CHUNK when the document is chunked), p50 / p99, for the
//   arm3 fixture and a one-million-triangle GLB, with rdtfd's defaults (validate, simulate, urdf on)
//   and with conversion only. The settle period (50 ms, the default) is part of every sample; the
//   counters also give the latency minus the settle period, rdtfd's stages from its log and its
//   CPU time per save. What each save changes (the third argument, arm3 only): the generator
//   string (metadata), a material's colour (visuals), or a joint's damping (the robot itself, so
//   that the dynamics check must run again). The fourth: converted while settling (rdtfd's
//   default, convert_while_settling) or only after the settle period, side by side in one run.
// - BM_InitialScan: rdtfd started on a tree of N small models; models per second from spawning the
//   daemon until the subscriber has a DESCRIPTION of every model, and VmRSS / VmHWM of rdtfd then.
// - BM_Restart: the same tree scanned once, rdtfd stopped and started again: the second start's
//   time to every model published (from the result cache) and its memory.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include <rdtf/description_chunk_t.hpp>
#include <rdtf/description_t.hpp>
#include <rdtf/request_t.hpp>
#include <rdtf/status_t.hpp>

#include "daemon_harness.h"
#include "synthetic_models.h"

namespace {

using namespace rdtf::bench;
using namespace std::chrono_literals;

constexpr int kSettleMs = 50;  // rdtfd's default settle_ms.

// `while_settling`: convert_while_settling (the default) or conversions only after the settle.
Json pipeline_config(bool full_pipeline, bool while_settling = true) {
  Json config = {{"settle_ms", kSettleMs}, {"convert_while_settling", while_settling}};
  if (!full_pipeline) config.update({{"validate", false}, {"simulate", false}, {"urdf", false}});
  return config;
}

// ------------------------------------------------------------------------------------------------
// Models whose every revision differs by a few bytes (the generator string), content otherwise equal.

struct EditableModel {
  std::string file_name;
  std::function<std::string(int)> revision_bytes;  // Content of save number k.
};

enum class Edit { kGenerator = 0, kColour = 1, kRobot = 2 };

const char* edit_name(Edit edit) {
  switch (edit) {
    case Edit::kGenerator: return "generator";
    case Edit::kColour: return "colour";
    case Edit::kRobot: return "joint damping";
  }
  return "?";
}

// Save k of arm3: the generator string names k, and, by `edit`, a material's base colour or the
// elbow's damping (0.4 N m s/rad plus k * 1e-5: every save another robot) depends on k too.
EditableModel arm3_model(const fs::path& folder, Edit edit) {
  const fs::path source = fs::path(RDTF_BENCH_DATA_DIR) / "blender";
  fs::copy_file(source / "arm3.bin", folder / "arm3.bin");
  Json document = Json::parse(read_file(source / "arm3.gltf"));
  document["materials"] = Json::array({{{"name", "paint"}, {"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.5, 0.5, 1.0}}}}}});
  for (auto& mesh : document["meshes"]) {
    for (auto& primitive : mesh["primitives"]) primitive["material"] = 0;
  }
  return {"arm3.gltf", [document, edit](int k) {
            Json edited = document;
            edited["asset"]["generator"] = "rdtf bench save " + std::to_string(k);
            if (edit == Edit::kColour) {
              edited["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"][0] = (k % 1000) / 1000.0;
            } else if (edit == Edit::kRobot) {
              for (auto& node : edited["nodes"]) {
                if (node.value("name", "") == "elbow") node["extras"]["rdtf_damping"] = 0.4 + k * 1e-5;
              }
            }
            return edited.dump(1);
          }};
}

EditableModel sphere_model() {
  const auto glb = mesh_glb(uv_sphere(1'000'000, 0.5));
  const std::string bytes(glb.begin(), glb.end());
  const std::size_t at = bytes.find("rdtf bench");  // asset.generator, 10 characters.
  if (at == std::string::npos) throw std::runtime_error("generator string not found in the GLB");
  return {"sphere_1m.glb", [bytes, at](int k) {
            std::string edited = bytes;
            char tag[16];
            std::snprintf(tag, sizeof(tag), "rdtf%06d", k % 1000000);
            std::memcpy(edited.data() + at, tag, 10);
            return edited;
          }};
}

// When each revision's DESCRIPTION, and its complete document (the last chunk), arrived.
struct Arrivals {
  std::map<std::int64_t, Clock::time_point> description;
  std::map<std::int64_t, Clock::time_point> complete;
  std::map<std::int64_t, int> chunks_seen;
  std::map<std::int64_t, int> chunks_expected;
  std::int64_t triangles_links = 0;
};

void record(Arrivals& arrivals, const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point at) {
  const std::string kind = kind_of(channel);
  const auto size = static_cast<int>(buffer.data_size);
  if (kind == "DESCRIPTION") {
    rdtf::description_t d;
    if (d.decode(buffer.data, 0, size) < 0) return;
    arrivals.description.emplace(d.revision, at);
    arrivals.chunks_expected[d.revision] = d.num_chunks;
    if (d.num_chunks == 0) arrivals.complete.emplace(d.revision, at);
  } else if (kind == "DESCRIPTION_CHUNK") {
    rdtf::description_chunk_t c;
    if (c.decode(buffer.data, 0, size) < 0) return;
    if (++arrivals.chunks_seen[c.revision] == c.count) arrivals.complete.emplace(c.revision, at);
  }
}

// rdtfd's own time per conversion job (read, hash, convert, validate, URDF, write) and each of its
// stages, from its log lines "converted <id> revision N (...) in X ms; stages: read X ms, ...",
// for revisions from `first_revision` on. By name: "worker", then each stage's.
std::map<std::string, std::vector<double>> stage_times_ms(const std::string& log, std::int64_t first_revision) {
  static const std::regex kLine(R"(converted \S+ revision (\d+) \([^)]*\) in ([0-9.]+) ms([^\n]*))");
  static const std::regex kStage(R"(([a-z][a-z ]*[a-z]) ([0-9.]+) ms)");
  std::map<std::string, std::vector<double>> times;
  for (std::sregex_iterator it(log.begin(), log.end(), kLine), end; it != end; ++it) {
    if (std::stoll((*it)[1]) < first_revision) continue;
    times["worker"].push_back(std::stod((*it)[2]));
    const std::string stages = (*it)[3];
    for (std::sregex_iterator st(stages.begin(), stages.end(), kStage); st != end; ++st) {
      times[(*st)[1]].push_back(std::stod((*st)[2]));
    }
  }
  return times;
}

// CPU time (user + system) of a process so far, in ms, from /proc/<pid>/stat.
double process_cpu_ms(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  double user = 0, system = 0;
  for (int i = 3; fields >> field; ++i) {  // Field 3 is the state; 14 utime, 15 stime.
    if (i == 14) user = std::stod(field);
    if (i == 15) {
      system = std::stod(field);
      break;
    }
  }
  return (user + system) * 1000.0 / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

// range(0): 0 arm3, 1 the 1M-triangle sphere; range(1): 1 rdtfd's defaults, 0 conversion only;
// range(2) what each save of arm3 changes (Edit).
void BM_SaveToPublish(benchmark::State& state) {
  const bool big = state.range(0) == 1;
  const bool full_pipeline = state.range(1) == 1;
  const auto edit = static_cast<Edit>(state.range(2));
  const bool while_settling = state.range(3) == 1;
  TempFolder root;
  const fs::path watch = root / "models", output = root / "out";
  fs::create_directories(watch);
  const EditableModel model = big ? sphere_model() : arm3_model(watch, edit);
  const auto timeout = big ? 60s : 10s;

  Arrivals arrivals;
  Subscriber subscriber("RDTF", [&](const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point at) {
    record(arrivals, channel, buffer, at);
  });
  int saves = 1;
  write_in_place(watch / model.file_name, model.revision_bytes(saves));
  Daemon daemon(watch, output, pipeline_config(full_pipeline, while_settling));
  if (!subscriber.wait([&] { return arrivals.complete.count(1) > 0; }, timeout)) {
    state.SkipWithError(("no first revision; rdtfd log:\n" + daemon.log()).c_str());
    return;
  }

  std::vector<double> to_description, to_complete;
  const double cpu_before = process_cpu_ms(daemon.pid());
  for (auto _ : state) {
    const std::string bytes = model.revision_bytes(++saves);
    const Clock::time_point saved = write_in_place(watch / model.file_name, bytes);
    const std::int64_t revision = saves;
    if (!subscriber.wait([&] { return arrivals.complete.count(revision) > 0; }, timeout)) {
      state.SkipWithError(("revision " + std::to_string(revision) + " not published; rdtfd log:\n" + daemon.log()).c_str());
      break;
    }
    subscriber.locked([&] {
      to_description.push_back(ms_between(saved, arrivals.description.at(revision)));
      to_complete.push_back(ms_between(saved, arrivals.complete.at(revision)));
    });
    state.SetIterationTime(to_complete.back() / 1e3);
  }
  // Everything rdtfd did meanwhile, the live simulation of the model (with the defaults) included.
  state.counters["cpu_per_save_ms"] = (process_cpu_ms(daemon.pid()) - cpu_before) / static_cast<double>(to_description.size());
  state.SetLabel(std::string(big ? "1M-triangle GLB" : std::string("arm3, ") + edit_name(edit) + " changed") +
                 (full_pipeline ? ", defaults" : ", convert only") +
                 (while_settling ? "" : ", converted after the settle"));
  state.counters["settle_ms"] = kSettleMs;
  state.counters["p50_ms"] = quantile(to_description, 0.5);
  state.counters["p99_ms"] = quantile(to_description, 0.99);
  state.counters["max_ms"] = quantile(to_description, 1.0);
  state.counters["p50_minus_settle_ms"] = quantile(to_description, 0.5) - kSettleMs;
  state.counters["p99_minus_settle_ms"] = quantile(to_description, 0.99) - kSettleMs;
  state.counters["p50_complete_ms"] = quantile(to_complete, 0.5);
  state.counters["p99_complete_ms"] = quantile(to_complete, 0.99);
  state.counters["samples"] = static_cast<double>(to_description.size());
  for (const auto& [stage, times] : stage_times_ms(daemon.log(), 2)) {
    std::string name = stage;
    std::replace(name.begin(), name.end(), ' ', '_');
    state.counters["p50_" + name + "_ms"] = quantile(times, 0.5);
    state.counters["p99_" + name + "_ms"] = quantile(times, 0.99);
  }
  daemon.stop();
}
// Arguments: big, defaults (else convert only), what each save changes, converted while settling
// (the default; 0: only after the settle, as before convert_while_settling).
BENCHMARK(BM_SaveToPublish)->Args({0, 1, 0, 1})->Iterations(200)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SaveToPublish)->Args({0, 1, 0, 0})->Iterations(200)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SaveToPublish)->Args({0, 1, 1, 1})->Iterations(200)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SaveToPublish)->Args({0, 1, 2, 1})->Iterations(200)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SaveToPublish)->Args({0, 1, 2, 0})->Iterations(200)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SaveToPublish)->Args({0, 0, 0, 1})->Iterations(200)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SaveToPublish)->Args({0, 0, 0, 0})->Iterations(200)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SaveToPublish)->Args({1, 1, 0, 1})->Iterations(20)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SaveToPublish)->Args({1, 1, 0, 0})->Iterations(20)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SaveToPublish)->Args({1, 0, 0, 1})->Iterations(20)->UseManualTime()->Unit(benchmark::kMillisecond);

// ------------------------------------------------------------------------------------------------
// Initial scan

// `count` one-box models, 100 per folder: models/dNNN/box_NNNNN.gltf.
void write_model_tree(const fs::path& watch, int count) {
  for (int i = 0; i < count; ++i) {
    char folder[16], name[32];
    std::snprintf(folder, sizeof(folder), "d%03d", i / 100);
    std::snprintf(name, sizeof(name), "box_%05d", i);
    fs::create_directories(watch / folder);
    write_in_place(watch / folder / (std::string(name) + ".gltf"), small_box_gltf(name));
  }
}

// range(0): number of models; range(1): 1 rdtfd's defaults, 0 validate, simulate and urdf off;
// range(2): 1 converted while settling (the default), 0 only after the settle.
void BM_InitialScan(benchmark::State& state) {
  const int count = static_cast<int>(state.range(0));
  const bool full_pipeline = state.range(1) == 1;
  const bool while_settling = state.range(2) == 1;
  TempFolder root;
  const fs::path watch = root / "models", output = root / "out";
  write_model_tree(watch, count);

  std::set<std::string> published;
  Clock::time_point last_description;
  Subscriber subscriber("RDTF", [&](const std::string& channel, const lcm::ReceiveBuffer&, Clock::time_point at) {
    if (kind_of(channel) == "DESCRIPTION" && published.insert(model_id_of(channel)).second) last_description = at;
  });
  for (auto _ : state) {
    const Clock::time_point started = Clock::now();
    Daemon daemon(watch, output, pipeline_config(full_pipeline, while_settling));
    const bool all = subscriber.wait([&] { return static_cast<int>(published.size()) == count; }, 150s);
    const Memory memory = process_memory(daemon.pid());
    double seconds = 0;
    subscriber.locked([&] { seconds = ms_between(started, last_description) / 1e3; });
    if (!all) {
      state.SkipWithError(("only " + std::to_string(published.size()) + " of " + std::to_string(count) +
                           " models published in 150 s").c_str());
    }
    state.SetIterationTime(seconds);
    state.counters["models_per_s"] = static_cast<double>(published.size()) / seconds;
    state.counters["VmRSS_MiB"] = static_cast<double>(memory.rss_kib) / 1024.0;
    state.counters["VmHWM_MiB"] = static_cast<double>(memory.hwm_kib) / 1024.0;
    state.counters["published"] = static_cast<double>(published.size());
    daemon.stop();
  }
  state.SetLabel(std::to_string(count) + " models, " + (full_pipeline ? "defaults" : "validate/simulate/urdf off") +
                (while_settling ? "" : ", converted after the settle"));
}
BENCHMARK(BM_InitialScan)->Args({1000, 0, 1})->Args({10000, 0, 1})->Args({1000, 1, 1})->Args({1000, 1, 0})
    ->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

// What a subscriber of a restart sees: the first DESCRIPTION of each model and when it came, and
// rdtfd's latest STATUS (periodic, so a lost one is followed by another).
struct RestartView {
  std::map<std::string, Clock::time_point> described;
  Clock::time_point last_description{};
  int status_models = -1, status_pending = -1;
  std::int64_t status_queue_bytes = -1, status_send_dropped = 0;
  std::int32_t status_pid = 0;
  void clear() { *this = RestartView{}; }
};

void record_restart(RestartView& view, const std::string& channel, const lcm::ReceiveBuffer& buffer,
                    Clock::time_point at) {
  const std::string kind = kind_of(channel);
  if (kind == "DESCRIPTION") {
    if (view.described.emplace(model_id_of(channel), at).second) view.last_description = at;
  } else if (kind == "STATUS") {
    rdtf::status_t status;
    if (status.decode(buffer.data, 0, static_cast<int>(buffer.data_size)) < 0) return;
    view.status_pid = status.pid;
    view.status_models = status.num_models;
    view.status_pending = status.pending;
    view.status_queue_bytes = status.send_queue_bytes;
    view.status_send_dropped = status.send_dropped;
  }
}

// range(0): number of models; range(1) as for BM_InitialScan. rdtfd scans the tree once (which
// fills its result cache), stops, and is started again over the unchanged tree: the time is from
// spawning the second rdtfd to the subscriber holding a DESCRIPTION of every model from it, the
// memory its VmRSS / VmHWM then.
//
// Nothing republishes here (republish_period_ms 0), so a DESCRIPTION the subscriber's socket
// dropped (its buffer full: with the defaults every model's live simulation multicasts its states
// on the same group) would never come. The first run is therefore over when rdtfd's STATUS says
// every model is live and none pending, not when every DESCRIPTION arrived; on the restart, once
// STATUS says so and rdtfd's send queue is empty, each model still missing is asked for with a
// REQUEST, as a subscriber that starts late does (docs/lcm.md). `lost` counts those, and
// `s_before_requests` is the time to the last DESCRIPTION that came unasked.
void BM_Restart(benchmark::State& state) {
  const int count = static_cast<int>(state.range(0));
  const bool full_pipeline = state.range(1) == 1;
  TempFolder root;
  const fs::path watch = root / "models", output = root / "out";
  write_model_tree(watch, count);

  RestartView view;
  Subscriber subscriber("RDTF", [&](const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point at) {
    record_restart(view, channel, buffer, at);
  });
  auto all_live = [&](pid_t pid) {
    return [&view, &count, pid] {
      return view.status_pid == pid && view.status_models == count && view.status_pending == 0;
    };
  };
  for (auto _ : state) {
    Clock::time_point started = Clock::now();
    double first_seconds = 0;
    {
      Daemon first(watch, output, pipeline_config(full_pipeline));
      if (!subscriber.wait(all_live(first.pid()), 900s)) {  // A loaded machine: the first scan may take minutes.
        state.SkipWithError(("first run: " + std::to_string(view.status_models) + " models live").c_str());
        break;
      }
      first_seconds = ms_between(started, Clock::now()) / 1e3;
      first.stop();
    }
    subscriber.locked([&] { view.clear(); });
    const UdpCounters udp_before = udp_counters();
    started = Clock::now();
    Daemon daemon(watch, output, pipeline_config(full_pipeline));
    auto all_described = [&] { return static_cast<int>(view.described.size()) == count; };
    // Every model live and everything rdtfd queued sent: what is still missing was lost.
    auto sent = [&] { return all_described() || (all_live(daemon.pid())() && view.status_queue_bytes == 0); };
    bool all = subscriber.wait(sent, 150s) && subscriber.wait(all_described, 1s);
    double unasked_seconds = 0;
    std::vector<std::string> missing;
    subscriber.locked([&] {
      unasked_seconds = ms_between(started, view.last_description) / 1e3;
      const fs::path tree = watch;
      for (const auto& entry : fs::recursive_directory_iterator(tree)) {
        if (!entry.is_regular_file()) continue;
        const std::string id = entry.path().lexically_relative(tree).generic_string();
        if (!view.described.count(id)) missing.push_back(id);
      }
    });
    for (const std::string& id : missing) {
      rdtf::request_t request;
      request.utime = 0;
      request.model_id = id;
      request.requester = "daemon_bench BM_Restart";
      subscriber.publish("RDTF/REQUEST", request);
    }
    if (!missing.empty()) all = subscriber.wait(all_described, 60s);
    const Memory memory = process_memory(daemon.pid());
    const UdpCounters udp_after = udp_counters();
    double seconds = 0;
    std::int64_t send_dropped = 0;
    subscriber.locked([&] {
      seconds = ms_between(started, view.last_description) / 1e3;
      send_dropped = view.status_send_dropped;
    });
    const std::string log = daemon.log();
    std::size_t from_cache = 0;
    for (std::size_t at = log.find(" from the result cache"); at != std::string::npos;
         at = log.find(" from the result cache", at + 1)) {
      ++from_cache;
    }
    if (!all) {
      state.SkipWithError(("restart: only " + std::to_string(view.described.size()) + " of " + std::to_string(count) +
                           " models described, " + std::to_string(missing.size()) + " asked for again").c_str());
    }
    state.SetIterationTime(seconds);
    state.counters["first_run_s"] = first_seconds;
    state.counters["s_before_requests"] = unasked_seconds;
    state.counters["lost"] = static_cast<double>(missing.size());
    state.counters["rcvbuf_errors"] =
        static_cast<double>(udp_after.receive_buffer_errors - udp_before.receive_buffer_errors);
    state.counters["send_dropped"] = static_cast<double>(send_dropped);
    state.counters["models_per_s"] = static_cast<double>(view.described.size()) / seconds;
    state.counters["from_cache"] = static_cast<double>(from_cache);
    state.counters["VmRSS_MiB"] = static_cast<double>(memory.rss_kib) / 1024.0;
    state.counters["VmHWM_MiB"] = static_cast<double>(memory.hwm_kib) / 1024.0;
    state.counters["published"] = static_cast<double>(view.described.size());
    daemon.stop();
  }
  state.SetLabel(std::to_string(count) + " models, restart, " +
                 (full_pipeline ? "defaults" : "validate/simulate/urdf off"));
}
BENCHMARK(BM_Restart)->Args({1000, 1})->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

// 10,000 models with the defaults: about 100 s of scanning plus minutes of writing and deleting
// the trees on a busy disk, so only on request (--with-10k-defaults).
bool take_flag(int& argc, char** argv, const std::string& flag) {
  for (int i = 1; i < argc; ++i) {
    if (argv[i] == flag) {
      for (int j = i; j + 1 < argc; ++j) argv[j] = argv[j + 1];
      --argc;
      return true;
    }
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  run_in_own_network_namespace(argc, argv);
  if (take_flag(argc, argv, "--with-10k-defaults")) {
    benchmark::RegisterBenchmark("BM_InitialScan", BM_InitialScan)
        ->Args({10000, 1, 1})->Args({10000, 1, 0})->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
    benchmark::RegisterBenchmark("BM_Restart", BM_Restart)
        ->Args({10000, 1})->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
