// ModelSchedule (daemon/model_schedule.h): every transition of a model's state machine, stepped with
// made-up times (no clock, no files, no threads).
#include "model_schedule.h"

#include <gtest/gtest.h>

namespace rdtf::daemon {
namespace {

using namespace std::chrono_literals;
using P = ModelPhase;

const Clock::time_point t0 = Clock::time_point{} + 1000h;  // Any fixed instant.
const SettlePolicy policy{50ms, 5s};

// A model that changed at t0 and settled: its job runs.
ModelSchedule converting() {
  ModelSchedule state;
  state.file_changed(t0, FileChange::kClosed);
  EXPECT_TRUE(state.timer(t0 + 50ms, policy, false).start_job);
  EXPECT_EQ(state.phase(), P::kConverting);
  return state;
}

bool no_actions(const ModelActions& a) {
  return !a.start_job && !a.publish_error && !a.publish_live && !a.remove && !a.retry_in;
}

TEST(ModelSchedule, IdleWaitsForEventsAndAnswersNoRequest) {
  ModelSchedule state;
  EXPECT_EQ(state.phase(), P::kIdle);
  EXPECT_FALSE(state.deadline(policy).has_value());
  EXPECT_FALSE(state.pending());
  EXPECT_TRUE(no_actions(state.timer(t0 + 1h, policy, false)));
  EXPECT_TRUE(no_actions(state.job_finished(t0, JobResult::kDone, false)));  // No job runs: ignored.
  EXPECT_EQ(state.phase(), P::kIdle);
  EXPECT_TRUE(no_actions(state.request()));
}

TEST(ModelSchedule, EveryKindOfFileChangeStartsASettle) {
  for (const FileChange change : {FileChange::kModified, FileChange::kClosed, FileChange::kTouched}) {
    ModelSchedule state;
    EXPECT_TRUE(no_actions(state.file_changed(t0, change)));
    EXPECT_EQ(state.phase(), P::kSettling);
    EXPECT_TRUE(state.pending());
    // A write still open holds the model until max_open_wait; the others settle.
    EXPECT_EQ(state.deadline(policy), change == FileChange::kModified ? t0 + 5s : t0 + 50ms);
  }
}

TEST(ModelSchedule, SettlingEventsMoveTheDeadlineAndTheQuietPeriodStartsTheJob) {
  ModelSchedule state;
  state.file_changed(t0, FileChange::kClosed);
  state.file_changed(t0 + 30ms, FileChange::kClosed);
  EXPECT_EQ(state.deadline(policy), t0 + 80ms);
  EXPECT_TRUE(no_actions(state.timer(t0 + 79ms, policy, false)));  // Early: nothing.
  EXPECT_EQ(state.phase(), P::kSettling);
  const ModelActions due = state.timer(t0 + 80ms, policy, false);
  EXPECT_TRUE(due.start_job);
  EXPECT_EQ(state.phase(), P::kConverting);
  EXPECT_FALSE(state.deadline(policy).has_value());  // A job has no deadline of its own.
  EXPECT_TRUE(state.pending());
}

TEST(ModelSchedule, AnOpenWriterHoldsTheModelAndIsLookedAtAgainASettleLater) {
  ModelSchedule state;
  state.file_changed(t0, FileChange::kClosed);
  EXPECT_TRUE(no_actions(state.timer(t0 + 50ms, policy, /*writer_open=*/true)));
  EXPECT_EQ(state.phase(), P::kWaitingForWriter);
  EXPECT_EQ(state.deadline(policy), t0 + 100ms);
  EXPECT_TRUE(no_actions(state.timer(t0 + 100ms, policy, true)));  // Still open.
  EXPECT_EQ(state.deadline(policy), t0 + 150ms);
  EXPECT_TRUE(state.timer(t0 + 150ms, policy, false).start_job);  // Closed (or open too long).
  EXPECT_EQ(state.phase(), P::kConverting);
}

TEST(ModelSchedule, AnEventWhileWaitingForAWriterSettlesAgain) {
  ModelSchedule state;
  state.file_changed(t0, FileChange::kClosed);
  state.timer(t0 + 50ms, policy, true);
  state.file_changed(t0 + 60ms, FileChange::kClosed);  // The writer's close.
  EXPECT_EQ(state.phase(), P::kSettling);
  EXPECT_EQ(state.deadline(policy), t0 + 110ms);
}

TEST(ModelSchedule, AJobThatEndsWellMakesTheModelLiveAndRequestsRepublishIt) {
  ModelSchedule state = converting();
  EXPECT_TRUE(no_actions(state.job_finished(t0 + 1s, JobResult::kDone, /*live=*/true)));
  EXPECT_EQ(state.phase(), P::kLive);
  EXPECT_FALSE(state.pending());
  EXPECT_TRUE(state.request().publish_live);
  // An unchanged content with nothing served yet (rejected before) leaves it idle.
  ModelSchedule unserved = converting();
  unserved.job_finished(t0 + 1s, JobResult::kDone, false);
  EXPECT_EQ(unserved.phase(), P::kIdle);
  EXPECT_FALSE(unserved.request().publish_live);
}

TEST(ModelSchedule, ALiveModelThatChangesSettlesAndStillAnswersRequests) {
  ModelSchedule state = converting();
  state.job_finished(t0 + 1s, JobResult::kDone, true);
  state.file_changed(t0 + 2s, FileChange::kModified);
  EXPECT_EQ(state.phase(), P::kSettling);
  EXPECT_TRUE(state.request().publish_live);
}

TEST(ModelSchedule, ARejectionIsPublishedAndKeepsWhatWasLive) {
  ModelSchedule state = converting();
  EXPECT_TRUE(state.job_finished(t0 + 1s, JobResult::kRejected, false).publish_error);
  EXPECT_EQ(state.phase(), P::kIdle);
  ModelSchedule live = converting();
  live.job_finished(t0 + 1s, JobResult::kDone, true);
  live.file_changed(t0 + 2s, FileChange::kClosed);
  live.timer(t0 + 2s + 50ms, policy, false);
  EXPECT_TRUE(live.job_finished(t0 + 3s, JobResult::kRejected, true).publish_error);
  EXPECT_EQ(live.phase(), P::kLive);
}

TEST(ModelSchedule, AChangeDuringTheJobSettlesMeanwhileAndConvertsAfterIt) {
  ModelSchedule state = converting();
  state.file_changed(t0 + 100ms, FileChange::kClosed);
  EXPECT_EQ(state.phase(), P::kChangedWhileConverting);
  EXPECT_EQ(state.deadline(policy), t0 + 150ms);
  // The job ends before the change settled: the settle runs on, then a job starts.
  EXPECT_TRUE(no_actions(state.job_finished(t0 + 120ms, JobResult::kDone, true)));
  EXPECT_EQ(state.phase(), P::kSettling);
  EXPECT_EQ(state.deadline(policy), t0 + 150ms);
  EXPECT_TRUE(state.timer(t0 + 150ms, policy, false).start_job);
}

TEST(ModelSchedule, AChangeThatSettlesDuringTheJobConvertsOnceMoreWhenItEnds) {
  ModelSchedule state = converting();
  state.file_changed(t0 + 100ms, FileChange::kClosed);
  // Settled while the job runs: no second job at once (one per model).
  EXPECT_TRUE(no_actions(state.timer(t0 + 150ms, policy, false)));
  EXPECT_EQ(state.phase(), P::kConvertAgain);
  EXPECT_FALSE(state.deadline(policy).has_value());
  // More events meanwhile change nothing of that.
  state.file_changed(t0 + 200ms, FileChange::kClosed);
  EXPECT_EQ(state.phase(), P::kConvertAgain);
  // The job ends: settle from its end, then convert.
  EXPECT_TRUE(no_actions(state.job_finished(t0 + 1s, JobResult::kDone, true)));
  EXPECT_EQ(state.phase(), P::kSettling);
  EXPECT_EQ(state.deadline(policy), t0 + 1s + 50ms);
  EXPECT_TRUE(state.timer(t0 + 1s + 50ms, policy, false).start_job);
}

TEST(ModelSchedule, ARejectionSupersededByASettledChangeIsNotPublished) {
  ModelSchedule settled = converting();
  settled.file_changed(t0 + 100ms, FileChange::kClosed);
  settled.timer(t0 + 150ms, policy, false);
  EXPECT_FALSE(settled.job_finished(t0 + 1s, JobResult::kRejected, false).publish_error);
  EXPECT_EQ(settled.phase(), P::kSettling);
  // A change still settling does not yet supersede it.
  ModelSchedule settling = converting();
  settling.file_changed(t0 + 100ms, FileChange::kClosed);
  EXPECT_TRUE(settling.job_finished(t0 + 120ms, JobResult::kRejected, false).publish_error);
}

TEST(ModelSchedule, AWriterOpenWhenAChangeSettlesDuringTheJobHoldsItBack) {
  ModelSchedule state = converting();
  state.file_changed(t0 + 100ms, FileChange::kModified);
  EXPECT_EQ(state.deadline(policy), t0 + 100ms + 5s);
  state.file_changed(t0 + 200ms, FileChange::kClosed);
  EXPECT_TRUE(no_actions(state.timer(t0 + 250ms, policy, /*writer_open=*/true)));
  EXPECT_EQ(state.phase(), P::kChangedWhileConverting);
  EXPECT_EQ(state.deadline(policy), t0 + 300ms);
}

TEST(ModelSchedule, FailedWritesBackOffDoublingUpToThreeSecondsWithOneError) {
  ModelSchedule state = converting();
  Clock::time_point now = t0 + 1s;
  const ModelActions first = state.job_finished(now, JobResult::kRetryable, false);
  EXPECT_TRUE(first.publish_error);
  EXPECT_EQ(first.retry_in, Clock::duration(200ms));
  EXPECT_EQ(state.phase(), P::kRetryAfter);
  EXPECT_TRUE(state.pending());
  EXPECT_EQ(state.deadline(policy), now + 200ms);
  const Clock::duration expected[] = {400ms, 800ms, 1600ms, 3000ms, 3000ms};
  for (const Clock::duration delay : expected) {
    now = *state.deadline(policy);
    EXPECT_TRUE(no_actions(state.timer(now, policy, false)));  // Back-off over: settle first.
    EXPECT_EQ(state.phase(), P::kSettling);
    now += 50ms;
    EXPECT_TRUE(state.timer(now, policy, false).start_job);
    const ModelActions again = state.job_finished(now, JobResult::kRetryable, false);
    EXPECT_FALSE(again.publish_error);  // One ERROR per outage.
    EXPECT_EQ(again.retry_in, delay);
    EXPECT_EQ(state.deadline(policy), now + delay);
  }
  EXPECT_EQ(state.attempts(), 6);
  // Space returns: the next attempt succeeds and a later outage starts from 200 ms again.
  now = *state.deadline(policy);
  state.timer(now, policy, false);
  state.timer(now + 50ms, policy, false);
  state.job_finished(now + 60ms, JobResult::kDone, true);
  EXPECT_EQ(state.phase(), P::kLive);
  EXPECT_EQ(state.attempts(), 0);
  state.file_changed(now + 1s, FileChange::kClosed);
  state.timer(now + 1s + 50ms, policy, false);
  const ModelActions next = state.job_finished(now + 2s, JobResult::kRetryable, true);
  EXPECT_TRUE(next.publish_error);
  EXPECT_EQ(next.retry_in, Clock::duration(200ms));
}

TEST(ModelSchedule, AChangeDuringTheBackOffConvertsAfterItsSettle) {
  ModelSchedule state = converting();
  state.job_finished(t0 + 1s, JobResult::kRetryable, false);
  state.file_changed(t0 + 1s + 10ms, FileChange::kClosed);
  EXPECT_EQ(state.phase(), P::kSettling);
  EXPECT_EQ(state.deadline(policy), t0 + 1s + 60ms);
  EXPECT_TRUE(state.timer(t0 + 1s + 60ms, policy, false).start_job);
  // Failing again continues the back-off of the same outage.
  const ModelActions again = state.job_finished(t0 + 2s, JobResult::kRetryable, false);
  EXPECT_FALSE(again.publish_error);
  EXPECT_EQ(again.retry_in, Clock::duration(400ms));
}

TEST(ModelSchedule, AFailedWriteWithANewerSaveWaitingSettlesThatSave) {
  ModelSchedule state = converting();
  state.file_changed(t0 + 100ms, FileChange::kClosed);
  const ModelActions actions = state.job_finished(t0 + 120ms, JobResult::kRetryable, false);
  EXPECT_TRUE(actions.publish_error);
  EXPECT_EQ(state.phase(), P::kSettling);
  EXPECT_EQ(state.deadline(policy), t0 + 150ms);
}

TEST(ModelSchedule, AModelGoneWhenItsJobReadsItIsRemoved) {
  ModelSchedule state = converting();
  EXPECT_TRUE(state.job_finished(t0 + 1s, JobResult::kVanished, false).remove);
  EXPECT_EQ(state.phase(), P::kRemoved);
  EXPECT_FALSE(state.pending());
  EXPECT_FALSE(state.deadline(policy).has_value());
  // Removed is final: nothing moves it.
  EXPECT_TRUE(no_actions(state.file_changed(t0 + 2s, FileChange::kClosed)));
  EXPECT_TRUE(no_actions(state.timer(t0 + 1h, policy, false)));
  EXPECT_TRUE(no_actions(state.request()));
  EXPECT_TRUE(no_actions(state.removed()));
  EXPECT_EQ(state.phase(), P::kRemoved);
}

TEST(ModelSchedule, AModelRecreatedWhileItsJobFoundItGoneSettlesTheNewFile) {
  ModelSchedule state = converting();
  EXPECT_TRUE(no_actions(state.job_finished(t0 + 1s, JobResult::kRecreated, true)));
  EXPECT_EQ(state.phase(), P::kSettling);
  EXPECT_EQ(state.deadline(policy), t0 + 1s + 50ms);
  EXPECT_TRUE(state.timer(t0 + 1s + 50ms, policy, false).start_job);
  // With a change already settling, that settle runs on from the job's end.
  ModelSchedule changed = converting();
  changed.file_changed(t0 + 100ms, FileChange::kModified);
  changed.job_finished(t0 + 1s, JobResult::kRecreated, true);
  EXPECT_EQ(changed.phase(), P::kSettling);
  EXPECT_EQ(changed.deadline(policy), t0 + 100ms + 5s);  // The open write still holds it.
}

TEST(ModelSchedule, AnUnwatchedModelIsRemovedFromAnyPhase) {
  ModelSchedule live = converting();
  live.job_finished(t0 + 1s, JobResult::kDone, true);
  EXPECT_TRUE(live.removed().remove);
  EXPECT_EQ(live.phase(), P::kRemoved);
  ModelSchedule settling;
  settling.file_changed(t0, FileChange::kClosed);
  EXPECT_TRUE(settling.removed().remove);
  EXPECT_FALSE(settling.deadline(policy).has_value());
  ModelSchedule busy = converting();
  EXPECT_TRUE(busy.removed().remove);
  // Its job's result, when it comes, changes nothing.
  EXPECT_TRUE(no_actions(busy.job_finished(t0 + 1s, JobResult::kDone, true)));
  EXPECT_EQ(busy.phase(), P::kRemoved);
}

TEST(ModelSchedule, EveryPhaseHasAName) {
  for (const P phase : {P::kIdle, P::kLive, P::kSettling, P::kWaitingForWriter, P::kConverting,
                        P::kChangedWhileConverting, P::kConvertAgain, P::kRetryAfter, P::kRemoved}) {
    EXPECT_STRNE(phase_name(phase), "?");
  }
}

}  // namespace
}  // namespace rdtf::daemon
