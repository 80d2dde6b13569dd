// rdtfd killed with SIGKILL at random moments while it converts: no output is ever partial, no
// temporary file outlives the next start, and after the last restart every model is converted and
// published again.
//
// Each cycle edits some models (their .bin sizes change, so a stale .gltf beside a new .bin would
// show), starts the daemon (which converts every model at start), waits a random time within what
// a start takes to publish every model (the median of three measured starts) and kills it. After
// each kill every output is checked: each .rdtf.gltf loads through our own loader (which also
// checks each .bin has the byteLength its JSON says), each robot.urdf parses with urdfdom and
// every mesh it names is there, whole (a binary STL of 84 + 50 n bytes that our STL reader takes)
// and its own (its volume is its link's mass at the density), every content-addressed file holds
// the content its name says; the only temporary files are the killed process's, and the next
// start removes them. After the last run each folder holds exactly the content-addressed files of
// its output and of the one before (docs/daemon.md, "Outputs").
//
// The number of kills: RDTF_CRASH_KILLS, else 1000 (200 under the sanitizers). The random moments
// come from a fixed seed (printed), RDTF_CRASH_SEED overrides it.
#include <algorithm>
#include <iostream>
#include <random>
#include <regex>
#include <set>

#include <urdf_parser/urdf_parser.h>

#include "daemon/harness.h"
#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/mass_properties.h"
#include "rdtf/urdf.h"

namespace rdtf::itest {
namespace {

constexpr int kModels = 8;

int env_int(const char* name, int fallback) {
  const char* value = std::getenv(name);
  return value != nullptr && *value != '\0' ? std::atoi(value) : fallback;
}

// Model `index` at `version`: a chain of boxes whose .bin grows with the version (padding after
// the mesh data, counted in byteLength), every other model with its buffer embedded instead.
GeneratedModel versioned_model(int index, int version) {
  const std::string name = "m" + std::to_string(index) + "_v" + std::to_string(version);
  const bool external = index % 2 == 0;
  GeneratedModel model = box_model(name, 0.05 + 0.01 * (version % 7), 1 + index % 3,
                                   external ? "m" + std::to_string(index) + ".bin" : "");
  if (external) {
    model.bin.append(static_cast<std::size_t>(4 * (version % 13)), '\0');
    Json document = Json::parse(model.gltf);
    document["buffers"][0]["byteLength"] = model.bin.size();
    model.gltf = document.dump(1);
  }
  return model;
}

std::string model_file(int index) { return "m" + std::to_string(index) + ".gltf"; }

const std::regex& temporary_name() {
  static const std::regex pattern(R"(\..+\.([0-9]+)-[0-9]+\.tmp)");
  return pattern;
}

// Every entry below `folder`, but none inside a temporary folder (a stage folder of outputs being
// written, docs/daemon.md "Outputs": what it holds is no output until moved out of it).
std::vector<fs::directory_entry> entries_below(const fs::path& folder) {
  std::vector<fs::directory_entry> entries;
  for (auto it = fs::recursive_directory_iterator(folder); it != fs::recursive_directory_iterator(); ++it) {
    entries.push_back(*it);
    if (it->is_directory() && std::regex_match(it->path().filename().string(), temporary_name())) {
      it.disable_recursion_pending();
    }
  }
  return entries;
}

// Temporary files (and stage folders) below `folder`, with the pid in their name.
std::vector<std::pair<fs::path, long>> temporaries(const fs::path& folder) {
  std::vector<std::pair<fs::path, long>> found;
  for (const auto& entry : entries_below(folder)) {
    std::smatch match;
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, match, temporary_name())) found.emplace_back(entry.path(), std::stol(match[1].str()));
  }
  return found;
}

bool is_gltf_output(const std::string& name) {
  return name.size() > 10 && name.compare(name.size() - 10, 10, ".rdtf.gltf") == 0;
}

// "<stem>.<16 hex digits>[.<ext>]": the digits, or "" for any other name.
std::string name_digest(const std::string& name) {
  static const std::regex pattern(R"(.+\.([0-9a-f]{16})(\.[^.]+)?)");
  std::smatch match;
  return std::regex_match(name, match, pattern) ? match[1].str() : "";
}

// The mesh files a URDF names, as paths below its folder.
std::vector<fs::path> urdf_meshes(const fs::path& urdf, const urdf::ModelInterface& model) {
  std::vector<fs::path> meshes;
  for (const auto& [name, link] : model.links_) {
    std::vector<urdf::GeometrySharedPtr> geometries;
    for (const auto& visual : link->visual_array) geometries.push_back(visual->geometry);
    for (const auto& collision : link->collision_array) geometries.push_back(collision->geometry);
    for (const auto& geometry : geometries) {
      if (geometry && geometry->type == urdf::Geometry::MESH) {
        meshes.push_back(urdf.parent_path() / static_cast<const urdf::Mesh&>(*geometry).filename);
      }
    }
  }
  return meshes;
}

// The files an output (.rdtf.gltf or robot.urdf) refers to; nothing when it cannot be read.
std::vector<fs::path> files_named_by(const fs::path& primary) {
  std::vector<fs::path> files;
  if (primary.filename() == "robot.urdf") {
    if (const auto model = urdf::parseURDF(read(primary))) files = urdf_meshes(primary, *model);
    return files;
  }
  const Json document = Json::parse(read(primary), nullptr, false);
  if (!document.is_object() || !document.contains("buffers")) return files;
  for (const auto& buffer : document["buffers"]) {
    const std::string uri = buffer.value("uri", "");
    if (!uri.empty() && uri.rfind("data:", 0) != 0) files.push_back(primary.parent_path() / uri);
  }
  return files;
}

void expect_whole_gltf(const fs::path& path) {
  Diagnostics diag;
  const auto asset = rdtf::load_gltf(path, LoadLimits{}, diag);
  std::string problems;
  for (const auto& d : diag.all()) problems += format(d) + "\n";
  EXPECT_TRUE(asset.has_value()) << path << " does not load:\n" << problems;
  if (!asset) return;
  EXPECT_TRUE(asset->document.contains("extras") && asset->document["extras"].contains("RDTF")) << path;
  // Each external buffer has exactly the size the JSON says (the loader checks it too).
  for (const auto& buffer : asset->document["buffers"]) {
    const std::string uri = buffer.value("uri", "");
    if (uri.empty() || uri.rfind("data:", 0) == 0) continue;
    EXPECT_EQ(fs::file_size(path.parent_path() / uri), buffer["byteLength"].get<std::uint64_t>()) << uri;
  }
}

// A binary STL: 80 bytes of header, a triangle count n, then 50 bytes per triangle; nothing when
// the file is not whole (after a failed expectation).
std::optional<TriangleMesh> whole_stl(const fs::path& path) {
  EXPECT_TRUE(fs::is_regular_file(path)) << path << " is named by its URDF but missing";
  const std::string bytes = fs::is_regular_file(path) ? read(path) : "";
  if (bytes.size() < 84) {
    ADD_FAILURE() << path << ": " << bytes.size() << " bytes, no STL";
    return std::nullopt;
  }
  std::uint32_t triangles = 0;
  for (int i = 3; i >= 0; --i) triangles = triangles << 8 | static_cast<unsigned char>(bytes[80 + i]);
  EXPECT_EQ(bytes.size(), 84 + 50 * std::size_t{triangles}) << path;
  std::string why;
  auto mesh = parse_stl(std::vector<std::uint8_t>(bytes.begin(), bytes.end()), why);
  EXPECT_TRUE(mesh) << path << ": " << why;
  if (mesh) {
    EXPECT_EQ(mesh->triangles.size(), triangles) << path;
  }
  return mesh;
}

// Each link's mesh is the one its URDF was written with: its volume at the default density
// (1000 kg/m^3) is the link's mass, to float32 precision (STL stores float32). Every version of a
// model has boxes of another size, so a mesh of another revision shows.
void expect_whole_urdf(const fs::path& path) {
  const auto model = urdf::parseURDF(read(path));
  ASSERT_TRUE(model != nullptr) << path << " does not parse";
  EXPECT_FALSE(urdf_meshes(path, *model).empty()) << path;
  for (const auto& [name, link] : model->links_) {
    for (const auto& visual : link->visual_array) {
      if (!visual->geometry || visual->geometry->type != urdf::Geometry::MESH) continue;
      const auto file = path.parent_path() / static_cast<const urdf::Mesh&>(*visual->geometry).filename;
      const auto mesh = whole_stl(file);
      if (!mesh || !link->inertial) continue;
      const double volume =
          integrate_solid(std::span<const TriangleMesh>(&*mesh, 1), Eigen::Affine3d::Identity()).volume;
      EXPECT_NEAR(1000 * volume, link->inertial->mass, 1e-6 * link->inertial->mass)
          << file << " is not the mesh of link '" << name << "' in " << path;
    }
  }
}

// Every finished output below `output` is whole. Returns how many outputs were checked.
int expect_whole_outputs(const fs::path& output) {
  int checked = 0;
  for (const auto& entry : entries_below(output)) {
    if (!entry.is_regular_file()) continue;
    const fs::path& path = entry.path();
    const std::string name = path.filename().string();
    if (std::regex_match(name, temporary_name())) continue;
    if (const std::string digest = name_digest(name); !digest.empty()) {
      // Named after its content, and holding it: no one ever finds other bytes under that name.
      EXPECT_EQ(sha256_plain(read(path)).substr(0, 16), digest) << path;
    } else if (is_gltf_output(name)) {
      expect_whole_gltf(path);
      ++checked;
    } else if (name == "robot.urdf") {
      expect_whole_urdf(path);
      ++checked;
    }
  }
  return checked;
}

// Every file an output below `output` refers to, and every content-addressed file there.
std::set<fs::path> files_referenced_below(const fs::path& output) {
  std::set<fs::path> files;
  for (const auto& entry : entries_below(output)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || (!is_gltf_output(name) && name != "robot.urdf")) continue;
    for (const auto& file : files_named_by(entry.path())) files.insert(file.lexically_normal());
  }
  return files;
}

std::set<fs::path> content_addressed_below(const fs::path& output) {
  std::set<fs::path> files;
  for (const auto& entry : entries_below(output)) {
    if (entry.is_regular_file() && !name_digest(entry.path().filename().string()).empty()) {
      files.insert(entry.path().lexically_normal());
    }
  }
  return files;
}

// Whether a write was cut between renaming secondary files and renaming their output: a
// content-addressed file beside an output (a .rdtf.gltf's folder, a robot.urdf's meshes/) that it
// does not refer to and that was renamed into place after it and after `since`. (The generation
// before, also not referred to, is older than the output.)
bool cut_between_files_and_output(const fs::path& output, fs::file_time_type since) {
  for (const auto& entry : entries_below(output)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || (!is_gltf_output(name) && name != "robot.urdf")) continue;
    const auto referenced = files_named_by(entry.path());
    const fs::path folder = is_gltf_output(name) ? entry.path().parent_path() : entry.path().parent_path() / "meshes";
    if (!fs::is_directory(folder)) continue;
    for (const auto& file : fs::directory_iterator(folder)) {
      if (name_digest(file.path().filename().string()).empty() ||
          std::find(referenced.begin(), referenced.end(), file.path()) != referenced.end()) {
        continue;
      }
      if (file.last_write_time() > entry.last_write_time() && file.last_write_time() >= since) return true;
    }
  }
  return false;
}

// The last description of each model names files that are on disk, with the text published.
void expect_descriptions_match_the_files(const std::vector<Message>& messages) {
  for (int i = 0; i < kModels; ++i) {
    const auto d = last_description(messages, model_file(i));
    ASSERT_TRUE(d) << model_file(i);
    EXPECT_EQ(read(d->output_path), d->rdtf_json) << d->output_path;
    ASSERT_FALSE(d->urdf_path.empty()) << model_file(i);
    EXPECT_EQ(read(d->urdf_path), d->urdf) << d->urdf_path;
    for (const auto& filename : urdf_mesh_filenames(d->urdf)) whole_stl(fs::path(d->urdf_path).parent_path() / filename);
  }
}

// Whether a STATUS from `pid` is among the messages from `from` on, which then moves to the end.
// (Looked up in place: a copy of every message so far, a thousand times, would dominate the run.)
bool sent_status(Session& s, long pid, std::size_t& from) {
  bool sent = false;
  s.wait_for([&](const std::vector<Message>& all) {
    for (; from < all.size(); ++from) {
      if (all[from].kind() == "STATUS") sent |= all[from].as<rdtf::status_t>().pid == pid;
    }
    return true;
  });
  return sent;
}

// How many models have a DESCRIPTION among `all` from `from` on.
std::size_t published_models(const std::vector<Message>& all, std::size_t from) {
  std::set<std::string> models;
  for (std::size_t i = from; i < all.size(); ++i) {
    if (all[i].kind() == "DESCRIPTION") models.insert(all[i].model_id());
  }
  return models.size();
}

// The median of three starts (the first one cold) from spawning the daemon until it has published
// every model; each is killed once idle. `daemon` is left started once, and killed.
void measure_time_to_publish_everything(Session& s, const DaemonOptions& options, std::unique_ptr<DaemonProcess>& daemon,
                                        std::chrono::microseconds& span) {
  std::vector<std::chrono::microseconds> spans;
  for (int run = 0; run < 3; ++run) {
    const std::size_t from = s.subscriber.size();
    const auto start = Clock::now();
    if (!daemon) {
      daemon = std::make_unique<DaemonProcess>(options);
    } else {
      daemon->restart();
    }
    ASSERT_TRUE(s.wait_for([&](const auto& all) { return published_models(all, from) == kModels; }, 30s))
        << daemon->log();
    spans.push_back(std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start));
    daemon->signal(SIGKILL);
    ASSERT_EQ(daemon->wait_exit(5s), 128 + SIGKILL);
  }
  std::sort(spans.begin(), spans.end());
  span = spans[1];
}

void kill_at_random_moments(int kills, unsigned seed) {
  std::cout << "kills: " << kills << ", seed: " << seed << std::endl;
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> which(0, kModels - 1);
  Session s;
  std::vector<int> version(kModels, 0);
  for (int i = 0; i < kModels; ++i) write_model(s.watch, model_file(i), versioned_model(i, 0));

  // The kills fall anywhere in the time a start takes to publish every model (a start converts
  // them all). A fixed span would fall before the first write on a slower build: under the
  // sanitizers the daemon's start alone takes longer than 40 ms.
  DaemonOptions options = DaemonOptions().with_settle(10).with("urdf", true).with_watch({s.watch}).with_output(s.output);
  std::unique_ptr<DaemonProcess> daemon;
  std::chrono::microseconds span{};
  measure_time_to_publish_everything(s, options, daemon, span);
  if (::testing::Test::HasFatalFailure()) return;
  auto delay_us = std::uniform_int_distribution<std::int64_t>(0, span.count());
  std::cout << "kill moments: 0 to " << span.count() / 1000.0 << " ms after a start (the time a start takes to "
            << "publish every model)" << std::endl;

  int killed_mid_write = 0;       // Kills that left a temporary file of the killed process.
  int killed_between_files = 0;   // Kills after some secondary files of an output and before it.
  int outputs_checked = 0;
  // Processes whose temporary files may still be there: a start removes the files of every
  // earlier process before its first heartbeat, so a process seen to send STATUS leaves only its own.
  // (Those of the measuring starts were killed idle.)
  std::set<long> uncleaned{daemon->last_pid()};
  std::size_t statuses_seen = 0;  // Messages already looked through for heartbeats.
  // A long run goes on past `kills` (up to three times as many) until a kill has landed between an
  // output's files: that window is about 1% of a start, less on a loaded machine (0 of 1,000 once
  // with the whole suite running beside it), and the check below would otherwise fail on chance.
  // Likewise until one landed mid-write: about 12% of the kills on a quiet machine (25 of 200
  // under ASan), fewer when the span was measured while another test held the cores.
  // Still short after `kills`, the span is measured again (at most twice): it is the time a start
  // takes now, and a test beside this one in `ctest -j2` may have slowed the starts since, so
  // that the kills fell before the writes (0 between files of 2,000 once, with 46 mid-write where
  // a run alone has 150 to 200 of 1,000).
  int made = 0;
  const auto short_of_a_landing = [&] {
    return (kills >= 1000 && killed_between_files == 0) || (kills >= 100 && killed_mid_write == 0);
  };
  for (int k = 0; k < kills || (short_of_a_landing() && k < 3 * kills); ++k) {
    if (k > 0 && k % kills == 0 && short_of_a_landing()) {
      measure_time_to_publish_everything(s, options, daemon, span);
      if (::testing::Test::HasFatalFailure()) return;
      delay_us = std::uniform_int_distribution<std::int64_t>(0, span.count());
      uncleaned = {daemon->last_pid()};
      std::cout << "after " << k << " kills, kill moments measured again: 0 to " << span.count() / 1000.0 << " ms"
                << std::endl;
    }
    made = k + 1;
    SCOPED_TRACE("kill " + std::to_string(k + 1));
    // Edit two models: the start converts everything anyway, these get new sizes too.
    for (int e = 0; e < 2; ++e) {
      const int i = which(random);
      write_model(s.watch, model_file(i), versioned_model(i, ++version[i]));
    }
    const auto started = fs::file_time_type::clock::now();
    daemon->restart();
    // The random moment: anywhere from before the first conversion to after the last output.
    std::this_thread::sleep_for(std::chrono::microseconds(delay_us(random)));
    daemon->signal(SIGKILL);
    ASSERT_EQ(daemon->wait_exit(5s), 128 + SIGKILL);
    const long pid = daemon->last_pid();
    if (sent_status(s, pid, statuses_seen)) uncleaned.clear();
    uncleaned.insert(pid);
    // A temporary file of the killed process shows it died mid-write.
    bool mid_write = false;
    for (const auto& [path, writer] : temporaries(s.output)) {
      mid_write |= writer == pid;
      EXPECT_TRUE(uncleaned.count(writer) > 0) << path << " outlived a restart";
    }
    killed_mid_write += mid_write;
    killed_between_files += cut_between_files_and_output(s.output, started);
    outputs_checked += expect_whole_outputs(s.output);
    if (::testing::Test::HasFailure()) {
      std::cerr << daemon->log();
      return;
    }
  }
  std::cout << "of " << made << " kills, " << killed_mid_write
            << " landed mid-write (a temporary file of the killed process left), " << killed_between_files
            << " between an output's secondary files and its primary file (new content-addressed files beside an "
            << "older output); outputs checked: " << outputs_checked << std::endl;
  // A long run whose kills never cut a write would have tested nothing.
  if (kills >= 100) {
    EXPECT_GT(killed_mid_write, 0);
  }
  // Outputs are staged: only the renames out of the stage are left between an output's files and
  // its primary file, about 2% of the kills (18 of 1,000 measured), too few to expect in 200.
  if (kills >= 1000) {
    EXPECT_GT(killed_between_files, 0);
  }

  // The last start: temporaries gone, every model converted and published again. What the outputs
  // on disk refer to now is what the start keeps; each model's one conversion then keeps it as the
  // generation before its own.
  daemon.reset();
  const auto kept_at_start = files_referenced_below(s.output);
  const std::size_t before = s.subscriber.size();  // Earlier runs published these models too.
  s.start(options);
  for (int i = 0; i < kModels; ++i) {
    const auto hash = content_hash(versioned_model(i, version[i]));
    EXPECT_TRUE(s.wait_for([&](const std::vector<Message>& all) {
      for (std::size_t m = before; m < all.size(); ++m) {
        if (all[m].kind() == "DESCRIPTION" && all[m].model_id() == model_file(i) &&
            all[m].as<rdtf::description_t>().content_hash == hash) {
          return true;
        }
      }
      return false;
    }, 10s)) << model_file(i);
  }
  // Revision numbers last across the kills (docs/lcm.md): over every run, no number of a model
  // was ever published with two contents.
  std::map<std::pair<std::string, std::int64_t>, std::set<std::string>> contents;
  for (const auto& d : decoded<rdtf::description_t>(s.messages(), "DESCRIPTION")) {
    contents[{d.model_id, d.revision}].insert(d.content_hash);
  }
  for (const auto& [number, hashes] : contents) {
    EXPECT_EQ(hashes.size(), 1u) << number.first << " revision " << number.second << " stood for " << hashes.size()
                                 << " contents";
  }
  ASSERT_TRUE(s.wait_idle());
  ASSERT_EQ(s.daemon->stop(), 0);
  EXPECT_TRUE(temporaries(s.output).empty());
  EXPECT_EQ(expect_whole_outputs(s.output), 2 * kModels);
  std::set<fs::path> expected = files_referenced_below(s.output);
  expected.insert(kept_at_start.begin(), kept_at_start.end());
  EXPECT_EQ(content_addressed_below(s.output), expected);
  expect_descriptions_match_the_files(s.messages());
  for (int i = 0; i < kModels; ++i) {
    // The output is the last version's: its base node carries the version in its name.
    const std::string base = "m" + std::to_string(i) + "_v" + std::to_string(version[i]);
    const auto text = read(s.output / model_file(i) / ("m" + std::to_string(i) + ".rdtf.gltf"));
    EXPECT_NE(text.find("\"" + base + "\""), std::string::npos) << base;
  }
}

// What a killed write leaves besides temporary files: content-addressed files whose output was
// never renamed into place. A start removes exactly those, in every folder of the output.
TEST(DaemonCrash, StartRemovesContentAddressedFilesNoOutputRefersTo) {
  Session s;
  const fs::path model = s.output / "gone.gltf";  // The output of a model no longer watched.
  fs::create_directories(model / "urdf" / "meshes");
  fs::create_directories(s.output / "never.gltf");
  Json document = Json::parse(box_model("gone_base", 0.1, 1, "gone.1111111111111111.bin").gltf);
  write_in_place(model / "gone.rdtf.gltf", document.dump());
  write_in_place(model / "gone.1111111111111111.bin", "referenced");
  write_in_place(model / "gone.2222222222222222.bin", "left by a killed write");
  write_in_place(model / "gone.bin", "not content-addressed");
  write_in_place(model / "urdf" / "robot.urdf",
                 R"(<robot name="gone"><link name="base"><visual><geometry>)"
                 R"(<mesh filename="meshes/base.3333333333333333.stl"/></geometry></visual></link></robot>)");
  write_in_place(model / "urdf" / "meshes" / "base.3333333333333333.stl", "referenced");
  write_in_place(model / "urdf" / "meshes" / "base.4444444444444444.stl", "left by a killed write");
  write_in_place(s.output / "never.gltf" / "never.5555555555555555.bin", "left before any output");
  // A link is nothing of ours: neither it nor what it points to goes.
  write_in_place(s.root / "precious", "not the daemon's");
  fs::create_symlink(s.root / "precious", model / "gone.6666666666666666.bin");

  s.start();  // The first heartbeat comes after the cleanup.
  std::set<fs::path> left;
  for (const auto& entry : fs::recursive_directory_iterator(s.output)) {
    const auto relative = entry.path().lexically_relative(s.output);
    // The daemon's own state (its boot, docs/daemon.md "Revision state") is no output.
    if (!entry.is_directory() && *relative.begin() != ".rdtfd-state") left.insert(relative);
  }
  EXPECT_EQ(left, (std::set<fs::path>{"gone.gltf/gone.rdtf.gltf", "gone.gltf/gone.1111111111111111.bin",
                                      "gone.gltf/gone.bin", "gone.gltf/gone.6666666666666666.bin",
                                      "gone.gltf/urdf/robot.urdf", "gone.gltf/urdf/meshes/base.3333333333333333.stl"}));
  EXPECT_EQ(read(s.root / "precious"), "not the daemon's");
  EXPECT_TRUE(s.daemon->wait_log("removed 3 files no output refers to from ")) << s.daemon->log();
}

// 1,000 kills take about a minute; under the sanitizers (RDTF_TEST_DEADLINE_SCALE 5) a start takes
// about 4 times as long and 1,000 kills about 4 minutes, so that build kills 200 times: as many
// restarts for ASan and UBSan to watch as it needs, in a CI run that must stay well inside its limit.
TEST(DaemonCrash, KilledAtRandomMomentsNeverLeavesAPartialOutput) {
  kill_at_random_moments(env_int("RDTF_CRASH_KILLS", 1000 / RDTF_TEST_DEADLINE_SCALE),
                         static_cast<unsigned>(env_int("RDTF_CRASH_SEED", 6)));
}

}  // namespace
}  // namespace rdtf::itest
