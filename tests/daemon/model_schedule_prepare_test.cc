// ModelSchedule's conversions while settling (convert_while_settling): a job may start once a
// settling model's files are closed; its result is used at the deadline only when no event came
// after it started. Stepped with made-up times, as model_schedule_test.cc.
#include <gtest/gtest.h>

#include "model_schedule.h"

namespace rdtf::daemon {
namespace {

using namespace std::chrono_literals;
using P = ModelPhase;

const Clock::time_point t0 = Clock::time_point{} + 1000h;
const SettlePolicy policy{50ms, 5s};

bool nothing(const ModelActions& a) {
  return !a.start_job && !a.publish_error && !a.publish_live && !a.remove && !a.retry_in && !a.use_prepared &&
         !a.discard_prepared;
}

// A model saved at t0 whose prepared job started at once.
ModelSchedule preparing() {
  ModelSchedule state;
  state.file_changed(t0, FileChange::kClosed);
  EXPECT_TRUE(state.can_prepare());
  state.begin_prepare();
  EXPECT_FALSE(state.can_prepare());  // One job per model.
  return state;
}

TEST(ModelSchedulePrepared, OnlyASettlingModelWithItsFilesClosedPrepares) {
  ModelSchedule idle;
  EXPECT_FALSE(idle.can_prepare());
  ModelSchedule writing;
  writing.file_changed(t0, FileChange::kModified);  // An in-place save still open.
  EXPECT_FALSE(writing.can_prepare());
  writing.file_changed(t0 + 5ms, FileChange::kClosed);
  EXPECT_TRUE(writing.can_prepare());
  ModelSchedule touched;  // A rescan: nothing known of writers, nothing open either.
  touched.file_changed(t0, FileChange::kTouched);
  EXPECT_TRUE(touched.can_prepare());
}

TEST(ModelSchedulePrepared, AResultReadyBeforeTheDeadlineIsHeldAndUsedAtIt) {
  ModelSchedule state = preparing();
  EXPECT_TRUE(nothing(state.prepare_finished(t0 + 10ms, true)));
  EXPECT_TRUE(state.holds_prepared());
  EXPECT_EQ(state.phase(), P::kSettling);
  EXPECT_TRUE(state.pending());
  EXPECT_EQ(state.deadline(policy), t0 + 50ms);  // Published no sooner than without it.
  EXPECT_TRUE(nothing(state.timer(t0 + 49ms, policy, false)));
  const ModelActions due = state.timer(t0 + 50ms, policy, false);
  EXPECT_TRUE(due.use_prepared);
  EXPECT_FALSE(due.start_job);
  EXPECT_FALSE(state.holds_prepared());
  EXPECT_EQ(state.phase(), P::kConverting);  // Until the committed result is applied.
  EXPECT_TRUE(nothing(state.job_finished(t0 + 52ms, JobResult::kDone, true)));
  EXPECT_EQ(state.phase(), P::kLive);
}

TEST(ModelSchedulePrepared, AnEventAfterTheResultDropsItAndSettlesAgain) {
  ModelSchedule state = preparing();
  state.prepare_finished(t0 + 10ms, true);
  const ModelActions changed = state.file_changed(t0 + 30ms, FileChange::kClosed);
  EXPECT_TRUE(changed.discard_prepared);
  EXPECT_FALSE(state.holds_prepared());
  EXPECT_EQ(state.deadline(policy), t0 + 80ms);
  EXPECT_TRUE(state.can_prepare());  // The new content may be prepared in turn.
  EXPECT_TRUE(state.timer(t0 + 80ms, policy, false).start_job);  // Not prepared: converted now.
}

TEST(ModelSchedulePrepared, AnEventWhileItRunsMakesItsResultStale) {
  ModelSchedule state = preparing();
  state.file_changed(t0 + 5ms, FileChange::kModified);  // The .bin after the .gltf.
  EXPECT_FALSE(state.can_prepare());
  EXPECT_TRUE(nothing(state.prepare_finished(t0 + 10ms, true)));  // Dropped, though usable.
  EXPECT_FALSE(state.holds_prepared());
  EXPECT_FALSE(state.can_prepare());  // The .bin is still open.
  state.file_changed(t0 + 20ms, FileChange::kClosed);
  EXPECT_TRUE(state.can_prepare());
  state.begin_prepare();
  state.prepare_finished(t0 + 30ms, true);
  EXPECT_TRUE(state.timer(t0 + 70ms, policy, false).use_prepared);
}

TEST(ModelSchedulePrepared, AJobStillRunningAtTheDeadlineIsTheConversion) {
  ModelSchedule state = preparing();
  EXPECT_TRUE(nothing(state.timer(t0 + 50ms, policy, false)));  // No second job.
  EXPECT_EQ(state.phase(), P::kConverting);
  EXPECT_TRUE(state.converting());
  EXPECT_TRUE(state.prepare_finished(t0 + 60ms, true).use_prepared);
  EXPECT_EQ(state.phase(), P::kConverting);
  state.job_finished(t0 + 62ms, JobResult::kDone, true);
  EXPECT_EQ(state.phase(), P::kLive);
}

TEST(ModelSchedulePrepared, AStaleJobAtTheDeadlineIsFollowedByAConversionOfWhatSettled) {
  ModelSchedule state = preparing();
  state.file_changed(t0 + 20ms, FileChange::kClosed);
  EXPECT_TRUE(nothing(state.timer(t0 + 70ms, policy, false)));  // Waits for the running job.
  EXPECT_EQ(state.phase(), P::kConverting);
  const ModelActions ended = state.prepare_finished(t0 + 80ms, true);
  EXPECT_TRUE(ended.start_job);
  EXPECT_FALSE(ended.use_prepared);
  EXPECT_EQ(state.phase(), P::kConverting);
}

TEST(ModelSchedulePrepared, AnAdoptedJobsResultIsUsedEvenIfTheFilesChangeAfterTheDeadline) {
  // As a job started at the deadline: it converts content that had settled; the newer save
  // settles meanwhile and is converted after it.
  ModelSchedule state = preparing();
  state.timer(t0 + 50ms, policy, false);
  state.file_changed(t0 + 60ms, FileChange::kClosed);
  EXPECT_EQ(state.phase(), P::kChangedWhileConverting);
  EXPECT_TRUE(state.prepare_finished(t0 + 70ms, true).use_prepared);
  state.job_finished(t0 + 72ms, JobResult::kDone, true);
  EXPECT_EQ(state.phase(), P::kSettling);
  EXPECT_EQ(state.deadline(policy), t0 + 110ms);
}

TEST(ModelSchedulePrepared, AnUnusableResultIsNotPreparedAgainUntilTheNextEvent) {
  ModelSchedule state = preparing();
  EXPECT_TRUE(nothing(state.prepare_finished(t0 + 10ms, false)));  // E.g. the file was gone.
  EXPECT_FALSE(state.holds_prepared());
  EXPECT_FALSE(state.can_prepare());  // It would only end the same way, again and again.
  EXPECT_TRUE(state.timer(t0 + 50ms, policy, false).start_job);  // The deadline converts as always.
  ModelSchedule again = preparing();
  again.prepare_finished(t0 + 10ms, false);
  again.file_changed(t0 + 20ms, FileChange::kClosed);
  EXPECT_TRUE(again.can_prepare());
}

TEST(ModelSchedulePrepared, AnUnusableJobAtTheDeadlineIsReplacedByAConversion) {
  ModelSchedule state = preparing();
  state.timer(t0 + 50ms, policy, false);
  EXPECT_TRUE(state.prepare_finished(t0 + 60ms, false).start_job);
}

TEST(ModelSchedulePrepared, AWriterStillOpenAtTheDeadlineDropsTheHeldResult) {
  // Never converted yet, the model waits for any file of its folder open for writing (its .bin
  // may be the one): what the job read may be half written.
  ModelSchedule state = preparing();
  state.prepare_finished(t0 + 10ms, true);
  const ModelActions held_back = state.timer(t0 + 50ms, policy, true);
  EXPECT_TRUE(held_back.discard_prepared);
  EXPECT_FALSE(held_back.use_prepared);
  EXPECT_EQ(state.phase(), P::kWaitingForWriter);
  EXPECT_TRUE(state.timer(t0 + 100ms, policy, false).start_job);
}

TEST(ModelSchedulePrepared, NoPreparingDuringABackOff) {
  ModelSchedule state;
  state.file_changed(t0, FileChange::kClosed);
  state.timer(t0 + 50ms, policy, false);
  const ModelActions failed = state.job_finished(t0 + 60ms, JobResult::kRetryable, false);
  ASSERT_TRUE(failed.retry_in.has_value());
  state.file_changed(t0 + 70ms, FileChange::kClosed);  // A save during the back-off.
  EXPECT_EQ(state.phase(), P::kSettling);
  EXPECT_FALSE(state.can_prepare());
}

TEST(ModelSchedulePrepared, RemovalDropsTheHeldResult) {
  ModelSchedule state = preparing();
  state.prepare_finished(t0 + 10ms, true);
  const ModelActions gone = state.removed();
  EXPECT_TRUE(gone.discard_prepared);
  EXPECT_FALSE(state.holds_prepared());
  EXPECT_TRUE(nothing(state.prepare_finished(t0 + 20ms, true)));  // Nothing outstanding.
}

}  // namespace
}  // namespace rdtf::daemon
