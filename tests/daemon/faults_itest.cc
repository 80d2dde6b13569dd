// rdtfd under faults of its environment: a full disk, unreadable files, models deleted while
// being read, a folder replaced by a file, inotify watches exhausted, LCM refusing to send. Each
// must be reported (a log line and an ERROR on LCM), none may stop the daemon, and once the fault
// clears the models it held back are converted and published.
//
// The full disk is a 256 KiB tmpfs mounted over the output folder inside the test's own mount
// namespace (tests/support/in_netns.sh makes one). LCM send failures are real: the test deletes
// the namespace's multicast route, so every send fails with ENETUNREACH, then restores it. The
// inotify limit (fs.inotify.max_user_watches is system-wide on this kernel, even from a user
// namespace) is injected through the watcher's seam RDTFD_TEST_INOTIFY_LIMIT_FILE.
#include <algorithm>
#include <fstream>
#include <sys/stat.h>
#include <cstring>
#include <sys/mount.h>

#include "daemon/harness.h"
#include "support/harness/fs_support.h"

namespace rdtf::itest {
namespace {

int shell(const std::string& command) { return std::system(command.c_str()); }

std::string diagnostics_text(const rdtf::model_error_t& error) {
  std::string text;
  for (const auto& d : error.diagnostics) text += d.code + " " + d.file + " " + d.pointer + " " + d.message + "\n";
  return text;
}

bool has_code(const rdtf::model_error_t& error, const std::string& code) {
  for (const auto& d : error.diagnostics) {
    if (d.code == code) return true;
  }
  return false;
}

TEST(DaemonFault, DiskFullOnTheOutputIsReportedAndConvertsOnceSpaceReturns) {
  Session s;
  Tmpfs disk(s.output, 256 * 1024);
  ASSERT_TRUE(disk.mounted()) << "cannot mount a tmpfs: run in tests/support/in_netns.sh";
  ASSERT_GT(disk.fill(s.output / "filler"), 0u);
  const auto model = box_model("full_base", 0.1, 3);
  write_model(s.watch, "arm.gltf", model);
  s.start();

  // Reported: an ERROR naming the output that could not be written, and a log line.
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "ERROR", "arm.gltf").empty(); }));
  const auto error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "arm.gltf").front();
  EXPECT_TRUE(has_code(error, "WRITE_FAILED")) << diagnostics_text(error);
  EXPECT_NE(diagnostics_text(error).find("No space left on device"), std::string::npos) << diagnostics_text(error);
  EXPECT_NE(diagnostics_text(error).find(s.output.string()), std::string::npos) << diagnostics_text(error);
  // Named where the outputs go, not in the stage folder (a random name, gone by now); and first.
  EXPECT_EQ(diagnostics_text(error).find(".stage."), std::string::npos) << diagnostics_text(error);
  EXPECT_EQ(error.diagnostics.front().severity, rdtf::diagnostic_t::ERROR) << diagnostics_text(error);
  ASSERT_TRUE(s.daemon->wait_log("could not write the outputs of arm.gltf"));
  // Still pending (the daemon retries), nothing published, no half-written file.
  ASSERT_TRUE(s.daemon->wait_log("(attempt 2)"));
  EXPECT_TRUE(on_kind(s.messages(), "DESCRIPTION", "arm.gltf").empty());
  for (const auto& entry : fs::recursive_directory_iterator(s.output)) {
    // The filler, and the daemon's lock (an empty file, held while it runs).
    EXPECT_TRUE(entry.is_directory() || entry.path().filename() == "filler" ||
                entry.path() == s.output / ".rdtfd-state" / "lock")
        << entry.path() << " left behind";
  }
  // Another model's conversion meanwhile fails the same way, and nothing stops.
  const auto other = box_model("other_base", 0.2);
  write_model(s.watch, "other.gltf", other);
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "ERROR", "other.gltf").empty(); }));

  // Space returns: both convert and publish, once each, with exactly one ERROR before.
  fs::remove(s.output / "filler");
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(model), 10s));
  ASSERT_TRUE(s.wait_revision("other.gltf", 1, content_hash(other), 10s));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 2);
  EXPECT_EQ(idle->pending, 0);
  EXPECT_EQ(model_events(s.messages(), "arm.gltf"),
            concat({{"arm.gltf ERROR live=0 " + short_hash(content_hash(model))},
                    revision_events("arm.gltf", 1, content_hash(model))}));
  EXPECT_TRUE(fs::exists(s.output / "arm.gltf" / "arm.rdtf.gltf"));
  EXPECT_TRUE(fs::exists(s.output / "arm.gltf" / "urdf" / "robot.urdf"));
  EXPECT_TRUE(s.daemon->running());
}

TEST(DaemonFault, LcmSendFailuresAreRetriedAndReportedOnceSendingWorks) {
  Session s;
  const auto first = box_model("first_base", 0.1);
  write_model(s.watch, "arm.gltf", first);
  s.start();
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(first)));

  // No route for multicast: every send fails (ENETUNREACH) while the model is saved again.
  ASSERT_EQ(shell("ip route del 224.0.0.0/4 dev lo"), 0);
  const auto second = box_model("second_base", 0.12);
  write_model(s.watch, "arm.gltf", second);
  ASSERT_TRUE(s.daemon->wait_log("converted arm.gltf revision 2"));
  ASSERT_TRUE(s.daemon->wait_log("LCM send failed on"));
  EXPECT_TRUE(s.daemon->running());
  EXPECT_FALSE(has_revision(s.messages(), "arm.gltf", 2, content_hash(second)));

  // The route returns: revision 2 arrives, once, and the outage is reported on <prefix>/ERROR.
  ASSERT_EQ(shell("ip route add 224.0.0.0/4 dev lo"), 0);
  ASSERT_TRUE(s.wait_revision("arm.gltf", 2, content_hash(second), 10s));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "ERROR", "").empty(); }));
  const auto outage = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "").front();
  EXPECT_EQ(outage.model_id, "");
  EXPECT_TRUE(has_code(outage, "LCM_SEND_FAILED")) << diagnostics_text(outage);
  EXPECT_TRUE(s.daemon->log().find("LCM sending works again") != std::string::npos);
  ASSERT_TRUE(s.wait_idle());
  EXPECT_EQ(model_events(s.messages(), "arm.gltf"),
            concat({revision_events("arm.gltf", 1, content_hash(first)),
                    revision_events("arm.gltf", 2, content_hash(second))}));
}

// A symlink planted where a model's output folder goes (<output>/<model> -> elsewhere): rdtfd
// writes nothing through it and removes nothing behind it, says so, and converts once it is gone.
TEST(DaemonFault, ASymlinkInTheOutputFolderIsNeverFollowed) {
  Session s;
  const fs::path elsewhere = s.output.parent_path() / "elsewhere";
  fs::create_directories(elsewhere / "urdf" / "meshes");
  // Names shaped like rdtfd's own content-addressed outputs, which its clean-up removes.
  for (const fs::path& file : {elsewhere / "keep.0123456789abcdef.bin", elsewhere / "urdf" / "meshes" / "part.0123456789abcdef.stl"}) {
    std::ofstream(file) << "precious";
  }
  fs::create_directories(s.output);
  fs::create_directory_symlink(elsewhere, s.output / "arm.gltf");
  const auto model = box_model("link_base", 0.1, 2);
  write_model(s.watch, "arm.gltf", model);
  s.start();

  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "ERROR", "arm.gltf").empty(); }));
  const auto error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "arm.gltf").front();
  EXPECT_TRUE(has_code(error, "WRITE_FAILED")) << diagnostics_text(error);
  EXPECT_NE(diagnostics_text(error).find((s.output / "arm.gltf").string() + " is a symbolic link"), std::string::npos)
      << diagnostics_text(error);
  ASSERT_TRUE(s.daemon->wait_log("(attempt 2)"));
  EXPECT_TRUE(on_kind(s.messages(), "DESCRIPTION", "arm.gltf").empty());
  std::vector<std::string> there;
  for (const auto& entry : fs::recursive_directory_iterator(elsewhere)) there.push_back(entry.path().lexically_relative(elsewhere).string());
  std::sort(there.begin(), there.end());
  EXPECT_EQ(there, (std::vector<std::string>{"keep.0123456789abcdef.bin", "urdf", "urdf/meshes",
                                              "urdf/meshes/part.0123456789abcdef.stl"}));

  // The link removed: the retry converts into a folder of rdtfd's own.
  fs::remove(s.output / "arm.gltf");
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(model), 30s));
  EXPECT_FALSE(fs::is_symlink(s.output / "arm.gltf"));
  EXPECT_TRUE(fs::exists(s.output / "arm.gltf" / "arm.rdtf.gltf"));
  EXPECT_TRUE(fs::exists(elsewhere / "keep.0123456789abcdef.bin"));
  EXPECT_TRUE(s.daemon->running());
}

// The file system of a watched folder unmounted (a USB disk pulled, an NFS or sshfs mount gone):
// its models are removals, not revisions served from files that are no longer there, and the
// folder left behind (the mount point) is watched as it is.
TEST(DaemonFault, AnUnmountedFolderIsARemovalOfItsModels) {
  Session s;
  fs::create_directories(s.watch / "usb");
  Tmpfs disk(s.watch / "usb", 1 << 20);
  ASSERT_TRUE(disk.mounted()) << "cannot mount a tmpfs: run in tests/support/in_netns.sh";
  const auto model = box_model("usb_base", 0.1, 2);
  write_model(s.watch / "usb", "arm.gltf", model);
  s.start();
  ASSERT_TRUE(s.wait_revision("usb/arm.gltf", 1, content_hash(model)));

  ASSERT_EQ(::umount2((s.watch / "usb").c_str(), MNT_DETACH), 0) << std::strerror(errno);
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "REMOVED", "usb/arm.gltf").empty(); }))
      << ::testing::PrintToString(model_events(s.messages()));
  // The mount point is an ordinary folder again, and watched: a model saved there converts.
  const auto after = box_model("after_base", 0.12);
  write_model(s.watch / "usb", "after.gltf", after);
  ASSERT_TRUE(s.wait_revision("usb/after.gltf", 1, content_hash(after)));
  EXPECT_TRUE(s.daemon->running());
}

TEST(DaemonFault, UnreadableFilesAreReportedAndConvertOnceReadable) {
  Session s;
  // Tests run as root, whom chmod 000 does not stop: unreadable here means a FIFO where the
  // model should be, and a folder where its .bin should be.
  const auto model = box_model("late_base", 0.1, 2, "arm.bin");
  fs::create_directory(s.watch / "arm.bin");
  write_in_place(s.watch / "arm.gltf", model.gltf);
  s.start(DaemonOptions().with("max_open_wait_ms", 300));
  ASSERT_EQ(::mkfifo((s.watch / "pipe.gltf").c_str(), 0644), 0);

  ASSERT_TRUE(s.wait_for([](const auto& all) {
    return !on_kind(all, "ERROR", "arm.gltf").empty() && !on_kind(all, "ERROR", "pipe.gltf").empty();
  })) << ::testing::PrintToString(model_events(s.messages()));
  const auto bin_error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "arm.gltf").front();
  ASSERT_FALSE(bin_error.diagnostics.empty());
  EXPECT_EQ(bin_error.diagnostics[0].pointer, "/buffers/0/uri");
  EXPECT_NE(bin_error.diagnostics[0].message.find("is a directory"), std::string::npos) << diagnostics_text(bin_error);
  const auto fifo_error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "pipe.gltf").front();
  ASSERT_FALSE(fifo_error.diagnostics.empty());
  EXPECT_EQ(fifo_error.diagnostics[0].code, "IO_ERROR");
  EXPECT_EQ(fs::path(fifo_error.diagnostics[0].file), fs::canonical(s.watch / "pipe.gltf"));
  ASSERT_TRUE(s.daemon->wait_log("rejected pipe.gltf"));

  // Made readable: the folder becomes the .bin, the FIFO a model. Both convert.
  fs::remove(s.watch / "arm.bin");
  write_in_place(s.watch / "arm.bin", model.bin);
  const auto piped = box_model("pipe_base", 0.1);
  write_by_rename(s.watch / "pipe.gltf", piped.gltf, "pipe.gltf.part");
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(model)));
  ASSERT_TRUE(s.wait_revision("pipe.gltf", 1, content_hash(piped)));
  EXPECT_TRUE(s.daemon->running());
}

TEST(DaemonFault, ModelsDeletedWhileBeingReadLeaveTheDaemonServing) {
  Session s;
  s.start(DaemonOptions().with_settle(5));
  // A model that takes a while to convert (thousands of parts), deleted at moments spread over
  // its conversion: before, during and after the read. The spacing is the point of the test.
  const auto big = many_parts_model("big", 4000, 0.01);
  for (int round = 0; round < 20; ++round) {
    write_in_place(s.watch / "big.gltf", big.gltf);
    std::this_thread::sleep_for(std::chrono::milliseconds(round * 3));
    fs::remove(s.watch / "big.gltf");
  }
  const auto idle = s.wait_idle(3, 20s);
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->pending, 0);
  EXPECT_EQ(idle->num_models, 0) << ::testing::PrintToString(model_events(s.messages()));
  // Whatever was published of it last says it is gone.
  const auto events = model_events(s.messages(), "big.gltf");
  if (!events.empty()) {
    EXPECT_EQ(events.back().substr(0, 17), "big.gltf REMOVED ") << ::testing::PrintToString(events);
  }
  const auto good = box_model("good_base", 0.1);
  write_model(s.watch, "good.gltf", good);
  EXPECT_TRUE(s.wait_revision("good.gltf", 1, content_hash(good)));
  EXPECT_TRUE(s.daemon->running());
}

TEST(DaemonFault, AFolderReplacedByAFileAndAModelByAFolderAreRemovals) {
  Session s;
  fs::create_directories(s.watch / "sub");
  const auto a = box_model("a_base", 0.1);
  const auto b = box_model("b_base", 0.1);
  const auto c = box_model("c_base", 0.1);
  write_model(s.watch / "sub", "a.gltf", a);
  write_model(s.watch / "sub", "b.gltf", b);
  write_model(s.watch, "c.gltf", c);
  s.start();
  ASSERT_TRUE(s.wait_revision("sub/a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_revision("sub/b.gltf", 1, content_hash(b)));
  ASSERT_TRUE(s.wait_revision("c.gltf", 1, content_hash(c)));

  fs::remove_all(s.watch / "sub");
  write_in_place(s.watch / "sub", "not a folder any more");
  fs::remove(s.watch / "c.gltf");
  fs::create_directory(s.watch / "c.gltf");
  ASSERT_TRUE(s.wait_for([](const auto& all) {
    return !on_kind(all, "REMOVED", "sub/a.gltf").empty() && !on_kind(all, "REMOVED", "sub/b.gltf").empty() &&
           !on_kind(all, "REMOVED", "c.gltf").empty();
  })) << ::testing::PrintToString(model_events(s.messages()));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->num_models, 0);
  EXPECT_EQ(model_events(s.messages(), "c.gltf"),
            concat({revision_events("c.gltf", 1, content_hash(c)), {"c.gltf REMOVED last=1"}}));
  // A model inside the folder that replaced the model file is a new model.
  const auto d = box_model("d_base", 0.1);
  write_model(s.watch / "c.gltf", "d.gltf", d);
  EXPECT_TRUE(s.wait_revision("c.gltf/d.gltf", 1, content_hash(d)));
  EXPECT_TRUE(s.daemon->running());
}

TEST(DaemonFault, InotifyWatchesExhaustedIsReportedAndRecoversWhenRaised) {
  Session s;
  const fs::path limit = s.root / "inotify_limit";
  testing::write_file(limit, "1");  // The watched folder itself, not its subfolder.
  fs::create_directories(s.watch / "sub");
  const auto first = box_model("first_base", 0.1);
  write_model(s.watch / "sub", "arm.gltf", first);
  s.start(DaemonOptions().with_env("RDTFD_TEST_INOTIFY_LIMIT_FILE=" + limit.string()));

  // The folder is reported (log and <prefix>/ERROR, naming the kernel limit); its model is
  // converted once all the same.
  ASSERT_TRUE(s.wait_revision("sub/arm.gltf", 1, content_hash(first)));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "ERROR", "").empty(); }));
  const auto error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "").front();
  EXPECT_TRUE(has_code(error, "WATCH_FAILED")) << diagnostics_text(error);
  EXPECT_EQ(fs::path(error.source_path), fs::canonical(s.watch / "sub"));
  EXPECT_NE(diagnostics_text(error).find("/proc/sys/fs/inotify/max_user_watches"), std::string::npos);
  EXPECT_TRUE(s.daemon->wait_log("/proc/sys/fs/inotify/max_user_watches"));

  // Saved while unwatched, then the limit is raised: the retry watches it and converts the save.
  const auto second = box_model("second_base", 0.12);
  write_model(s.watch / "sub", "arm.gltf", second);
  fs::remove(limit);
  ASSERT_TRUE(s.wait_revision("sub/arm.gltf", 2, content_hash(second), 10s));
  ASSERT_TRUE(s.daemon->wait_log("every folder is watched again"));
  // Watched now: the next save is seen at once.
  const auto third = box_model("third_base", 0.14);
  write_model(s.watch / "sub", "arm.gltf", third);
  ASSERT_TRUE(s.wait_revision("sub/arm.gltf", 3, content_hash(third)));
  EXPECT_EQ(decoded<rdtf::model_error_t>(s.messages(), "ERROR", "").size(), 1u);
  EXPECT_TRUE(s.daemon->running());
}

}  // namespace
}  // namespace rdtf::itest
