// The result cache's store (daemon/result_cache.h): an entry reads back bit for bit, any torn or
// altered entry is refused, lookups match model, key and content, the least recently used go
// beyond the bound, and the key follows exactly the settings that change results.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/stat.h>

#include "conversion.h"
#include "result_cache.h"
#include "revision_store.h"
#include "support/test_support.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;

struct Converted {
  rdtf::testing::TempDir tmp;
  ConversionJob job;
  ConversionOutcome outcome;
};

// arm3 through the whole pipeline (the gate, the URDF) with a cache in the temporary folder.
std::unique_ptr<Converted> convert_arm3(const std::string& name = "arm3.glb") {
  auto c = std::make_unique<Converted>();
  fs::create_directories(c->tmp / "watch");
  const fs::path root = fs::canonical(c->tmp / "watch");
  rdtf::testing::write_file(root / name,
                            rdtf::testing::read_file(rdtf::testing::data_dir() / "blender" / "arm3.glb"));
  c->job.model_id = "arm3.glb";
  c->job.root = root;
  c->job.source = root / name;
  c->job.output_dir = c->tmp / "out" / "arm3.glb";
  c->job.validation = ValidationOptions{};
  c->job.urdf = UrdfOptions{};
  c->job.cache = std::make_shared<ResultCache>(ResultCache::folder_for(c->tmp / "out"), 10);
  c->job.cache_key = "key";
  c->outcome = run_conversion(c->job);
  // The entry is written after the hand-over (what a worker does once the loop has the outcome).
  EXPECT_EQ(c->job.cache->entries(), 0u);
  EXPECT_TRUE(static_cast<bool>(c->outcome.after_handover));
  if (c->outcome.after_handover) c->outcome.after_handover();
  return c;
}

std::vector<std::string> formatted(const Diagnostics& diagnostics) {
  std::vector<std::string> out;
  for (const Diagnostic& d : diagnostics.all()) out.push_back(format(d));
  return out;
}

void expect_same_robot(const Robot& a, const Robot& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.root_links, b.root_links);
  ASSERT_EQ(a.links.size(), b.links.size());
  for (std::size_t i = 0; i < a.links.size(); ++i) {
    const Link &x = a.links[i], &y = b.links[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.node, y.node);
    EXPECT_EQ(x.parent_joint, y.parent_joint);
    EXPECT_EQ(x.child_joints, y.child_joints);
    EXPECT_EQ(x.X_SL.matrix(), y.X_SL.matrix());  // Exactly: the same doubles.
    ASSERT_EQ(x.meshes.size(), y.meshes.size());
    for (std::size_t m = 0; m < x.meshes.size(); ++m) {
      EXPECT_EQ(x.meshes[m].node, y.meshes[m].node);
      EXPECT_EQ(x.meshes[m].volume, y.meshes[m].volume);
      EXPECT_EQ(x.meshes[m].density, y.meshes[m].density);
    }
    EXPECT_EQ(x.inertial.volume, y.inertial.volume);
    EXPECT_EQ(x.inertial.mass, y.inertial.mass);
    EXPECT_EQ(x.inertial.center_of_mass, y.inertial.center_of_mass);
    EXPECT_EQ(x.inertial.inertia, y.inertial.inertia);
    EXPECT_EQ(x.inertial_source, y.inertial_source);
    EXPECT_EQ(x.inertial_node, y.inertial_node);
    EXPECT_EQ(x.ignored_inertial_extras, y.ignored_inertial_extras);
  }
  ASSERT_EQ(a.joints.size(), b.joints.size());
  for (std::size_t i = 0; i < a.joints.size(); ++i) {
    const Joint &x = a.joints[i], &y = b.joints[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.node, y.node);
    EXPECT_EQ(x.frame_node, y.frame_node);
    EXPECT_EQ(x.source_node, y.source_node);
    EXPECT_EQ(x.source_is_entry, y.source_is_entry);
    EXPECT_EQ(x.ignored_extras_node, y.ignored_extras_node);
    EXPECT_EQ(x.parent_link, y.parent_link);
    EXPECT_EQ(x.child_link, y.child_link);
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.X_PJ.matrix(), y.X_PJ.matrix());
    EXPECT_EQ(x.axis, y.axis);
    ASSERT_EQ(x.limits.has_value(), y.limits.has_value());
    if (x.limits) {
      EXPECT_EQ(x.limits->lower, y.limits->lower);
      EXPECT_EQ(x.limits->upper, y.limits->upper);
      EXPECT_EQ(x.limits->effort, y.limits->effort);
      EXPECT_EQ(x.limits->velocity, y.limits->velocity);
    }
    EXPECT_EQ(x.damping, y.damping);
    EXPECT_EQ(x.friction, y.friction);
    EXPECT_EQ(x.spring_stiffness, y.spring_stiffness);
  }
}

TEST(ResultCache, AConversionIsStoredAndTheNextOneIsTheCachedResultBitForBit) {
  auto c = convert_arm3();
  ASSERT_EQ(c->outcome.kind, ConversionOutcome::Kind::kConverted) << ::testing::PrintToString(formatted(c->outcome.diagnostics));
  ASSERT_FALSE(c->outcome.from_cache);
  const ConvertedModel& first = *c->outcome.converted;
  ASSERT_TRUE(first.validation && first.validation->passed);
  ASSERT_FALSE(first.urdf.empty());
  EXPECT_EQ(c->job.cache->entries(), 1u);

  const ConversionOutcome again = run_conversion(c->job);
  ASSERT_EQ(again.kind, ConversionOutcome::Kind::kConverted);
  EXPECT_TRUE(again.from_cache);
  EXPECT_EQ(again.cache_note, "");
  const ConvertedModel& cached = *again.converted;
  expect_same_robot(cached.robot, first.robot);
  EXPECT_EQ(facts_to_json(cached.facts), facts_to_json(first.facts));
  EXPECT_EQ(cached.totals.mass, first.totals.mass);
  EXPECT_EQ(cached.totals.center_of_mass_scene, first.totals.center_of_mass_scene);
  EXPECT_EQ(cached.rdtf_json, first.rdtf_json);
  EXPECT_EQ(cached.urdf, first.urdf);
  EXPECT_EQ(cached.output_path, first.output_path);
  EXPECT_EQ(cached.urdf_path, first.urdf_path);
  EXPECT_EQ(cached.files, first.files);
  EXPECT_EQ(cached.written, first.written);
  EXPECT_EQ(result_digest(cached), result_digest(first));
  ASSERT_TRUE(cached.validation);
  EXPECT_EQ(cached.validation->passed, first.validation->passed);
  EXPECT_EQ(cached.validation->steps, first.validation->steps);
  EXPECT_EQ(cached.validation->simulated_time, first.validation->simulated_time);
  EXPECT_EQ(cached.validation->energy_drift, first.validation->energy_drift);
  EXPECT_EQ(cached.validation->worst_joint_error, first.validation->worst_joint_error);
  EXPECT_EQ(cached.validation->summary_line, first.validation->summary_line);
  EXPECT_EQ(formatted(cached.validation->diagnostics), formatted(first.validation->diagnostics));
  EXPECT_EQ(cached.validation->live_stepper, first.validation->live_stepper);
  EXPECT_EQ(formatted(again.diagnostics), formatted(c->outcome.diagnostics));
}

// A model whose file name is not UTF-8 (Linux allows any bytes) finds its entry again: its name
// was written with U+FFFD in place of the byte, and every restart checked the model anew.
TEST(ResultCache, AFileNameThatIsNotUtf8FindsItsEntry) {
  auto c = convert_arm3("arm\xff.glb");
  ASSERT_EQ(c->outcome.kind, ConversionOutcome::Kind::kConverted) << ::testing::PrintToString(formatted(c->outcome.diagnostics));
  ASSERT_FALSE(c->outcome.from_cache);
  EXPECT_EQ(c->job.cache->entries(), 1u);
  const ConversionOutcome again = run_conversion(c->job);
  ASSERT_EQ(again.kind, ConversionOutcome::Kind::kConverted);
  EXPECT_TRUE(again.from_cache) << again.cache_note;
  EXPECT_EQ(again.converted->output_path, c->outcome.converted->output_path);
  EXPECT_EQ(again.converted->files, c->outcome.converted->files);
  // The diagnostics name the file as it is (they named it with U+FFFD after a restart).
  ASSERT_FALSE(again.diagnostics.all().empty());
  EXPECT_EQ(formatted(again.diagnostics), formatted(c->outcome.diagnostics));
}

// The stepper of the run that is the verdict (dWorldStep where QuickStep failed the model) comes
// back with it, so that a restart simulates the model as its check did.
TEST(ResultCache, TheVerdictsLiveStepperReadsBack) {
  auto c = convert_arm3();
  ASSERT_EQ(c->outcome.kind, ConversionOutcome::Kind::kConverted);
  std::string why;
  auto entry = cache_entry_from_text(rdtf::testing::read_file(c->job.cache->file_for(c->job.source.string())), why);
  ASSERT_TRUE(entry && entry->validation) << why;
  EXPECT_EQ(entry->validation->live_stepper, Stepper::kWorldStep);  // arm3's 2 bodies: dWorldStep by itself
  EXPECT_FALSE(entry->validation->after_quickstep_failed);
  for (const Stepper stepper : {Stepper::kQuickStep, Stepper::kWorldStep, Stepper::kAuto}) {
    for (const bool rerun : {false, true}) {
      entry->validation->live_stepper = stepper;
      entry->validation->after_quickstep_failed = rerun;
      const auto again = cache_entry_from_text(cache_entry_text(*entry), why);
      ASSERT_TRUE(again && again->validation) << why;
      EXPECT_EQ(again->validation->live_stepper, stepper);
      EXPECT_EQ(again->validation->after_quickstep_failed, rerun);
    }
  }
}

TEST(ResultCache, EveryTruncationAndEveryFlippedBitIsRefused) {
  auto c = convert_arm3();
  ASSERT_EQ(c->outcome.kind, ConversionOutcome::Kind::kConverted);
  const std::string text = rdtf::testing::read_file(c->job.cache->file_for(c->job.source.string()));
  std::string why;
  ASSERT_TRUE(cache_entry_from_text(text, why)) << why;
  for (std::size_t length = 0; length < text.size(); ++length) {
    ASSERT_FALSE(cache_entry_from_text(std::string_view(text).substr(0, length), why)) << length;
  }
  for (std::size_t at = 0; at < text.size(); ++at) {
    for (const char bit : {'\x01', '\x40'}) {
      std::string altered = text;
      altered[at] = static_cast<char>(altered[at] ^ bit);
      ASSERT_FALSE(cache_entry_from_text(altered, why)) << "byte " << at;
    }
  }
  // Appended bytes are no entry either.
  EXPECT_FALSE(cache_entry_from_text(text + " ", why));
  EXPECT_NE(why.find("checksum"), std::string::npos) << why;
}

TEST(ResultCache, OnlyTheSameModelKeyAndContentHit) {
  auto c = convert_arm3();
  ResultCache& cache = *c->job.cache;
  const std::string source = c->job.source.string(), hash = c->outcome.content_hash;
  const std::string key = cache_entry_key(c->job);  // "key" and the output folder
  CachedResult out;
  std::string why;
  EXPECT_EQ(cache.find(source, key, hash, out, why), ResultCache::Lookup::kHit);
  EXPECT_EQ(cache.find(source, "other key", hash, out, why), ResultCache::Lookup::kMiss);
  EXPECT_EQ(cache.find(source, "key", hash, out, why), ResultCache::Lookup::kMiss);  // another output folder
  EXPECT_EQ(cache.find(source, key, std::string(64, '0'), out, why), ResultCache::Lookup::kMiss);
  EXPECT_EQ(cache.find(source + "x", key, hash, out, why), ResultCache::Lookup::kMiss);
  // Another entry copied into this model's slot names another model: a miss, never its result.
  CachedResult other = out;
  other.source = source + "x";
  ASSERT_TRUE(cache.store(other, why)) << why;
  fs::copy_file(cache.file_for(other.source), cache.file_for(source), fs::copy_options::overwrite_existing);
  EXPECT_EQ(cache.find(source, key, hash, out, why), ResultCache::Lookup::kMiss);
  // A folder where an entry should be is refused, with its reason.
  fs::remove(cache.file_for(source));
  fs::create_directory(cache.file_for(source));
  EXPECT_EQ(cache.find(source, key, hash, out, why), ResultCache::Lookup::kRefused);
  EXPECT_NE(why.find(cache.file_for(source).string()), std::string::npos) << why;
}

void set_mtime(const fs::path& path, std::time_t seconds) {
  const timespec times[2] = {{seconds, 0}, {seconds, 0}};
  ASSERT_EQ(::utimensat(AT_FDCWD, path.c_str(), times, 0), 0) << path;
}

TEST(ResultCache, TheLeastRecentlyUsedGoBeyondTheBound) {
  rdtf::testing::TempDir tmp;
  ResultCache cache(tmp / "results", 3);
  EXPECT_EQ(cache.open(), 0u);  // No folder yet: nothing.
  std::string why;
  CachedResult entry;
  entry.key = "k";
  entry.content_hash = "h";
  for (int i = 0; i < 3; ++i) {
    entry.source = "/m" + std::to_string(i);
    ASSERT_TRUE(cache.store(entry, why)) << why;
    set_mtime(cache.file_for(entry.source), 1'000'000'000 + i);  // Written in order, long ago.
  }
  EXPECT_EQ(cache.entries(), 3u);
  CachedResult out;
  ASSERT_EQ(cache.find("/m0", "k", "h", out, why), ResultCache::Lookup::kHit);  // m0 used now: m1 is the oldest.
  entry.source = "/m0";
  ASSERT_TRUE(cache.store(entry, why));  // Replaces its own slot: no eviction.
  EXPECT_EQ(cache.entries(), 3u);
  entry.source = "/m3";
  ASSERT_TRUE(cache.store(entry, why));
  EXPECT_EQ(cache.entries(), 3u);
  EXPECT_EQ(cache.evicted(), 1u);
  EXPECT_FALSE(fs::exists(cache.file_for("/m1")));
  for (const char* kept : {"/m0", "/m2", "/m3"}) EXPECT_TRUE(fs::exists(cache.file_for(kept))) << kept;
  // A new daemon with a smaller bound: down to it at open, the oldest first.
  ResultCache smaller(tmp / "results", 1);
  EXPECT_EQ(smaller.open(), 2u);
  EXPECT_EQ(smaller.entries(), 1u);
  EXPECT_TRUE(fs::exists(cache.file_for("/m3")));
}

TEST(ResultCacheKey, FollowsEverySettingThatChangesResultsAndNoOther) {
  const DaemonConfig base = default_config();
  const std::string key = settings_key(base);
  EXPECT_EQ(settings_key(base), key);
  const std::vector<std::pair<const char*, std::function<void(DaemonConfig&)>>> changing = {
      {"default_density", [](DaemonConfig& c) { c.convert.default_density = 500; }},
      {"max_triangles", [](DaemonConfig& c) { c.convert.limits.max_triangles = 10; }},
      {"validate", [](DaemonConfig& c) { c.validate = false; }},
      {"validation_seconds", [](DaemonConfig& c) { c.validation_seconds = 1; }},
      {"time_step", [](DaemonConfig& c) { c.time_step = 2e-3; }},
      {"gravity", [](DaemonConfig& c) { c.gravity = {0, 0, -9.80665}; }},
      {"energy_tolerance", [](DaemonConfig& c) { c.energy_tolerance = 0.02; }},
      {"publish_failed", [](DaemonConfig& c) { c.publish_failed = true; }},
      {"urdf", [](DaemonConfig& c) { c.urdf = false; }},
      {"urdf_y_up", [](DaemonConfig& c) { c.urdf_y_up = true; }},
      {"output", [](DaemonConfig& c) { c.output = "/elsewhere"; }},
  };
  for (const auto& [name, change] : changing) {
    DaemonConfig config = base;
    change(config);
    EXPECT_NE(settings_key(config), key) << name;
  }
  const std::vector<std::pair<const char*, std::function<void(DaemonConfig&)>>> neutral = {
      {"settle_ms", [](DaemonConfig& c) { c.settle = std::chrono::milliseconds(500); }},
      {"workers", [](DaemonConfig& c) { c.workers = 4; }},
      {"simulate", [](DaemonConfig& c) { c.simulate = false; }},
      {"state_rate_hz", [](DaemonConfig& c) { c.state_rate_hz = 10; }},
      {"channel_prefix", [](DaemonConfig& c) { c.channel_prefix = "X"; }},
      {"max_cached_results", [](DaemonConfig& c) { c.max_cached_results = 5; }},
  };
  for (const auto& [name, change] : neutral) {
    DaemonConfig config = base;
    change(config);
    EXPECT_EQ(settings_key(config), key) << name;
  }
}

}  // namespace
}  // namespace rdtf::daemon
