// One rdtfd per output folder (docs/daemon.md, "The output folder"): two on one output shared its
// revision numbers, clean-stop mark and result cache, and published one revision number for two
// documents (helper sweep s70cache D2). And the state folder is the output's own, never a link to
// a folder elsewhere, where its files would be written and its cache's eviction remove files
// (s70cache D3).
#include <unistd.h>

#include <csignal>
#include <thread>

#include "daemon/harness.h"
#include "support/harness/fs_support.h"

namespace rdtf::itest {
namespace {

TEST(DaemonOutputLock, ASecondDaemonOnTheSameOutputIsRefusedAndTheFirstServesOn) {
  Session s;
  s.start();
  const auto first = box_model("first_base", 0.1);
  write_model(s.watch, "box.gltf", first);
  ASSERT_TRUE(s.wait_revision("box.gltf", 1, content_hash(first)));

  // Another watched folder, the same output, other settings.
  const fs::path other_watch = s.root / "other";
  fs::create_directories(other_watch);
  DaemonProcess second(DaemonOptions().with_watch({other_watch}).with_output(s.output).with("default_density", 500.0));
  const auto code = second.wait_exit(10s);
  ASSERT_TRUE(code.has_value()) << second.log();
  EXPECT_EQ(*code, 1);
  EXPECT_NE(second.log().find("another rdtfd uses the output folder " + s.output.string()), std::string::npos)
      << second.log();

  EXPECT_TRUE(s.daemon->running());
  const auto edited = box_model("edited_base", 0.12);
  write_model(s.watch, "box.gltf", edited);
  EXPECT_TRUE(s.wait_revision("box.gltf", 2, content_hash(edited)));
  // Stopped, the first lets the next daemon have the folder.
  ASSERT_EQ(s.daemon->stop(10s), 0);
  DaemonProcess third(DaemonOptions().with_watch({s.watch}).with_output(s.output));
  EXPECT_TRUE(third.wait_log("rdtfd started", 10s)) << third.log();
  EXPECT_TRUE(third.running());
}

// A reload that moves the output takes the new folder's lock before it lets the old one go; one
// another daemon holds is refused and the running config stays (review s70rev D1: the lock stayed
// on the old folder, and a second daemon started on the new one).
TEST(DaemonOutputLock, AReloadMovesTheLockWithTheOutput) {
  Session s;
  const fs::path config = s.root / "rdtfd.json", moved = s.root / "moved";
  auto write_config = [&](const fs::path& output) {
    testing::write_file(config, Json{{"watch", {s.watch.string()}}, {"output", output.string()}, {"validate", false},
                                     {"simulate", false}}.dump());
  };
  // Its folders from the config file only (a folder given with --output stays through reloads).
  write_config(s.output);
  ChildProcess first({RDTFD_PATH, "--config", config.string()}, s.root / "first.log");
  auto wait_output = [](const ChildProcess& process, const std::string& text) {
    for (int i = 0; i < 200; ++i) {
      if (process.output().find(text) != std::string::npos) return true;
      std::this_thread::sleep_for(50ms);
    }
    return false;
  };
  ASSERT_TRUE(wait_output(first, "rdtfd started")) << first.output();
  write_config(moved);
  first.signal(SIGHUP);
  ASSERT_TRUE(wait_output(first, "config reloaded")) << first.output();

  DaemonProcess on_moved(DaemonOptions().with_watch({s.root / "w2"}).with_output(moved));
  const auto code = on_moved.wait_exit(10s);
  ASSERT_TRUE(code.has_value()) << on_moved.log();
  EXPECT_EQ(*code, 1);
  DaemonProcess on_old(DaemonOptions().with_watch({s.root / "w3"}).with_output(s.output));
  EXPECT_TRUE(on_old.wait_log("rdtfd started", 10s)) << on_old.log();

  // Back to the old output, which the third daemon now holds: refused, the running config stays.
  write_config(s.output);
  first.signal(SIGHUP);
  EXPECT_TRUE(wait_output(first, "config not reloaded, the running config stays: another rdtfd uses the output folder " +
                                     s.output.string()))
      << first.output();
  EXPECT_FALSE(first.wait_exit(0s).has_value()) << "still running";
}

TEST(DaemonOutputLock, AStateFolderThatIsALinkIsRefused) {
  Session s;
  const fs::path elsewhere = s.root / "elsewhere";
  fs::create_directories(elsewhere);
  fs::create_directories(s.output);
  fs::create_directory_symlink(elsewhere, s.output / ".rdtfd-state");
  DaemonProcess daemon(DaemonOptions().with_watch({s.watch}).with_output(s.output));
  const auto code = daemon.wait_exit(10s);
  ASSERT_TRUE(code.has_value()) << daemon.log();
  EXPECT_EQ(*code, 1);
  EXPECT_NE(daemon.log().find((s.output / ".rdtfd-state").string() + " is a symbolic link"), std::string::npos)
      << daemon.log();
  EXPECT_TRUE(fs::is_empty(elsewhere));
}

}  // namespace
}  // namespace rdtf::itest
