// SettleQueue (daemon/settle.h) over an injected clock: when a model's files have been quiet long
// enough to convert it, and how a file still open for writing holds it back.
#include "settle.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace rdtf::daemon {
namespace {

using namespace std::chrono_literals;

const Clock::time_point t0 = Clock::time_point{} + 1000h;  // Any fixed instant.

TEST(Settle, NothingPendingNothingDue) {
  SettleQueue queue(50ms, 5s);
  EXPECT_EQ(queue.size(), 0u);
  EXPECT_FALSE(queue.next_deadline().has_value());
  EXPECT_TRUE(queue.take_due(t0).empty());
}

TEST(Settle, BurstOfTouchesGivesOneDueAfterTheQuietPeriod) {
  SettleQueue queue(50ms, 5s);
  // 100 events, 10 ms apart (a save every 10 ms for a second): never quiet for 50 ms.
  for (int i = 0; i < 100; ++i) {
    const auto now = t0 + i * 10ms;
    queue.touch("/w/arm.gltf", now);
    EXPECT_TRUE(queue.take_due(now).empty()) << "due during the burst, at event " << i;
  }
  const auto last = t0 + 990ms;
  EXPECT_EQ(queue.size(), 1u);
  ASSERT_TRUE(queue.next_deadline().has_value());
  EXPECT_EQ(*queue.next_deadline(), last + 50ms);
  EXPECT_TRUE(queue.take_due(last + 49ms).empty());
  EXPECT_EQ(queue.take_due(last + 50ms), std::vector<std::string>{"/w/arm.gltf"});
  // Taken once: nothing left.
  EXPECT_EQ(queue.size(), 0u);
  EXPECT_TRUE(queue.take_due(last + 10s).empty());
  EXPECT_FALSE(queue.next_deadline().has_value());
}

TEST(Settle, ClosedCountsAsAnEvent) {
  SettleQueue queue(50ms, 5s);
  queue.closed("/w/a.gltf", t0);  // A close with no event before it (e.g. the initial scan).
  EXPECT_TRUE(queue.take_due(t0 + 49ms).empty());
  EXPECT_EQ(queue.take_due(t0 + 50ms), std::vector<std::string>{"/w/a.gltf"});

  queue.touch("/w/a.gltf", t0 + 1s);
  queue.closed("/w/a.gltf", t0 + 1s + 30ms);  // Re-arms the deadline.
  EXPECT_TRUE(queue.take_due(t0 + 1s + 79ms).empty());
  EXPECT_EQ(queue.take_due(t0 + 1s + 80ms).size(), 1u);
}

TEST(Settle, StillOpenFileWaitsForItsClose) {
  SettleQueue queue(50ms, 5s);
  // An in-place save: written (IN_MODIFY) and not closed; the writer pauses for 2 s.
  queue.touch("/w/arm.gltf", t0, /*still_open=*/true);
  EXPECT_TRUE(queue.take_due(t0 + 50ms).empty());
  EXPECT_TRUE(queue.take_due(t0 + 2s).empty());
  ASSERT_TRUE(queue.next_deadline().has_value());
  EXPECT_EQ(*queue.next_deadline(), t0 + 5s);  // At most max_open_wait.
  // A later plain event does not make the open file look closed.
  queue.touch("/w/arm.gltf", t0 + 2s + 100ms, /*still_open=*/false);
  EXPECT_TRUE(queue.take_due(t0 + 2s + 200ms).empty());
  // The writer closes: settle from the close.
  queue.closed("/w/arm.gltf", t0 + 3s);
  ASSERT_TRUE(queue.next_deadline().has_value());
  EXPECT_EQ(*queue.next_deadline(), t0 + 3s + 50ms);
  EXPECT_TRUE(queue.take_due(t0 + 3s + 49ms).empty());
  EXPECT_EQ(queue.take_due(t0 + 3s + 50ms), std::vector<std::string>{"/w/arm.gltf"});
}

TEST(Settle, StillOpenFileIsConvertedAnywayAfterMaxOpenWait) {
  SettleQueue queue(50ms, 1s);
  queue.touch("/w/mmap.glb", t0, /*still_open=*/true);  // A writer that never closes.
  EXPECT_TRUE(queue.take_due(t0 + 999ms).empty());
  EXPECT_EQ(queue.take_due(t0 + 1s), std::vector<std::string>{"/w/mmap.glb"});
}

TEST(Settle, MaxOpenWaitCountsFromTheFirstEventButQuietStillApplies) {
  SettleQueue queue(50ms, 1s);
  for (int i = 0; i < 100; ++i) queue.touch("/w/a.gltf", t0 + i * 10ms, /*still_open=*/true);
  // Last event at 990 ms: the quiet period ends at 1040 ms, after max_open_wait (1000 ms).
  ASSERT_TRUE(queue.next_deadline().has_value());
  EXPECT_EQ(*queue.next_deadline(), t0 + 1040ms);
  EXPECT_TRUE(queue.take_due(t0 + 1039ms).empty());
  EXPECT_EQ(queue.take_due(t0 + 1040ms).size(), 1u);
}

TEST(Settle, ModelsSettleIndependently) {
  SettleQueue queue(50ms, 5s);
  queue.touch("/w/a.gltf", t0);
  queue.touch("/w/b.gltf", t0 + 30ms);
  queue.touch("/w/c.gltf", t0 + 10ms, /*still_open=*/true);
  EXPECT_EQ(queue.size(), 3u);
  ASSERT_TRUE(queue.next_deadline().has_value());
  EXPECT_EQ(*queue.next_deadline(), t0 + 50ms);  // The earliest.
  EXPECT_EQ(queue.take_due(t0 + 50ms), std::vector<std::string>{"/w/a.gltf"});
  EXPECT_EQ(*queue.next_deadline(), t0 + 80ms);
  // Events of b do not move a's or c's deadlines.
  queue.touch("/w/b.gltf", t0 + 70ms);
  EXPECT_TRUE(queue.take_due(t0 + 119ms).empty());
  EXPECT_EQ(queue.take_due(t0 + 120ms), std::vector<std::string>{"/w/b.gltf"});
  EXPECT_EQ(queue.size(), 1u);  // c still waits for its writer.
  queue.closed("/w/c.gltf", t0 + 200ms);
  EXPECT_EQ(queue.take_due(t0 + 250ms), std::vector<std::string>{"/w/c.gltf"});
}

TEST(Settle, SeveralDueAtOnceAreAllTaken) {
  SettleQueue queue(50ms, 5s);
  queue.touch("/w/a.gltf", t0);
  queue.touch("/w/b.gltf", t0 + 1ms);
  queue.touch("/w/c.gltf", t0 + 2ms);
  auto due = queue.take_due(t0 + 1s);
  std::sort(due.begin(), due.end());
  EXPECT_EQ(due, (std::vector<std::string>{"/w/a.gltf", "/w/b.gltf", "/w/c.gltf"}));
  EXPECT_EQ(queue.size(), 0u);
}

TEST(Settle, ForgetDropsAPendingModel) {
  SettleQueue queue(50ms, 5s);
  queue.touch("/w/a.gltf", t0);
  queue.touch("/w/b.gltf", t0);
  queue.forget("/w/a.gltf");
  queue.forget("/w/never-seen.gltf");  // Harmless.
  EXPECT_EQ(queue.take_due(t0 + 1s), std::vector<std::string>{"/w/b.gltf"});
}

TEST(Settle, ANewSettlePeriodAppliesToPendingModels) {
  SettleQueue queue(50ms, 5s);
  queue.touch("/w/a.gltf", t0);
  queue.set_settle(200ms);  // SIGHUP with a new settle_ms.
  EXPECT_TRUE(queue.take_due(t0 + 199ms).empty());
  EXPECT_EQ(queue.take_due(t0 + 200ms).size(), 1u);
}

TEST(Settle, AfterBeingTakenAModelStartsAFreshWait) {
  SettleQueue queue(50ms, 1s);
  queue.touch("/w/a.gltf", t0, /*still_open=*/true);
  queue.closed("/w/a.gltf", t0 + 10ms);
  EXPECT_EQ(queue.take_due(t0 + 60ms).size(), 1u);
  // A new save long after: its max_open_wait counts from its own first event, not the old one.
  queue.touch("/w/a.gltf", t0 + 10s, /*still_open=*/true);
  EXPECT_TRUE(queue.take_due(t0 + 10s + 999ms).empty());
  EXPECT_EQ(queue.take_due(t0 + 11s).size(), 1u);
}

}  // namespace
}  // namespace rdtf::daemon
