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
  if (!window_) {
    window_ = SettleWindow::opened(now, still_open);
  } else if (change == FileChange::kClosed) {
    window_->closed(now);
  } else {
    window_->touch(now, still_open);
  }
  return {};
}

ModelActions ModelSchedule::timer(Clock::time_point now, const SettlePolicy& policy, bool writer_open) {
  const auto due = deadline(policy);
  if (!due || *due > now) return {};
  if (phase_ == ModelPhase::kRetryAfter) {
    phase_ = ModelPhase::kSettling;  // The attempt goes through the settle and the writer check too.
    window_ = SettleWindow::opened(now, false);
    return {};
  }
  if (writer_open) {
    // Look again a settle period later (the writer's close is an event that comes sooner).
    window_ = SettleWindow::opened(now, false);
    if (phase_ == ModelPhase::kSettling) phase_ = ModelPhase::kWaitingForWriter;
    return {};
  }
  window_.reset();
  ModelActions actions;
  switch (phase_) {
    case ModelPhase::kSettling:
    case ModelPhase::kWaitingForWriter:
      phase_ = ModelPhase::kConverting;
      actions.start_job = true;
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
  phase_ = ModelPhase::kRemoved;
  window_.reset();
  return actions;
}

}  // namespace rdtf::daemon
