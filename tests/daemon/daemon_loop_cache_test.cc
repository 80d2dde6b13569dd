// rdtfd's result cache across restarts, with the loop stepped in-process (daemon_loop.h): a restart
// over unchanged models publishes what the first run published without converting anything; a
// setting that changes results, a changed model, a torn or altered entry and outputs removed from
// disk each make that model convert again; the number of entries stays within its bound.
#include <sys/stat.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <set>

#include "daemon_loop.h"
#include "rdtf/version.h"
#include "result_cache.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

class DaemonCache : public DaemonLoop {
 protected:
  // The full pipeline (the gate, the URDF), as rdtfd runs by default; no live simulation.
  void start_full(const std::function<void(DaemonConfig&)>& tweak = {}) {
    start([&](DaemonConfig& config) {
      config.validate = true;
      config.urdf = true;
      if (tweak) tweak(config);
    });
    advance(50ms);  // The settle of the initial scan.
    convert();
  }
  void restart(const std::function<void(DaemonConfig&)>& tweak = {}) {
    daemon_.reset();
    clear_bus();
    start_full(tweak);
  }
  // The id the registry gives `file` (below the watched folder), "(none)" when it is not known.
  std::string id_of(const fs::path& file) {
    const ModelRecord* record = const_cast<Registry&>(daemon_->registry()).find(watch_ / file);
    return record != nullptr ? record->id : std::string("(none)");
  }
  void write_models() {
    rdtf::testing::write_file(watch_ / "arm3.glb", fixture("arm3.glb"));
    rdtf::testing::write_file(watch_ / "two_cylinder.gltf", fixture("two_cylinder.gltf"));
    rdtf::testing::write_file(watch_ / "two_cylinder.bin", fixture("two_cylinder.bin"));
  }
  // Every message a subscriber gets about a revision (description, inertia table, verdict, manifest),
  // by channel, with the time of sending (every type's first field) zeroed.
  std::vector<std::string> revision_messages() {
    std::vector<std::string> out;
    for (const auto& sent : bus_->sent) {
      const auto kind = sent.channel.substr(sent.channel.rfind('/') + 1);
      if (kind != "DESCRIPTION" && kind != "INERTIA" && kind != "VALIDATION" && kind != "MANIFEST") continue;
      std::string bytes(sent.bytes.begin(), sent.bytes.end());
      EXPECT_GE(bytes.size(), 16u);
      if (bytes.size() >= 16) bytes.replace(8, 8, 8, '\0');  // After the 8-byte fingerprint: utime.
      out.push_back(sent.channel + " " + bytes);
    }
    return out;
  }
  // Each output file with its inode and modification time: rewritten files get a new inode.
  std::map<fs::path, std::pair<ino_t, std::int64_t>> outputs() {
    std::map<fs::path, std::pair<ino_t, std::int64_t>> files;
    for (const auto& entry : fs::recursive_directory_iterator(out_)) {
      if (!entry.is_regular_file() || entry.path().string().find(".rdtfd-state") != std::string::npos) continue;
      struct stat info {};
      EXPECT_EQ(::lstat(entry.path().c_str(), &info), 0);
      files[entry.path()] = {info.st_ino, info.st_mtim.tv_sec * 1'000'000'000LL + info.st_mtim.tv_nsec};
    }
    return files;
  }
  std::vector<fs::path> cache_entries() {
    std::vector<fs::path> files;
    const fs::path folder = ResultCache::folder_for(out_);
    if (!fs::exists(folder)) return files;
    for (const auto& entry : fs::directory_iterator(folder)) files.push_back(entry.path());
    return files;
  }
  fs::path entry_of(const std::string& name) {
    return ResultCache(ResultCache::folder_for(out_), 1).file_for((watch_ / name).string());
  }
};

TEST_F(DaemonCache, ARestartOverUnchangedModelsPublishesTheSameRevisionsWithoutConverting) {
  write_models();
  start_full();
  ASSERT_EQ(events("arm3.glb"), kRevision1);
  ASSERT_EQ(events("two_cylinder.gltf"), kRevision1);
  EXPECT_EQ(daemon_->counters().from_cache, 0);
  const auto first = revision_messages();
  const auto written = outputs();
  ASSERT_FALSE(written.empty());
  EXPECT_EQ(cache_entries().size(), 2u);

  restart();
  EXPECT_EQ(daemon_->counters().from_cache, 2);
  EXPECT_EQ(daemon_->counters().conversions, 2);
  EXPECT_EQ(daemon_->counters().cache_refused, 0);
  EXPECT_EQ(events("arm3.glb"), kRevision1);  // The same number, and no DELTA: nothing changed.
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
  // Byte for byte what the first run published (the verdict and the inertia table included).
  EXPECT_EQ(revision_messages(), first);
  EXPECT_EQ(outputs(), written) << "an output was written again";
}

TEST_F(DaemonCache, ASettingThatChangesResultsConvertsAgainAndOneThatDoesNotKeepsTheCache) {
  write_models();
  start_full();
  restart([](DaemonConfig& config) { config.state_rate_hz = 50; });  // The live simulation's only.
  EXPECT_EQ(daemon_->counters().from_cache, 2);
  restart([](DaemonConfig& config) { config.convert.default_density = 2000; });  // Every mass changes.
  EXPECT_EQ(daemon_->counters().from_cache, 0);
  EXPECT_EQ(events("arm3.glb"), (std::vector<std::string>{"DESCRIPTION r2", "INERTIA"}));
  restart([](DaemonConfig& config) { config.validation_seconds = 1; });  // The verdict may change.
  EXPECT_EQ(daemon_->counters().from_cache, 0);
  // The entries now hold the results under the last settings.
  restart();
  EXPECT_EQ(daemon_->counters().from_cache, 2);
}

TEST_F(DaemonCache, AModelChangedWhileTheDaemonWasStoppedIsConvertedAgain) {
  write_models();
  start_full();
  daemon_.reset();
  std::string gltf = fixture("two_cylinder.gltf");
  rdtf::testing::write_file(watch_ / "two_cylinder.gltf", gltf + " ");
  clear_bus();
  start_full();
  EXPECT_EQ(daemon_->counters().from_cache, 1);  // arm3 only.
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  // New content, converted and checked: a number of its own (docs/lcm.md, "Revision numbers").
  EXPECT_EQ(events("two_cylinder.gltf"), (std::vector<std::string>{"DESCRIPTION r2", "INERTIA"}));
  EXPECT_EQ(daemon_->counters().conversions, 2);
  // A new .bin alone is a change too (the content hash covers the files a model names).
  daemon_.reset();
  std::string bin = fixture("two_cylinder.bin");
  bin[bin.size() / 2] = static_cast<char>(bin[bin.size() / 2] ^ 1);
  rdtf::testing::write_file(watch_ / "two_cylinder.bin", bin);
  clear_bus();
  start_full();
  EXPECT_EQ(daemon_->counters().from_cache, 1);
}

TEST_F(DaemonCache, ATornOrAlteredEntryIsReportedAndRecomputed) {
  write_models();
  start_full();
  daemon_.reset();
  const fs::path torn = entry_of("arm3.glb"), altered = entry_of("two_cylinder.gltf");
  ASSERT_TRUE(fs::exists(torn));
  ASSERT_TRUE(fs::exists(altered));
  fs::resize_file(torn, fs::file_size(torn) / 2);  // A crash before all of it reached the disk.
  std::string bytes = rdtf::testing::read_file(altered);
  bytes[bytes.size() - 40] = static_cast<char>(bytes[bytes.size() - 40] ^ 0x20);  // One flipped bit.
  rdtf::testing::write_file(altered, bytes);
  clear_bus();
  ::testing::internal::CaptureStderr();
  start_full();
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(daemon_->counters().from_cache, 0);
  EXPECT_EQ(daemon_->counters().cache_refused, 2);
  EXPECT_NE(log.find("arm3.glb: result cache entry refused (" + torn.string()), std::string::npos) << log;
  EXPECT_NE(log.find("two_cylinder.gltf: result cache entry refused (" + altered.string() +
                     ": its checksum does not match"),
            std::string::npos)
      << log;
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  EXPECT_EQ(events("two_cylinder.gltf"), kRevision1);
  // Both were written again, whole: the next restart uses them.
  restart();
  EXPECT_EQ(daemon_->counters().from_cache, 2);
  EXPECT_EQ(daemon_->counters().cache_refused, 0);
}

TEST_F(DaemonCache, OutputsRemovedOrChangedOnDiskAreWrittenAgain) {
  write_models();
  start_full();
  daemon_.reset();
  const fs::path urdf = out_ / "arm3.glb" / "urdf" / "robot.urdf";
  const fs::path gltf = out_ / "two_cylinder.gltf" / "two_cylinder.rdtf.gltf";
  ASSERT_TRUE(fs::exists(urdf));
  ASSERT_TRUE(fs::exists(gltf));
  fs::remove(urdf);
  rdtf::testing::write_file(gltf, rdtf::testing::read_file(gltf) + " ");
  clear_bus();
  ::testing::internal::CaptureStderr();
  start_full();
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(daemon_->counters().from_cache, 0);
  EXPECT_EQ(daemon_->counters().cache_refused, 2);
  EXPECT_NE(log.find("the outputs changed on disk (" + urdf.string()), std::string::npos) << log;
  EXPECT_NE(log.find("the outputs changed on disk (" + gltf.string() + " was changed)"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(urdf));
  EXPECT_EQ(events("arm3.glb"), kRevision1);
  restart();
  EXPECT_EQ(daemon_->counters().from_cache, 2);
}

TEST_F(DaemonCache, EntriesStayWithinTheirBound) {
  for (int i = 0; i < 5; ++i) rdtf::testing::write_file(watch_ / ("arm" + std::to_string(i) + ".glb"), fixture("arm3.glb"));
  start_full([](DaemonConfig& config) { config.max_cached_results = 3; });
  EXPECT_EQ(daemon_->counters().conversions, 5);
  EXPECT_EQ(cache_entries().size(), 3u);
  restart([](DaemonConfig& config) { config.max_cached_results = 5; });
  EXPECT_EQ(daemon_->counters().from_cache, 3);  // The three kept; the two evicted converted again.
  EXPECT_EQ(cache_entries().size(), 5u);
  // A smaller bound: the least recently used beyond it go, at start and as entries are written.
  restart([](DaemonConfig& config) { config.max_cached_results = 2; });
  EXPECT_LE(cache_entries().size(), 2u);
  EXPECT_EQ(daemon_->counters().conversions, 5);
  // 0: no cache at all.
  restart([](DaemonConfig& config) { config.max_cached_results = 0; });
  EXPECT_EQ(daemon_->counters().from_cache, 0);
}

TEST_F(DaemonCache, TheStatusNamesTheBuildsVersionAndCommit) {
  start();
  EXPECT_EQ(last_status().version, version_line("rdtfd"));
}

// Files whose names sanitise to one id ("a b.glb", "a_b.glb") are numbered as they are found; a
// restart finds them in the directory's order, which may put the newer first. Each keeps its id:
// the id an earlier run gave a file that is still here stays that file's. Both orders are made:
// the same pair of names, the earlier file the spaced one in one folder and the other in the other
// (a directory lists the pair in one order, so one folder lists the newer file first).
TEST_F(DaemonCache, FilesWhoseNamesSanitiseAlikeKeepTheirIdsAcrossARestart) {
  fs::create_directories(watch_ / "one");
  fs::create_directories(watch_ / "two");
  rdtf::testing::write_file(watch_ / "one" / "a b.glb", fixture("arm3.glb"));
  rdtf::testing::write_file(watch_ / "two" / "a_b.glb", fixture("arm3.glb"));
  start_full();
  rdtf::testing::write_file(watch_ / "one" / "a_b.glb", fixture("modelled_arm.glb"));
  rdtf::testing::write_file(watch_ / "two" / "a b.glb", fixture("modelled_arm.glb"));
  notify(Kind::kWritten, watch_ / "one" / "a_b.glb");
  notify(Kind::kWritten, watch_ / "two" / "a b.glb");
  advance(50ms);
  convert();
  const std::map<std::string, std::string> expected{{"one/a b.glb", "one/a_b.glb"}, {"one/a_b.glb", "one/a_b.glb_2"},
                                                    {"two/a_b.glb", "two/a_b.glb"}, {"two/a b.glb", "two/a_b.glb_2"}};
  for (const auto& [file, id] : expected) ASSERT_EQ(id_of(file), id) << file << " before the restart";
  restart();
  for (const auto& [file, id] : expected) EXPECT_EQ(id_of(file), id) << file << " after the restart";
  // The id's revision is its own file's, restored and republished unchanged (once the paced
  // send queue has let all four models' messages out).
  advance(1s);
  EXPECT_EQ(events("one/a_b.glb"), kRevision1);
  EXPECT_EQ(events("two/a_b.glb"), kRevision1);
}

// Three files whose names sanitise alike; the one with "_2" is deleted while rdtfd is stopped.
// The others keep their ids: the third stays "_3" (it took the freed "_2", its channels silent
// and "_2" another robot; s100java D5), and a new file of the same id takes the freed "_2".
TEST_F(DaemonCache, AnIdFreedWhileStoppedIsNotTakenByAFileThatHadItsOwn) {
  const std::vector<std::string> names{"a b.glb", "a#b.glb", "a+b.glb"};
  for (const auto& name : names) rdtf::testing::write_file(watch_ / name, fixture("arm3.glb"));
  start_full();
  std::map<std::string, std::string> before;
  for (const auto& name : names) before[name] = id_of(name);
  std::string freed;
  for (const auto& [name, id] : before) {
    if (id == "a_b.glb_2") freed = name;
  }
  ASSERT_FALSE(freed.empty());
  daemon_.reset();
  fs::remove(watch_ / freed);
  restart();
  for (const auto& [name, id] : before) {
    if (name == freed) continue;
    EXPECT_EQ(id_of(name), id) << name;
  }
  daemon_.reset();
  rdtf::testing::write_file(watch_ / "a(b.glb", fixture("arm3.glb"));  // new to the folder
  restart();
  for (const auto& [name, id] : before) {
    if (name == freed) continue;
    EXPECT_EQ(id_of(name), id) << name;
  }
  EXPECT_EQ(id_of("a(b.glb"), "a_b.glb_2");
}

// Many alike names (more than the 8 ids the search once looked at): after two of their files are
// deleted and two new ones added while rdtfd is stopped, every untouched file keeps its id and the
// new ones take the two freed (s100rev D3: with 110 files, 8 untouched files moved).
TEST_F(DaemonCache, ManyAlikeNamesKeepTheirIdsWhenSomeAreReplacedWhileStopped) {
  const std::string box = rdtf::testing::read_file(rdtf::testing::data_dir() / "khronos" / "Box.gltf");
  const std::string others = "_ #+!";
  std::vector<std::string> names;
  for (const char a : others) {
    for (const char b : others) names.push_back(std::string("bx") + a + "b" + b + "x.gltf");  // "bx_b_x.gltf"
  }
  for (const auto& name : names) rdtf::testing::write_file(watch_ / name, box);
  start_full();
  std::map<std::string, std::string> before;
  for (const auto& name : names) before[name] = id_of(name);
  std::set<std::string> freed_ids{"bx_b_x.gltf_5", "bx_b_x.gltf_20"};
  std::vector<std::string> gone;
  for (const auto& [name, id] : before) {
    if (freed_ids.count(id) != 0) gone.push_back(name);
  }
  ASSERT_EQ(gone.size(), 2u);
  daemon_.reset();
  for (const auto& name : gone) fs::remove(watch_ / name);
  const std::vector<std::string> added{"bx(b(x.gltf", "bx)b)x.gltf"};
  for (const auto& name : added) rdtf::testing::write_file(watch_ / name, box);
  restart();
  for (const auto& [name, id] : before) {
    if (std::find(gone.begin(), gone.end(), name) != gone.end()) continue;
    EXPECT_EQ(id_of(name), id) << name;
  }
  EXPECT_EQ((std::set<std::string>{id_of(added[0]), id_of(added[1])}), freed_ids);
}

}  // namespace
}  // namespace rdtf::daemon
