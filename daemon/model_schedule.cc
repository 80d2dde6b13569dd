#include "model_schedule.h"

#include <algorithm>

namespace rdtf::daemon {

const char* phase_name(ModelPhase phase) {
  switch (phase) {
    case ModelPhase::kIdle: return "idle";
    case ModelPhase::kLive: return "live";
    case ModelPhase::kSettling: return "settling";
    case ModelPhase::kWaitingForWriter: return "waiting for writer";
    case ModelPhase::kConverting: return "converting";
    case ModelPhase::kChangedWhileConverting: return "changed while converting";
    case ModelPhase::kConvertAgain: return "convert again";
    case ModelPhase::kRetryAfter: return "retry after";
    case ModelPhase::kRemoved: return "removed";
  }
  return "?";
}

std::optional<Clock::time_point> ModelSchedule::deadline(const SettlePolicy& policy) const {
  if (phase_ == ModelPhase::kRetryAfter) return retry_due_;
  if (window_) return window_->deadline(policy);
  return std::nullopt;
}

bool ModelSchedule::pending() const {
  return phase_ != ModelPhase::kIdle && phase_ != ModelPhase::kLive && phase_ != ModelPhase::kRemoved;
}

bool ModelSchedule::converting() const {
  return phase_ == ModelPhase::kConverting || phase_ == ModelPhase::kChangedWhileConverting ||
         phase_ == ModelPhase::kConvertAgain;
}

ModelActions ModelSchedule::file_changed(Clock::time_point now, FileChange change) {
  const bool still_open = change == FileChange::kModified;
  switch (phase_) {
    case ModelPhase::kRemoved:
      return {};
    case ModelPhase::kIdle:
    case ModelPhase::kLive:
    case ModelPhase::kRetryAfter:  // A change converts after its settle, sooner than the back-off.
      phase_ = ModelPhase::kSettling;
      window_ = SettleWindow::opened(now, still_open);
      return {};
    case ModelPhase::kConverting:
      phase_ = ModelPhase::kChangedWhileConverting;
      window_ = SettleWindow::opened(now, still_open);
      return {};
    case ModelPhase::kWaitingForWriter:
      phase_ = ModelPhase::kSettling;
      break;
    case ModelPhase::kSettling:
    case ModelPhase::kChangedWhileConverting:
    case ModelPhase::kConvertAgain:
      break;
  }
  ModelActions actions;
  // While converting, a prepared job adopted at the deadline converts settled content: it stays.
  if (phase_ == ModelPhase::kSettling) prepared_superseded(actions);
  if (!window_) {
    window_ = SettleWindow::opened(now, still_open);
  } else if (change == FileChange::kClosed) {
    window_->closed(now);
  } else {
    window_->touch(now, still_open);
  }
  return actions;
}

void ModelSchedule::prepared_superseded(ModelActions& actions) {
  switch (prepare_) {
    case Prepare::kRunning: prepare_ = Prepare::kStale; break;
    case Prepare::kHeld:
      prepare_ = Prepare::kNone;
      actions.discard_prepared = true;
      break;
    case Prepare::kDeclined: prepare_ = Prepare::kNone; break;
    case Prepare::kNone:
    case Prepare::kStale: break;
  }
}

bool ModelSchedule::can_prepare() const {
  // Not during a back-off: the disk refused the outputs, and the back-off paces the attempts.
  return phase_ == ModelPhase::kSettling && prepare_ == Prepare::kNone && attempts_ == 0 && window_ &&
         !window_->open_for_writing;
}

void ModelSchedule::begin_prepare() { prepare_ = Prepare::kRunning; }

ModelActions ModelSchedule::prepare_finished(Clock::time_point now, bool usable) {
  const Prepare was = prepare_;
  if (was != Prepare::kRunning && was != Prepare::kStale) return {};
  // Its result stands for the content only if no event came after the job read it.
  const bool fresh = was == Prepare::kRunning && usable;
  prepare_ = Prepare::kNone;
  ModelActions actions;
  switch (phase_) {
    case ModelPhase::kSettling:
    case ModelPhase::kWaitingForWriter:
      if (fresh) {
        prepare_ = Prepare::kHeld;
      } else if (was == Prepare::kRunning) {
        prepare_ = Prepare::kDeclined;  // Not again before the next event: it would end the same.
      }
      break;
    case ModelPhase::kConverting:
      // Adopted at the deadline: it was the model's conversion. A stale or unusable one is
      // replaced by a conversion of the content as it is now (it has settled).
      if (fresh) {
        actions.use_prepared = true;
      } else {
        actions.start_job = true;
      }
      break;
    case ModelPhase::kChangedWhileConverting:
    case ModelPhase::kConvertAgain:
      if (fresh) {
        actions.use_prepared = true;  // The settled content's result, as any job's; then settles on.
      } else {
        settle_after_job(now);
      }
      break;
    default:
      break;
  }
  return actions;
}

ModelActions ModelSchedule::timer(Clock::time_point now, const SettlePolicy& policy, bool writer_open) {
  const auto due = deadline(policy);
  if (!due || *due > now) return {};
  if (phase_ == ModelPhase::kRetryAfter) {
    phase_ = ModelPhase::kSettling;  // The attempt goes through the settle and the writer check too.
    window_ = SettleWindow::opened(now, false);
    return {};
  }
  ModelActions actions;
  if (writer_open) {
    // Look again a settle period later (the writer's close is an event that comes sooner). What
    // a prepared job read may be half written.
    window_ = SettleWindow::opened(now, false);
    if (phase_ == ModelPhase::kSettling || phase_ == ModelPhase::kWaitingForWriter) {
      phase_ = ModelPhase::kWaitingForWriter;
      prepared_superseded(actions);
    }
    return actions;
  }
  window_.reset();
  switch (phase_) {
    case ModelPhase::kSettling:
    case ModelPhase::kWaitingForWriter:
      phase_ = ModelPhase::kConverting;
      if (prepare_ == Prepare::kHeld) {
        prepare_ = Prepare::kNone;
        actions.use_prepared = true;
      } else if (prepare_ == Prepare::kNone || prepare_ == Prepare::kDeclined) {
        prepare_ = Prepare::kNone;
        actions.start_job = true;
      }
      // Running (fresh or stale): that job is the conversion now; prepare_finished() decides.
      break;
    case ModelPhase::kChangedWhileConverting:
    case ModelPhase::kConvertAgain:
      phase_ = ModelPhase::kConvertAgain;  // One job at a time per model.
      break;
    default:
      break;
  }
  return actions;
}

void ModelSchedule::settle_after_job(Clock::time_point now) {
  // Changed and settled while converting: settle from the job's end (the change is older). Still
  // settling: the window runs on.
  if (phase_ == ModelPhase::kConvertAgain) {
    if (window_) {
      window_->touch(now, false);
    } else {
      window_ = SettleWindow::opened(now, false);
    }
  }
  phase_ = ModelPhase::kSettling;
}

ModelActions ModelSchedule::job_finished(Clock::time_point now, JobResult result, bool live) {
  live_ = live;
  if (!converting()) return {};
  ModelActions actions;
  if (result == JobResult::kRetryable) {
    ++attempts_;
    retry_delay_ = attempts_ == 1 ? kFirstRetryDelay : std::min(retry_delay_ * 2, kLongestRetryDelay);
    actions.retry_in = retry_delay_;
    actions.publish_error = attempts_ == 1;  // One ERROR per outage, not one per attempt.
    if (phase_ == ModelPhase::kConverting) {
      phase_ = ModelPhase::kRetryAfter;
      retry_due_ = now + retry_delay_;
    } else {
      settle_after_job(now);  // A newer save is tried after its settle; the back-off goes on if it fails too.
    }
    return actions;
  }
  attempts_ = 0;
  switch (result) {
    case JobResult::kVanished:
      phase_ = ModelPhase::kRemoved;
      window_.reset();
      actions.remove = true;
      return actions;
    case JobResult::kRecreated:
      phase_ = ModelPhase::kConvertAgain;  // Settle from now: the new file is converted.
      settle_after_job(now);
      return actions;
    case JobResult::kRejected:
      // A newer save that has already settled supersedes the rejected content: nothing said of it.
      actions.publish_error = phase_ != ModelPhase::kConvertAgain;
      break;
    default:
      break;
  }
  if (phase_ == ModelPhase::kConverting) {
    phase_ = live_ ? ModelPhase::kLive : ModelPhase::kIdle;
  } else {
    settle_after_job(now);
  }
  return actions;
}

ModelActions ModelSchedule::request() const {
  ModelActions actions;
  actions.publish_live = live_ && phase_ != ModelPhase::kRemoved;
  return actions;
}

ModelActions ModelSchedule::removed() {
  ModelActions actions;
  actions.remove = phase_ != ModelPhase::kRemoved;
  actions.discard_prepared = prepare_ == Prepare::kHeld;
  prepare_ = Prepare::kNone;
  phase_ = ModelPhase::kRemoved;
  window_.reset();
  return actions;
}

}  // namespace rdtf::daemon
