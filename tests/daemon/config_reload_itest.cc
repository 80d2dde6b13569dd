// SIGHUP with a config that cannot be read (a directory, a FIFO) or that holds a value outside its
// range keeps the running config and the daemon serving; file names reach the log escaped.
#include <sys/stat.h>

#include "daemon/harness.h"
#include "support/harness/fs_support.h"

namespace rdtf::itest {
namespace {

// A save converts: the loop is alive and runs on the config it had.
void expect_serving(Session& s, const std::string& base, std::int64_t revision) {
  const auto model = box_model(base, 0.1 + 0.01 * static_cast<double>(revision));
  write_model(s.watch, "arm.gltf", model);
  EXPECT_TRUE(s.wait_revision("arm.gltf", revision, content_hash(model))) << base;
}

TEST(DaemonReload, ADirectoryOrAFifoAsTheConfigKeepsTheRunningConfig) {
  Session s;
  s.start();
  expect_serving(s, "first_base", 1);
  const fs::path config = s.daemon->config_path();
  const std::string good = read(config);

  fs::remove(config);
  fs::create_directory(config);
  s.daemon->signal(SIGHUP);
  ASSERT_TRUE(s.daemon->wait_log("config not reloaded"));
  EXPECT_NE(s.daemon->log().find("is a directory"), std::string::npos);
  EXPECT_TRUE(s.daemon->running());
  expect_serving(s, "second_base", 2);

  fs::remove(config);
  ASSERT_EQ(::mkfifo(config.c_str(), 0644), 0);
  s.daemon->signal(SIGHUP);
  ASSERT_TRUE(s.daemon->wait_log("not a regular file"));
  EXPECT_TRUE(s.daemon->running());
  expect_serving(s, "third_base", 3);

  // A good change: the log names the keys and what each does (and one kept until a restart).
  Json changed = Json::parse(good);
  changed["status_period_ms"] = 120;
  changed["workers"] = 3;
  fs::remove(config);
  testing::write_file(config, changed.dump());
  s.daemon->signal(SIGHUP);
  ASSERT_TRUE(s.daemon->wait_log("SIGHUP: config reloaded: changed status_period_ms (live); kept until a restart: workers"))
      << s.daemon->log();
  fs::remove(config);
  testing::write_file(config, good);

  // A value outside its range: refused, naming the key and the range.
  fs::remove(config);
  Json wedging = Json::parse(good);
  wedging["time_step"] = 1e-7;
  testing::write_file(config, wedging.dump());
  s.daemon->signal(SIGHUP);
  ASSERT_TRUE(s.daemon->wait_log("\"time_step\" is 1e-07, outside its valid range"));
  EXPECT_TRUE(s.daemon->running());
  expect_serving(s, "fourth_base", 4);
}

TEST(DaemonReload, ATimeStepThatWouldWedgeTheDaemonIsRefusedAtStart) {
  Session s;
  DaemonOptions options;
  options.with("time_step", 1e-7);
  std::unique_ptr<DaemonProcess> daemon = std::make_unique<DaemonProcess>(options.with_watch({s.watch}).with_output(s.output));
  const auto code = daemon->wait_exit(10s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 2);
  EXPECT_NE(daemon->log().find("time_step"), std::string::npos) << daemon->log();
}

// A misspelt LCM option is a bad setting, refused at start with exit 2 (LCM itself only warned
// and ran with TTL 0); a URL LCM cannot open at this moment is not, and exits 1 so that systemd
// restarts it (a network not yet up at boot).
TEST(DaemonReload, AMisspeltLcmOptionIsRefusedAtStart) {
  Session s;
  DaemonOptions options;
  options.with("lcm_url", "udpm://239.255.76.67:7667?tll=1");
  auto daemon = std::make_unique<DaemonProcess>(options.with_watch({s.watch}).with_output(s.output));
  const auto code = daemon->wait_exit(10s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 2);
  EXPECT_NE(daemon->log().find("option \"tll=1\" is not one LCM's udpm provider reads"), std::string::npos) << daemon->log();
}

// A config file that is not there, or a directory, given at start: exit 2 like any bad setting,
// naming the file and what is wrong (CLI11's own check exited 105 with its wording).
TEST(DaemonReload, AMissingOrDirectoryConfigIsRefusedAtStartNamingIt) {
  Session s;
  for (const fs::path& config : {s.root / "missing.json", s.root.path()}) {
    ChildProcess daemon({RDTFD_PATH, "--config", config.string()}, s.root / "daemon.log");
    const auto code = daemon.wait_exit(10s);
    ASSERT_TRUE(code.has_value()) << config;
    EXPECT_EQ(*code, 2) << daemon.output();
    EXPECT_NE(daemon.output().find(config.string() + ": "), std::string::npos) << daemon.output();
  }
}

TEST(DaemonLog, FileNamesAreEscapedSoThatNoneForgesALine) {
  Session s;
  s.start();
  const std::string forged = "FORGED 2026-01-01T00:00:00.000Z converted victim.gltf revision 9";
  const std::string name = "bad\n" + forged + "\x1b[2J.gltf";
  testing::write_file(s.watch / name, "{ not json");
  ASSERT_TRUE(s.daemon->wait_log("rejected "));
  const std::string log = s.daemon->log();
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    EXPECT_NE(line.rfind("FORGED", 0), 0u) << "a forged line: " << line;
    EXPECT_EQ(line.find('\x1b'), std::string::npos) << "a terminal escape: " << line;
  }
  EXPECT_NE(log.find("bad\\nFORGED"), std::string::npos) << log;
  EXPECT_NE(log.find("\\x1b[2J"), std::string::npos) << log;
}

}  // namespace
}  // namespace rdtf::itest
