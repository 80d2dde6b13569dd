// One model's scheduling as a state machine: when it settles, waits for a writer, converts,
// converts again, backs off after a failed write, and goes away. A value: events in (file
// changes, timer expiries, job results, requests), actions out (start a job, publish, drop the
// model); the only timer is deadline(). No I/O, no clock reads, no threads: the daemon feeds it
// what it saw and does what it says, and tests step it with made-up times. docs/daemon.md has the
// state diagram.
#pragma once

#include <chrono>
#include <optional>

#include "settle.h"

namespace rdtf::daemon {

enum class ModelPhase {
  kIdle,                    // Nothing to do; no revision served (never converted, or rejected).
  kLive,                    // Nothing to do; a revision is served.
  kSettling,                // Files changed: converts once they have been quiet (SettleWindow).
  kWaitingForWriter,        // Settled, but a file is still open for writing: looks again a settle later.
  kConverting,              // A job runs.
  kChangedWhileConverting,  // A job runs and the files changed since: settling meanwhile.
  kConvertAgain,            // A job runs and a change has settled: converts again when it ends.
  kRetryAfter,              // The outputs could not be written (disk full): tries again at a deadline.
  kRemoved,                 // The model file is gone: announced, forgotten.
};
const char* phase_name(ModelPhase phase);

enum class FileChange {
  kModified,  // Written, not yet closed by its writer (an in-place save in progress).
  kClosed,    // Closed after writing, created, moved in or out, deleted.
  kTouched,   // Worth a look, with nothing known of writers (a rescan).
};

enum class JobResult {
  kDone,       // Converted (or found unchanged): the daemon applied the result.
  kRejected,   // The content is bad; its ERROR is published unless a newer save already waits.
  kRetryable,  // The environment failed (disk full): the same content is tried again later.
  kVanished,   // The model file was gone when the job read it.
  kRecreated,  // It was gone, and a file is back at its path since.
};

// What the daemon does after a transition (several may be set).
struct ModelActions {
  bool start_job = false;      // Hand a conversion of the model to a worker.
  bool publish_error = false;  // The job's diagnostics on the model's ERROR.
  bool publish_live = false;   // The live revision again (a request).
  bool remove = false;         // Announce REMOVED (when a revision was live) and forget the model.
  // Use the result of the job begin_prepare() announced, held or just finished: commit its staged
  // outputs (or apply it when it wrote none), as a job started now would have.
  bool use_prepared = false;
  bool discard_prepared = false;  // The held prepared result is stale: drop it (and its stage).
  std::optional<Clock::duration> retry_in;  // A back-off was scheduled: attempt `attempts()` failed.
};

class ModelSchedule {
 public:
  // The back-off of failed writes: 200 ms, doubled per failure in a row, at most 3 s.
  static constexpr Clock::duration kFirstRetryDelay = std::chrono::milliseconds(200);
  static constexpr Clock::duration kLongestRetryDelay = std::chrono::milliseconds(3000);

  ModelPhase phase() const { return phase_; }
  // When timer() is due; none when the model waits for nothing but events or a job.
  std::optional<Clock::time_point> deadline(const SettlePolicy& policy) const;
  // Settling, waiting or converting: the models STATUS counts as `pending`.
  bool pending() const;
  bool converting() const;
  int attempts() const { return attempts_; }  // Failed writes in a row.

  ModelActions file_changed(Clock::time_point now, FileChange change);
  // The deadline passed. `writer_open`: a file of the model is still open for writing (and has
  // been for at most max_open_wait).
  ModelActions timer(Clock::time_point now, const SettlePolicy& policy, bool writer_open);
  // The job ended; `live`: a revision is served now (after the daemon applied the result).
  ModelActions job_finished(Clock::time_point now, JobResult result, bool live);
  ModelActions request() const;
  ModelActions removed();  // Its folder is no longer watched.

  // Converting while settling (`convert_while_settling`): once a settling model's files are
  // closed, a job may convert it and stage its outputs ahead of the deadline; the deadline then
  // commits them, unless an event came after the job started (the result is dropped and the model
  // settles on). Whether such a job may start now: settling, the window's files closed, no
  // prepared job running or held, none declined since the last event.
  bool can_prepare() const;
  void begin_prepare();  // The daemon started one (can_prepare() was true).
  // The prepared job ended. `usable`: its result can stand for a conversion of the content (not
  // cancelled, the model not gone, its outputs not refused by the disk).
  ModelActions prepare_finished(Clock::time_point now, bool usable);
  bool holds_prepared() const { return prepare_ == Prepare::kHeld; }

 private:
  enum class Prepare {
    kNone,      // No prepared job.
    kRunning,   // Running, and no event since it started.
    kStale,     // Running, and an event came since it started: its result will be dropped.
    kHeld,      // Done, no event since it started: its result waits for the deadline.
    kDeclined,  // Ended unusable: no other until the next event.
  };
  // A file event while settling: a prepared result no longer shows the files.
  void prepared_superseded(ModelActions& actions);

  // Where a job's end leads when the files changed meanwhile: settle again.
  void settle_after_job(Clock::time_point now);

  ModelPhase phase_ = ModelPhase::kIdle;
  // Events since the model last settled (settling, waiting for a writer, changed while converting,
  // and in kConvertAgain when yet another change came).
  std::optional<SettleWindow> window_;
  Clock::time_point retry_due_{};
  Clock::duration retry_delay_{};
  int attempts_ = 0;
  bool live_ = false;
  // The prepared job, while settling; while converting, kRunning or kStale say that the job
  // converting is the prepared one (adopted at the deadline).
  Prepare prepare_ = Prepare::kNone;
};

}  // namespace rdtf::daemon
