// rdtfd against a careless or hostile filesystem: models that are symlinks or hard links to files
// outside the watched folder, a watched subfolder swapped for a symlink to another folder, the
// watched folder deleted and made again, a disk that fills up between two files of an output,
// a model naming one huge sparse file many times, names too long for the output file system.
// Each must be refused or recovered from with a clear report, the live revision's files intact.
#include <sys/resource.h>
#include <sys/stat.h>

#include <iostream>
#include <set>

#include "daemon/harness.h"
#include "support/harness/fs_support.h"

namespace rdtf::itest {
namespace {

std::string diagnostics_text(const rdtf::model_error_t& error) {
  std::string text;
  for (const auto& d : error.diagnostics) text += d.code + " " + d.file + " " + d.pointer + " " + d.message + "\n";
  return text;
}

// Every message's bytes and the daemon's log, for "nothing of X anywhere".
std::string everything_said(const Session& s) {
  std::string all = s.daemon->log();
  for (const auto& m : s.messages()) all.append(m.bytes.begin(), m.bytes.end());
  return all;
}

TEST(DaemonFilesystem, ModelFilesThatAreSymlinksOrHardLinksAreRefusedWithoutShowingWhatTheyLeadTo) {
  Session s;
  const fs::path outside = s.root / "outside";
  fs::create_directories(outside);
  const auto victim = box_model("victim_base", 0.1);
  write_model(outside, "victim.gltf", victim);
  const std::string secret = "TOPSECRET-e3b0c442 line of a file that is no glTF\n";
  testing::write_file(outside / "secret.txt", secret);
  fs::create_symlink("../outside/victim.gltf", s.watch / "evil.gltf");
  fs::create_symlink(outside / "secret.txt", s.watch / "secret.gltf");
  fs::create_hard_link(outside / "victim.gltf", s.watch / "hard.gltf");
  // A buffer that is a hard link to a file outside (the model itself is an ordinary file).
  const auto linked = box_model("linked_base", 0.1, 2, "outside.bin");
  testing::write_file(outside / "outside.bin", linked.bin);
  fs::create_hard_link(outside / "outside.bin", s.watch / "outside.bin");
  write_in_place(s.watch / "linked.gltf", linked.gltf);
  // Not a glTF at all, inside the folder: its bytes must not be quoted back either.
  testing::write_file(s.watch / "notes.gltf", secret);
  const auto good = box_model("good_base", 0.1);
  write_model(s.watch, "good.gltf", good);
  s.start(DaemonOptions().in_directory("/"));

  const std::vector<std::string> refused = {"evil.gltf", "secret.gltf", "hard.gltf", "linked.gltf", "notes.gltf"};
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    for (const auto& id : refused) {
      if (on_kind(all, "ERROR", id).empty()) return false;
    }
    return has_revision(all, "good.gltf", 1, content_hash(good));
  }, 10s)) << ::testing::PrintToString(model_events(s.messages()));
  ASSERT_TRUE(s.wait_idle());

  for (const auto& id : refused) {
    SCOPED_TRACE(id);
    EXPECT_TRUE(on_kind(s.messages(), "DESCRIPTION", id).empty());
    EXPECT_FALSE(fs::exists(s.output / id));
    const auto error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", id).front();
    ASSERT_FALSE(error.diagnostics.empty());
    EXPECT_EQ(error.diagnostics[0].severity, rdtf::diagnostic_t::ERROR);
  }
  auto first = [&](const std::string& id) {
    return diagnostics_text(decoded<rdtf::model_error_t>(s.messages(), "ERROR", id).front());
  };
  EXPECT_NE(first("evil.gltf").find("symbolic link"), std::string::npos) << first("evil.gltf");
  EXPECT_NE(first("secret.gltf").find("symbolic link"), std::string::npos) << first("secret.gltf");
  EXPECT_NE(first("hard.gltf").find("hard links"), std::string::npos) << first("hard.gltf");
  EXPECT_NE(first("linked.gltf").find("/buffers/0/uri"), std::string::npos) << first("linked.gltf");
  EXPECT_NE(first("linked.gltf").find("hard links"), std::string::npos) << first("linked.gltf");
  EXPECT_NE(first("notes.gltf").find("INVALID_JSON"), std::string::npos) << first("notes.gltf");

  // Neither the secret's bytes nor where the links lead, in any message or log line.
  const std::string said = everything_said(s);
  for (const std::string& needle : {std::string("TOPSECRET"), std::string("victim"), outside.string(),
                                    std::string("../outside")}) {
    EXPECT_EQ(said.find(needle), std::string::npos) << "'" << needle << "' was said";
  }
  EXPECT_TRUE(s.daemon->running());
}

TEST(DaemonFilesystem, AWatchedSubfolderSwappedForASymlinkToAnOutsideFolderIsARemoval) {
  Session s;
  fs::create_directories(s.watch / "sub");
  const auto inside = box_model("inside_base", 0.1, 2, "arm.bin");
  write_model(s.watch / "sub", "arm.gltf", inside);
  // The outside folder holds a model of the same name, with a .bin of its own.
  const fs::path outside = s.root / "outside";
  fs::create_directories(outside);
  const auto other = box_model("outside_base", 0.15, 3, "arm.bin");
  write_model(outside, "arm.gltf", other);
  s.start();
  ASSERT_TRUE(s.wait_revision("sub/arm.gltf", 1, content_hash(inside)));

  fs::remove_all(s.watch / "sub");
  fs::create_directory_symlink(outside, s.watch / "sub");
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "REMOVED", "sub/arm.gltf").empty(); }))
      << ::testing::PrintToString(model_events(s.messages()));
  // A save in the outside folder, seen or not, changes nothing either.
  write_model(outside, "arm.gltf", box_model("outside_again", 0.16, 3, "arm.bin"));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->num_models, 0);
  EXPECT_EQ(model_events(s.messages(), "sub/arm.gltf"),
            concat({revision_events("sub/arm.gltf", 1, content_hash(inside)), {"sub/arm.gltf REMOVED last=1"}}));
  // No byte of the outside folder's .bin was copied into the outputs.
  for (const auto& entry : fs::recursive_directory_iterator(s.output)) {
    if (entry.is_regular_file()) {
      EXPECT_NE(read(entry.path()), other.bin) << entry.path();
    }
  }
  EXPECT_EQ(everything_said(s).find("outside_base"), std::string::npos);
}

// A .bin named through a symlink inside the watched folder (allowed: it stays inside) is saved at
// its target, which is the path inotify reports: an edit there is a new revision of every model
// that reads it, whether it names the target, a link to it, or a linked folder.
TEST(DaemonFilesystem, ABinReadThroughASymlinkIsWatchedAtItsTarget) {
  Session s;
  fs::create_directories(s.watch / "meshes");
  const auto direct = box_model("direct_base", 0.1, 2, "meshes/box.bin");
  const auto by_link = box_model("link_base", 0.1, 2, "current.bin");
  const auto by_folder = box_model("folder_base", 0.1, 2, "lnk/box.bin");
  ASSERT_EQ(direct.bin, by_link.bin);
  ASSERT_EQ(direct.bin, by_folder.bin);
  write_model(s.watch, "direct.gltf", direct);
  write_in_place(s.watch / "link.gltf", by_link.gltf);
  write_in_place(s.watch / "folder.gltf", by_folder.gltf);
  fs::create_symlink("meshes/box.bin", s.watch / "current.bin");
  fs::create_directory_symlink("meshes", s.watch / "lnk");
  s.start();
  ASSERT_TRUE(s.wait_revision("direct.gltf", 1, content_hash(direct)));
  ASSERT_TRUE(s.wait_revision("link.gltf", 1, content_hash(by_link)));
  ASSERT_TRUE(s.wait_revision("folder.gltf", 1, content_hash(by_folder)));

  // The boxes shrink inside the accessors' declared bounds: the same accessors, other bytes.
  const std::string grown = box_model("direct_base", 0.08, 2, "meshes/box.bin").bin;
  ASSERT_EQ(grown.size(), direct.bin.size());
  ASSERT_NE(grown, direct.bin);
  write_in_place(s.watch / "meshes" / "box.bin", grown);
  for (auto [id, model] : {std::pair{"direct.gltf", direct}, std::pair{"link.gltf", by_link}, std::pair{"folder.gltf", by_folder}}) {
    model.bin = grown;
    EXPECT_TRUE(s.wait_revision(id, 2, content_hash(model))) << id << ": "
        << ::testing::PrintToString(model_events(s.messages(), id));
  }
}

// Hidden folders hold no models: a .git, and a folder named like rdtfd's own state folder, whose
// model would have had its outputs written over rdtfd's clean-stop mark.
TEST(DaemonFilesystem, ModelsInHiddenFoldersAreNotConverted) {
  Session s;
  fs::create_directories(s.watch / ".rdtfd-state" / "clean-stop");
  fs::create_directories(s.watch / "sub" / ".git");
  const auto shown = box_model("shown_base", 0.1);
  write_model(s.watch / "sub", "arm.gltf", shown);
  write_model(s.watch / ".rdtfd-state" / "clean-stop", "x.gltf", box_model("hidden_base", 0.1));
  s.start();
  ASSERT_TRUE(s.wait_revision("sub/arm.gltf", 1, content_hash(shown)));
  // Made while running, in a hidden folder made while running too.
  write_model(s.watch / "sub" / ".git", "y.gltf", box_model("git_base", 0.1));
  fs::create_directories(s.watch / ".later");
  write_model(s.watch / ".later", "z.gltf", box_model("later_base", 0.1));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->num_models, 1);
  const std::string said = everything_said(s);
  for (const char* name : {"hidden_base", "git_base", "later_base", "x.gltf", "y.gltf", "z.gltf"}) {
    EXPECT_EQ(said.find(name), std::string::npos) << name;
  }
  // rdtfd's own state is untouched: a clean stop is marked as one.
  s.daemon->stop();
  EXPECT_TRUE(fs::is_regular_file(s.output / ".rdtfd-state" / "clean-stop"));
}

TEST(DaemonFilesystem, AWatchedFolderDeletedAndMadeAgainIsWatchedAgain) {
  Session s;
  fs::create_directories(s.watch / "sub");
  const auto a = box_model("a_base", 0.1);
  const auto b = box_model("b_base", 0.1, 2, "b.bin");
  write_model(s.watch, "a.gltf", a);
  write_model(s.watch / "sub", "b.gltf", b);
  s.start();
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_revision("sub/b.gltf", 1, content_hash(b)));

  fs::remove_all(s.watch);
  ASSERT_TRUE(s.wait_for([](const auto& all) {
    return !on_kind(all, "REMOVED", "a.gltf").empty() && !on_kind(all, "REMOVED", "sub/b.gltf").empty() &&
           !on_kind(all, "ERROR", "").empty();
  })) << ::testing::PrintToString(model_events(s.messages()));
  const auto error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "").front();
  ASSERT_FALSE(error.diagnostics.empty());
  EXPECT_EQ(error.diagnostics[0].code, "WATCH_FAILED");
  EXPECT_EQ(fs::path(error.source_path), s.watch);
  EXPECT_NE(diagnostics_text(error).find("missing"), std::string::npos) << diagnostics_text(error);
  EXPECT_EQ(diagnostics_text(error).find("inotify watches exhausted"), std::string::npos) << diagnostics_text(error);

  // Made again, with the models back: published again, numbered on from their revision state
  // (docs/lcm.md): b, the same content, keeps revision 1; a, another content, gets 2.
  fs::create_directories(s.watch / "sub");
  const auto a2 = box_model("a2_base", 0.12);
  write_model(s.watch, "a.gltf", a2);
  write_model(s.watch / "sub", "b.gltf", b);
  ASSERT_TRUE(s.wait_revision("a.gltf", 2, content_hash(a2), 10s));
  ASSERT_TRUE(s.wait_revision("sub/b.gltf", 1, content_hash(b), 10s));
  ASSERT_TRUE(s.daemon->wait_log("every folder is watched again"));
  // Watched, not just found: the next save is seen.
  const auto a3 = box_model("a3_base", 0.14);
  write_model(s.watch, "a.gltf", a3);
  ASSERT_TRUE(s.wait_revision("a.gltf", 3, content_hash(a3)));
  EXPECT_EQ(decoded<rdtf::model_error_t>(s.messages(), "ERROR", "").size(), 1u);
  EXPECT_TRUE(s.daemon->running());
}

// Every file the live description names (its JSON's buffers, its URDF's meshes) is in the output
// folder with the bytes it had when that revision was published.
void expect_files_of(const rdtf::description_t& d, const std::map<std::string, std::string>& at_publication,
                     const fs::path& folder) {
  for (const auto& uri : uris_of(d.rdtf_json)) {
    ASSERT_TRUE(at_publication.count(uri)) << uri;
    ASSERT_TRUE(fs::exists(folder / uri)) << "the live revision's " << uri << " is gone";
    EXPECT_EQ(read(folder / uri), at_publication.at(uri)) << uri;
  }
  for (const auto& mesh : meshes_of(d.urdf)) {
    const std::string relative = "urdf/" + mesh;
    ASSERT_TRUE(at_publication.count(relative)) << relative;
    ASSERT_TRUE(fs::exists(folder / relative)) << "the live revision's " << relative << " is gone";
    EXPECT_EQ(read(folder / relative), at_publication.at(relative)) << relative;
  }
}

TEST(DaemonFilesystem, ADiskFullBetweenTheGltfAndTheUrdfLeavesTheLiveRevisionWhole) {
  Session s;
  Tmpfs disk(s.output, 1 << 20);
  ASSERT_TRUE(disk.mounted()) << "cannot mount a tmpfs: run in tests/support/in_netns.sh";
  const auto first = box_model("first_base", 0.1, 3, "arm.bin");
  write_model(s.watch, "arm.gltf", first);
  s.start();
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(first)));
  const auto live = *last_description(s.messages(), "arm.gltf");
  ASSERT_FALSE(live.urdf.empty());
  const fs::path folder = s.output / "arm.gltf";
  const auto at_publication = snapshot(folder);
  // Room for the new revision's glTF side (its .bin and JSON, as large as the first's) and not
  // for its URDF side too (three new meshes, other boxes, and robot.urdf: a page each at least).
  std::size_t gltf_pages = 0;
  for (const auto& [name, bytes] : at_publication) {
    if (name.rfind("urdf/", 0) != 0) gltf_pages += pages(bytes.size());
  }
  disk.fill_leaving(s.output / "filler", gltf_pages);

  const auto second = box_model("secnd_base", 0.12, 3, "arm.bin");
  write_model(s.watch, "arm.gltf", second);
  ASSERT_TRUE(s.daemon->wait_log("could not write the outputs of arm.gltf"));
  // The retries are where an older daemon removed the live revision's .bin.
  ASSERT_TRUE(s.daemon->wait_log("(attempt 3)", 10s));
  expect_files_of(live, at_publication, folder);
  EXPECT_EQ(read(folder / "arm.rdtf.gltf"), live.rdtf_json);
  EXPECT_EQ(read(folder / "urdf" / "robot.urdf"), live.urdf);
  EXPECT_FALSE(has_revision(s.messages(), "arm.gltf", 2, content_hash(second)));

  // Space again: revision 2 in place, whole, and the description names its files.
  fs::remove(s.output / "filler");
  ASSERT_TRUE(s.wait_revision("arm.gltf", 2, content_hash(second), 10s));
  const auto now_live = *last_description(s.messages(), "arm.gltf");
  EXPECT_EQ(read(folder / "arm.rdtf.gltf"), now_live.rdtf_json);
  EXPECT_EQ(read(folder / "urdf" / "robot.urdf"), now_live.urdf);
  expect_files_of(now_live, snapshot(folder), folder);
  EXPECT_TRUE(s.daemon->running());
}

// Under a file-size limit (systemd's LimitFSIZE=, ulimit -f), an output larger than the limit fails
// its write (EFBIG) like a full disk: the revision is not published, the live one stays, rdtfd
// retries and keeps serving. SIGXFSZ killed it, and again after every restart on the same model.
// The limit is set in this process only while rdtfd is started (a child inherits it); 64 KiB holds
// rdtfd's log, state and a one-box model's outputs, not the RDTF JSON and URDF of a chain of 400
// boxes (hundreds of KiB).
TEST(DaemonFilesystem, AFileSizeLimitFailsTheWriteNotTheDaemon) {
  Session s;
  const auto first = box_model("first_base", 0.1, 1, "arm.bin");
  write_model(s.watch, "arm.gltf", first);
  rlimit before{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &before), 0);
  rlimit limit = before;
  limit.rlim_cur = 64 * 1024;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  s.start();
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &before), 0);
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(first)));
  const auto big = box_model("big_base", 0.1, 400, "arm.bin");
  write_model(s.watch, "arm.gltf", big);
  ASSERT_TRUE(s.daemon->wait_log("could not write the outputs of arm.gltf", 10s));
  ASSERT_TRUE(s.daemon->wait_log("(attempt 2)", 10s));
  EXPECT_TRUE(s.daemon->running());
  EXPECT_FALSE(has_revision(s.messages(), "arm.gltf", 2, content_hash(big)));
  // Still serving revision 1: a request is answered with it.
  s.request("arm.gltf", "after");
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    const auto d = last_description(all, "arm.gltf");
    return d && d->revision == 1 && d->content_hash == content_hash(first) &&
           on_kind(all, "DESCRIPTION", "arm.gltf").size() >= 2;
  }));
  EXPECT_TRUE(s.daemon->running());
}

TEST(DaemonFilesystem, RdtfConvertOnAFullDiskLeavesThePreviousOutputWhole) {
  testing::TempDir root;
  const fs::path out = root / "out";
  fs::create_directories(out);
  Tmpfs disk(out, 512 * 1024);
  ASSERT_TRUE(disk.mounted()) << "cannot mount a tmpfs: run in tests/support/in_netns.sh";
  const auto first = box_model("first_base", 0.1, 3, "arm.bin");
  write_model(root.path(), "arm.gltf", first);
  const std::string convert = std::string(RDTF_CLI_PATH) + " convert " + (root / "arm.gltf").string() + " -o " +
                              (out / "arm.rdtf.gltf").string() + " 2>" + (root / "convert.log").string();
  ASSERT_EQ(run_shell(convert), 0) << read(root / "convert.log");
  const auto before = snapshot(out);
  // The buffer is written beside the output under the output's stem.
  ASSERT_TRUE(before.count("arm.rdtf.bin") && before.count("arm.rdtf.gltf"));

  // A new .bin fits, its JSON does not.
  const auto second = box_model("secnd_base", 0.2, 3, "arm.bin");
  write_model(root.path(), "arm.gltf", second);
  disk.fill_leaving(out / "filler", pages(before.at("arm.rdtf.bin").size()));
  EXPECT_NE(run_shell(convert), 0);
  EXPECT_NE(read(root / "convert.log").find("No space left on device"), std::string::npos) << read(root / "convert.log");
  auto after = snapshot(out);
  after.erase("filler");
  EXPECT_EQ(after, before) << "the previous output changed";

  fs::remove(out / "filler");
  ASSERT_EQ(run_shell(convert), 0) << read(root / "convert.log");
  EXPECT_NE(snapshot(out).at("arm.rdtf.bin"), before.at("arm.rdtf.bin"));
}

TEST(DaemonFilesystem, AModelNamingOneHugeSparseFileManyTimesIsRefusedBeforeReadingIt) {
  Session s;
  // 500 MB, every byte a hole: reading it costs memory, not disk.
  const std::uint64_t size = 500'000'000;
  {
    const int fd = ::open((s.watch / "huge.bin").c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::ftruncate(fd, static_cast<off_t>(size)), 0);
    ::close(fd);
  }
  Json document = Json::parse(box_model("huge_base", 0.1).gltf);
  document["buffers"] = Json::array();
  for (int i = 0; i < 40; ++i) document["buffers"].push_back({{"uri", "huge.bin"}, {"byteLength", size}});
  document["buffers"].push_back(Json::parse(box_model("huge_base", 0.1).gltf)["buffers"][0]);
  for (auto& view : document["bufferViews"]) view["buffer"] = 40;
  write_in_place(s.watch / "huge.gltf", document.dump());
  const auto good = box_model("good_base", 0.1);
  write_model(s.watch, "good.gltf", good);
  s.start();

  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "ERROR", "huge.gltf").empty(); }, 20s));
  ASSERT_TRUE(s.wait_revision("good.gltf", 1, content_hash(good)));
  const auto error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "huge.gltf").front();
  const std::string text = diagnostics_text(error);
  EXPECT_NE(text.find("LIMIT_EXCEEDED"), std::string::npos) << text;
  EXPECT_NE(text.find("max_read_bytes"), std::string::npos) << text;
  EXPECT_NE(text.find(std::to_string(40 * size + fs::file_size(s.watch / "huge.gltf"))), std::string::npos) << text;
  // Memory: the peak resident set stays below one read of the file (it was never read).
  const long peak_kb = status_kb(s.daemon->pid(), "VmHWM");
  ASSERT_GT(peak_kb, 0);
  std::cerr << "rdtfd peak RSS (VmHWM): " << peak_kb / 1024 << " MiB\n";
  EXPECT_LT(static_cast<std::uint64_t>(peak_kb) * 1024, size) << "peak RSS " << peak_kb << " kB";
  EXPECT_TRUE(s.daemon->running());
}

TEST(DaemonFilesystem, NamesTooLongForTheOutputFileSystemAreRefusedNotRetried) {
  Session s;
  // "<250 bytes>.gltf" is a name the watched folder takes (255 bytes), but "<250 bytes>.rdtf.gltf" is not.
  const std::string stem(250, 'n');
  const auto model = box_model("long_base", 0.1);
  write_in_place(s.watch / (stem + ".gltf"), model.gltf);
  s.start();
  ASSERT_TRUE(s.wait_for([](const auto& all) {
    for (const auto& m : all) {
      if (m.kind() == "ERROR" && !m.model_id().empty()) return true;
    }
    return false;
  })) << ::testing::PrintToString(model_events(s.messages()));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->pending, 0) << "still retried";
  EXPECT_EQ(s.daemon->log().find("trying again"), std::string::npos) << "retried as a disk fault";
  std::vector<rdtf::model_error_t> errors;
  for (const auto& m : s.messages()) {
    if (m.kind() == "ERROR" && !m.model_id().empty()) errors.push_back(m.as<rdtf::model_error_t>());
  }
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(diagnostics_text(errors[0]).find("NAME_TOO_LONG"), std::string::npos) << diagnostics_text(errors[0]);
  // Another model converts meanwhile.
  const auto good = box_model("good_base", 0.1);
  write_model(s.watch, "good.gltf", good);
  EXPECT_TRUE(s.wait_revision("good.gltf", 1, content_hash(good)));
}

TEST(DaemonFilesystem, ABurstOfTwentyThousandFilesIsHandledWhileRequestsAndHeartbeatsGoOn) {
  constexpr int kFiles = 20000;
  Session s;
  const auto a = box_model("a_base", 0.1);
  write_model(s.watch, "a.gltf", a);
  s.start();
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  // Made outside and moved in as one folder: one inotify event, then 20,000 files at once.
  const fs::path burst = s.root / "burst";
  fs::create_directories(burst);
  for (int i = 0; i < kFiles; ++i) testing::write_file(burst / ("f" + std::to_string(i) + ".gltf"), "");
  const std::size_t before = s.subscriber.size();
  fs::rename(burst, s.watch / "burst");
  s.request("a.gltf", "during-burst");

  auto burst_errors = [](const std::vector<Message>& all, std::size_t from) {
    std::vector<std::size_t> at;
    for (std::size_t i = from; i < all.size(); ++i) {
      if (all[i].kind() == "ERROR" && all[i].model_id().rfind("burst/", 0) == 0) at.push_back(i);
    }
    return at;
  };
  // Every file handled: the daemon's counters say 20,000 rejections (an empty file is no glTF).
  // ERRORs are counted as received: under this load a few datagrams may be lost on the way.
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    const auto heartbeats = statuses(all);
    return !heartbeats.empty() && heartbeats.back().rejections >= kFiles;
  }, 60s)) << burst_errors(s.messages(), before).size() << " ERRORs of " << kFiles;
  const auto idle = s.wait_idle(3, 30s);
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->rejections, kFiles);
  EXPECT_EQ(idle->pending, 0);
  // Every ERROR left the daemon: its send queue dropped none. How many reach this test's own
  // subscriber depends on how fast its thread drains LCM's 30-message queue under a 20,000-message
  // burst (between 50% and 97% in runs on a loaded 2-core machine): that is the test's side of UDP,
  // so only some are required here, each once.
  EXPECT_EQ(idle->send_dropped, 0);
  const auto all = s.messages();
  const auto errors = burst_errors(all, before);
  ASSERT_GT(errors.size(), 0u);
  std::set<std::string> ids;
  for (const auto i : errors) ids.insert(all[i].model_id());
  EXPECT_EQ(ids.size(), errors.size()) << "a file was reported twice";

  // The request sent as the burst arrived was answered before the burst was worked off, and
  // heartbeats went on between the burst's errors.
  std::optional<std::size_t> answer;
  int statuses_during = 0;
  for (std::size_t i = before; i < all.size(); ++i) {
    if (!answer && all[i].kind() == "DESCRIPTION" && all[i].model_id() == "a.gltf") answer = i;
    if (all[i].kind() == "STATUS" && i > errors.front() && i < errors.back()) ++statuses_during;
  }
  ASSERT_TRUE(answer.has_value());
  EXPECT_LT(*answer, errors.back()) << "the request waited for the whole burst";
  std::cerr << "STATUS messages between the burst's first and last ERROR: " << statuses_during << "\n";
  EXPECT_GE(statuses_during, 1);
  EXPECT_TRUE(s.daemon->running());
}

}  // namespace
}  // namespace rdtf::itest
