// The settle policy (daemon/settle.h) over made-up times: when a model's files have been quiet
// long enough to convert it, and how a file still open for writing holds it back.
#include "settle.h"

#include <gtest/gtest.h>

namespace rdtf::daemon {
namespace {

using namespace std::chrono_literals;

const Clock::time_point t0 = Clock::time_point{} + 1000h;  // Any fixed instant.
const SettlePolicy policy{50ms, 5s};

TEST(Settle, BurstOfEventsIsDueOnceQuietForTheSettlePeriod) {
  // 100 events, 10 ms apart (a save every 10 ms for a second): never quiet for 50 ms.
  SettleWindow window = SettleWindow::opened(t0, false);
  for (int i = 1; i < 100; ++i) {
    window.touch(t0 + i * 10ms, false);
    EXPECT_EQ(window.deadline(policy), t0 + i * 10ms + 50ms) << "event " << i;
  }
  EXPECT_EQ(window.deadline(policy), t0 + 990ms + 50ms);
}

TEST(Settle, ClosedCountsAsAnEvent) {
  SettleWindow window = SettleWindow::opened(t0, false);
  window.closed(t0 + 30ms);  // Re-arms the deadline.
  EXPECT_EQ(window.deadline(policy), t0 + 80ms);
}

TEST(Settle, StillOpenFileWaitsForItsClose) {
  // An in-place save: written (IN_MODIFY) and not closed; the writer pauses for 2 s.
  SettleWindow window = SettleWindow::opened(t0, /*still_open=*/true);
  EXPECT_EQ(window.deadline(policy), t0 + 5s);  // At most max_open_wait.
  // A later plain event does not make the open file look closed.
  window.touch(t0 + 2s + 100ms, false);
  EXPECT_EQ(window.deadline(policy), t0 + 5s);
  // The writer closes: settle from the close.
  window.closed(t0 + 3s);
  EXPECT_EQ(window.deadline(policy), t0 + 3s + 50ms);
}

TEST(Settle, StillOpenFileIsConvertedAnywayAfterMaxOpenWait) {
  const SettlePolicy short_wait{50ms, 1s};
  const SettleWindow window = SettleWindow::opened(t0, /*still_open=*/true);  // A writer that never closes.
  EXPECT_EQ(window.deadline(short_wait), t0 + 1s);
}

TEST(Settle, MaxOpenWaitCountsFromTheFirstEventButQuietStillApplies) {
  const SettlePolicy short_wait{50ms, 1s};
  SettleWindow window = SettleWindow::opened(t0, true);
  for (int i = 1; i < 100; ++i) window.touch(t0 + i * 10ms, true);
  // Last event at 990 ms: the quiet period ends at 1040 ms, after max_open_wait (1000 ms).
  EXPECT_EQ(window.deadline(short_wait), t0 + 1040ms);
}

TEST(Settle, ANewSettlePeriodAppliesToAPendingWindow) {
  const SettleWindow window = SettleWindow::opened(t0, false);
  EXPECT_EQ(window.deadline(SettlePolicy{200ms, 5s}), t0 + 200ms);  // SIGHUP with a new settle_ms.
}

TEST(OpenWrites, HoldsOnlyFilesOpenForAtMostTheLongestWait) {
  OpenWrites open;
  open.opened("/w/a.bin", t0);
  open.opened("/w/a.bin", t0 + 1s);  // Keeps the first time.
  const std::vector<std::filesystem::path> files{"/w/a.gltf", "/w/a.bin"};
  EXPECT_TRUE(open.holds(files, nullptr, t0 + 5s, 5s));
  EXPECT_FALSE(open.holds(files, nullptr, t0 + 5s + 1ms, 5s));
  EXPECT_FALSE(open.holds({"/w/b.gltf"}, nullptr, t0, 5s));
  const std::filesystem::path folder = "/w";
  EXPECT_TRUE(open.holds({"/w/b.gltf"}, &folder, t0, 5s));  // Any file in the folder.
  open.closed("/w/a.bin");
  EXPECT_FALSE(open.holds(files, &folder, t0, 5s));
  EXPECT_EQ(open.size(), 0u);
}

}  // namespace
}  // namespace rdtf::daemon
