// rdtfd's scheduling: each model's state machine (model_schedule.h) fed with timer expiries and job
// outcomes; jobs handed to the runner; outcomes applied to the registry and published.
#include <algorithm>

#include "daemon.h"
#include "daemon_internal.h"
#include "delta_messages.h"
#include "messages.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/glb.h"

namespace rdtf::daemon {
namespace {

bool same_result(const ModelRecord& record, const ConvertedModel& candidate) {
  const ConvertedModel& live = *record.live;
  return live.content_hash == candidate.content_hash && live.written == candidate.written &&
         live.output_path == candidate.output_path && live.urdf_path == candidate.urdf_path &&
         live.files == candidate.files && same_live_texts(record, candidate) &&
         live.validation.has_value() == candidate.validation.has_value() &&
         (!live.validation || live.validation->passed == candidate.validation->passed);
}

// Whether `path` is a regular file reached from `root` through real folders only (no symlink on
// the way, none at the end): where read_beneath would find a model.
bool regular_file_below(const std::filesystem::path& root, const std::filesystem::path& path) {
  const auto relative = path.lexically_relative(root);
  if (relative.empty() || *relative.begin() == "..") return false;
  std::filesystem::path at = root;
  std::error_code ec;
  for (auto it = relative.begin(); it != relative.end(); ++it) {
    at /= *it;
    const auto status = std::filesystem::symlink_status(at, ec);
    const bool last = std::next(it) == relative.end();
    if (ec || !(last ? std::filesystem::is_regular_file(status) : std::filesystem::is_directory(status))) return false;
  }
  return true;
}

}  // namespace

void Daemon::file_timer(ModelRecord& record) {
  record.timer = record.schedule.deadline(settle_policy());
  if (record.timer) timers_.emplace(*record.timer, record.source);
}

void Daemon::unfile_timer(ModelRecord& record) {
  if (record.timer) timers_.erase({*record.timer, record.source});
  record.timer.reset();
}

void Daemon::fire_timers(Clock::time_point now) {
  // The models due now, taken first: a transition files the model's next deadline, which is later.
  std::vector<std::filesystem::path> due;
  for (auto it = timers_.begin(); it != timers_.end() && it->first <= now; ++it) due.push_back(it->second);
  for (const auto& source : due) {
    ModelRecord* record = registry_.find(source);
    if (record == nullptr) continue;
    const bool writer_open = waiting_for_writer(*record, now);
    const ModelActions actions =
        transition(*record, [&](ModelSchedule& schedule) { return schedule.timer(now, settle_policy(), writer_open); });
    if (actions.discard_prepared) record->prepared.reset();
    if (actions.use_prepared && record->prepared) {
      ConversionOutcome prepared = std::move(*record->prepared);
      record->prepared.reset();
      use_prepared(*record, std::move(prepared));
    }
    if (actions.start_job) start_job(*record);
  }
}

void Daemon::on_settling(ModelRecord& record, const ModelActions& actions) {
  if (actions.discard_prepared) record.prepared.reset();  // Its stage folder goes with it.
  if (config_.convert_while_settling && record.schedule.can_prepare()) to_prepare_.push_back(record.source);
}

void Daemon::start_prepared_jobs(Clock::time_point now) {
  // Taken once the events that came together are all handled: a .gltf and its .bin written one
  // after the other give one prepared job, not one the second event makes stale at once.
  std::sort(to_prepare_.begin(), to_prepare_.end());
  to_prepare_.erase(std::unique(to_prepare_.begin(), to_prepare_.end()), to_prepare_.end());
  for (const auto& source : to_prepare_) {
    ModelRecord* record = registry_.find(source);
    if (record == nullptr || !record->schedule.can_prepare() || waiting_for_writer(*record, now)) continue;
    if (!state_known(*record, nullptr)) continue;  // The deadline's job says why, and tries again.
    record->schedule.begin_prepare();
    ConversionJob job = make_job(*record);
    job.prepare = true;
    runner_->submit(std::move(job));
  }
  to_prepare_.clear();
}

bool Daemon::waiting_for_writer(const ModelRecord& record, Clock::time_point now) const {
  // The model file, a file it refers to, or (never converted yet: its .bin unknown) any file in its folder.
  std::vector<std::filesystem::path> files = record.dependencies;
  files.push_back(record.source);
  const auto folder = record.source.parent_path();
  return open_for_writing_.holds(files, record.dependencies.empty() ? &folder : nullptr, now, config_.max_open_wait);
}

void Daemon::drop_model(const std::filesystem::path& source, std::chrono::microseconds checked) {
  const auto start = clock_->now();
  ModelRecord* record = registry_.find(source);
  if (record == nullptr) return;
  if (record->live) publisher_->publish(channel(record->id, "REMOVED"), make_model_removed(*record));
  if (simulation_) simulation_->remove(record->id);
  blobs_.remove_model(record->id);
  log_line("removed " + record->id + " in " +
           milliseconds(checked + std::chrono::duration_cast<std::chrono::microseconds>(clock_->now() - start)) +
           (record->live ? " (revision " + std::to_string(record->revisions) + " was live)" : ""));
  unfile_timer(*record);
  registry_.erase(source);
}

void Daemon::start_job(ModelRecord& record) {
  ConversionJob job = make_job(record);
  // Numbers known before anything of this run is written: read after this job's outputs, a state
  // still absent would find them and take them for an earlier run's (numbered from the clock).
  state_known(record, &job.not_now);
  runner_->submit(std::move(job));
}

bool Daemon::state_known(ModelRecord& record, std::string* why) {
  if (!record.state_unread) return true;
  const std::string line = restore_revisions(config_.output, record);
  if (record.state_unread) {
    if (why != nullptr) *why = line;
    return false;
  }
  if (!line.empty()) log_line(line);
  return true;
}

ConversionJob Daemon::make_job(const ModelRecord& record) const {
  ConversionJob job;
  job.model_id = record.id;
  job.root = root_of(record.source);
  job.source = record.source;
  LiveTexts live;
  std::string why;
  if (record.live && !record.live->files.empty()) {
    job.live_files = record.live->files;
  } else if (record.live && live_texts(record, live, why)) {
    job.live_rdtf_json = std::move(live.rdtf_json);
    job.live_urdf = std::move(live.urdf);
  }
  job.max_read_bytes = config_.max_read_bytes;
  job.budget = read_budget_;
  job.output_dir = config_.output / record.id;
  job.output_root = config_.output;
  job.options = config_.convert;
  job.previous_hash = record.last_hash;
  job.write_failed = config_.publish_failed;
  job.cache = cache_;
  job.cache_key = cache_key_;
  if (config_.validate) {
    job.validation = validation_options(config_);
    job.validation->cancel = &cancel_validations_;
    job.verdict = record.verdict;
  }
  if (config_.urdf) {
    UrdfOptions urdf;
    urdf.y_up = config_.urdf_y_up;
    job.urdf = urdf;
  }
  job.express = is_small(record);
  return job;
}

// Whether the model and the files it named when last converted hold at most kExpressBytes. A .gltf
// never converted is not: the .bin beside it is not known yet, and may be large.
bool Daemon::is_small(const ModelRecord& record) const {
  if (record.dependencies.empty() && !has_glb_extension(record.source)) return false;
  std::uint64_t bytes = 0;
  std::error_code error;
  for (const std::filesystem::path& file : record.dependencies) {
    bytes += std::filesystem::file_size(file, error);
    if (error) return false;
  }
  bytes += std::filesystem::file_size(record.source, error);
  return !error && bytes <= kExpressBytes;
}

void Daemon::use_prepared(ModelRecord& record, ConversionOutcome outcome) {
  if (outcome.staged) {
    // Its outputs are staged: a worker moves them into place (fsyncs) and hands it back.
    ConversionJob job = make_job(record);
    job.commit = std::make_shared<ConversionOutcome>(std::move(outcome));
    job.express = true;  // Renames and fsyncs only.
    runner_->submit(std::move(job));
    return;
  }
  // Nothing to move into place (rejected, unchanged, from the cache, failed unwritten): as a job's.
  outcome.prepared = false;
  outcome.while_settling = true;
  apply(std::move(outcome));
}

// A job started while the model settled ended: its result waits for the deadline, serves now
// (the deadline came while it ran), or is dropped (a file changed after it read them).
void Daemon::apply_prepared(ConversionOutcome outcome) {
  ModelRecord* record = registry_.find(outcome.source);
  if (record == nullptr) return;
  // A verdict depends only on what it was computed from: kept whatever becomes of this result.
  if (outcome.verdict) record->verdict = outcome.verdict;
  // Prepared under settings a reload has since changed: dropped, the deadline converts afresh.
  const bool usable = !outcome.cancelled && !outcome.retry && outcome.kind != ConversionOutcome::Kind::kVanished &&
                      outcome.cache_key == cache_key_;
  const auto now = clock_->now();
  const ModelActions actions =
      transition(*record, [&](ModelSchedule& schedule) { return schedule.prepare_finished(now, usable); });
  if (actions.use_prepared) {
    use_prepared(*record, std::move(outcome));
  } else if (record->schedule.holds_prepared()) {
    record->prepared = std::move(outcome);
  }
  if (actions.start_job) start_job(*record);
  // Dropped as stale: the files may have settled into something to prepare again.
  on_settling(*record, {});
  start_prepared_jobs(now);
}

void Daemon::handle_outcomes(std::size_t max_outcomes) {
  bool more = false;
  for (auto& outcome : runner_->take(max_outcomes, more)) apply(std::move(outcome));
}

void Daemon::apply(ConversionOutcome outcome) {
  if (outcome.prepared) {
    apply_prepared(std::move(outcome));
    return;
  }
  ModelRecord* record = registry_.find(outcome.source);
  if (record == nullptr) return;
  const std::string id = record->id;
  if (outcome.verdict) record->verdict = outcome.verdict;
  if (!outcome.cache_note.empty()) {
    ++counters_.cache_refused;
    log_line(id + ": " + outcome.cache_note);
  }
  JobResult result = JobResult::kDone;
  // Converted under settings a reload changed while it ran (the reload's rescan found the model
  // busy): its result is not the running config's, and applying it marked the content converted
  // for good (s80cfg D1). Nothing of it is applied; the model is converted again.
  const bool stale = outcome.cache_key != cache_key_ && !outcome.cancelled &&
                     outcome.kind != ConversionOutcome::Kind::kVanished;
  if (stale) {
    log_line(id + ": converted under the settings before the last reload; converting again");
    record->last_hash.clear();
    result = JobResult::kRecreated;  // Settles from now, then converts: what a new save gets.
  } else switch (outcome.kind) {
    case ConversionOutcome::Kind::kConverted:
      if (!state_known(*record, nullptr)) {
        // A job started before this record's state became unreadable (the record made again under
        // the same path meanwhile): never numbered blind. Its outputs are written; the same
        // content comes again as a job once the state can be read.
        outcome.diagnostics = Diagnostics{};
        outcome.diagnostics.error(codes::IO_ERROR, "",
                                  "revision state of " + id + " cannot be read now; it is read again before a "
                                  "revision of it is numbered");
        result = JobResult::kRetryable;
        break;
      }
      apply_converted(outcome, *record);
      break;
    case ConversionOutcome::Kind::kUnchanged:
      ++counters_.skipped_unchanged;
      record->dependencies = outcome.dependencies;
      break;
    case ConversionOutcome::Kind::kRejected:
      ++counters_.rejections;
      if (outcome.retry) {
        result = JobResult::kRetryable;  // last_hash kept: the same content is converted again.
        break;
      }
      result = JobResult::kRejected;
      record->last_hash = outcome.content_hash;
      // What it named, and what was named before: a .gltf too broken to name anything (cut short)
      // names no .bin, and the save that repairs it writes the .bin just after (Blender): that event
      // must still reach this model, or the repair converted with the old .bin was the last word.
      for (const auto& file : outcome.dependencies) {
        if (std::find(record->dependencies.begin(), record->dependencies.end(), file) == record->dependencies.end()) {
          record->dependencies.push_back(file);
        }
      }
      log_line("rejected " + id + " in " + milliseconds(outcome.duration) + ": " +
               first_error(outcome.diagnostics) +
               (record->live ? "; still serving revision " + std::to_string(record->revisions) : ""));
      break;
    case ConversionOutcome::Kind::kVanished:
      // Recreated while its conversion found it gone: the new file is converted.
      result = regular_file_below(root_of(outcome.source), outcome.source) ? JobResult::kRecreated : JobResult::kVanished;
      break;
  }
  const ModelActions actions = transition(*record, [&](ModelSchedule& schedule) {
    return schedule.job_finished(clock_->now(), result, record->live.has_value());
  });
  if (actions.retry_in) {
    const Diagnostic* failure = outcome.diagnostics.first_error();
    const bool unread = failure != nullptr && failure->code == codes::IO_ERROR;
    log_line((unread ? "could not read " + id + " now: " : "could not write the outputs of " + id + ": ") +
             first_error(outcome.diagnostics) + "; trying again in " +
             std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(*actions.retry_in).count()) +
             " ms (attempt " + std::to_string(record->schedule.attempts()) + ")");
  }
  if (actions.publish_error) publish_error(*record, make_model_error(*record, outcome.content_hash, outcome.diagnostics, config_.max_chunk_bytes));
  if (actions.remove) drop_model(outcome.source, outcome.duration);
}

// A conversion that gave a result: a new revision (numbered, saved, published with its verdict and
// delta), the same result as the live one (a reload), or one the dynamics check rejected.
void Daemon::apply_converted(ConversionOutcome& outcome, ModelRecord& record) {
  const std::string id = record.id;
  if (outcome.from_cache) ++counters_.from_cache;
  const ConvertedModel& candidate = *outcome.converted;
  const bool failed = candidate.validation && !candidate.validation->passed;
  record.last_hash = outcome.content_hash;
  record.dependencies = outcome.dependencies;
  if (record.live && same_result(record, candidate)) {
    // A reload changed settings this model's result does not depend on.
    ++counters_.skipped_unchanged;
    log_line("unchanged " + id + " in " + milliseconds(outcome.duration) + ": still revision " +
             std::to_string(record.revisions));
    return;
  }
  // The first conversion after a restart that gives the result the earlier run served keeps
  // its number; any other content that gets a VALIDATION gets a number of its own, accepted or
  // not, saved before anything publishes it (docs/lcm.md, "Revision numbers").
  const std::string candidate_result = result_digest(candidate);
  const bool kept = !record.live && record.restored &&
                    record.restored->content_hash == candidate.content_hash &&
                    record.restored->result_digest == candidate_result;
  const std::optional<StoredRevision> previous = stored_live(record);
  const std::int64_t number = kept ? record.restored->revision : ++record.numbered;
  // The event loop's share of the latency, for the log line: from the worker's end to here, the
  // revision state saved, the messages queued and sent.
  const auto picked_up = std::chrono::steady_clock::now();
  if (!kept) {
    // The live revision after this one: this one, unless the check rejects it unpublished.
    const std::optional<StoredRevision> live =
        failed && !config_.publish_failed
            ? previous
            : StoredRevision{number, candidate.content_hash, candidate_result, candidate.facts};
    const std::string why = save_revisions(config_.output, record, live);
    if (!why.empty()) {
      log_line("could not save the revision state of " + id + " (revision " + std::to_string(number) +
               " may be numbered again after a restart): " + why);
    }
  }
  // Warnings of a conversion that succeeded: one log line each, and on LCM with the verdict
  // (with the infos, which every Blender export has and which would only crowd the log).
  for (const Diagnostic& d : outcome.diagnostics.all()) {
    if (d.severity == Severity::kWarning) log_line("warning " + id + " revision " + std::to_string(number) + ": " + format(d));
  }
  // The verdict with the conversion's warnings: published before every description of the
  // revision, so a subscriber that starts late gets the report too.
  std::optional<ValidationSummary> report = candidate.validation;
  if (report) report->diagnostics.append(outcome.diagnostics);
  if (failed && !config_.publish_failed) {
    publisher_->publish(channel(id, "VALIDATION"),
                        make_validation_report(id, number, outcome.content_hash, *report, config_.max_chunk_bytes));
    ++counters_.rejections;
    log_line("rejected " + id + " revision " + std::to_string(number) + " (dynamics) in " +
             milliseconds(outcome.duration) + ": " + candidate.validation->summary_line +
             (outcome.verdict_reused ? " (the verdict of the same robot, reused)" : "") +
             (record.live ? "; still serving revision " + std::to_string(record.revisions) : ""));
    publish_error(record, make_model_error(record, outcome.content_hash, candidate.validation->diagnostics, config_.max_chunk_bytes));
    return;
  }
  ++counters_.conversions;
  std::vector<ElementChange> changes;
  if (!kept) changes = diff_robots(previous ? previous->facts : RobotFacts{}, candidate.facts);
  record.revisions = number;
  record.restored.reset();
  record.live_result = candidate_result;
  record.live = std::move(outcome.converted);
  record.refusal.reset();
  record.texts_on_disk = false;
  record.live->validation = std::move(report);
  // From now on the previous revision's files are no longer served (docs/lcm.md, "Files and blobs").
  blobs_.set_model(id, config_.output / id, record.live->files);
  const auto saved = std::chrono::steady_clock::now();
  // Sent now, not at the end of this turn of the loop: nothing below is needed for the
  // description, and the live simulation is rebuilt after it (on the host's own thread).
  publish_model(record);
  release_live_texts(record);
  publisher_->drain(clock_->now());
  const auto sent = std::chrono::steady_clock::now();
  auto ms = [](auto duration) { return milliseconds(std::chrono::duration_cast<std::chrono::microseconds>(duration)); };
  const StageTimes& stages = outcome.stages;
  log_line("converted " + id + " revision " + std::to_string(record.revisions) + " (" +
           std::to_string(record.live->robot.links.size()) + " links, " +
           std::to_string(record.live->robot.joints.size()) + " joints" +
           (record.live->validation ? std::string(", dynamics ") + (failed ? "FAILED" : "passed") : "") +
           (outcome.verdict_reused ? ", verdict reused" : "") + ") in " + milliseconds(outcome.duration) +
           (outcome.from_cache ? " from the result cache" : "") + (outcome.while_settling ? " while settling" : "") + (kept ? " (the result the earlier run served: its number kept)" : "") +
           "; stages: read " + milliseconds(stages.read) + ", convert " + milliseconds(stages.convert) + ", check " +
           milliseconds(stages.check) + ", write " + milliseconds(stages.write) + ", cache " + milliseconds(stages.cache) +
           ", picked up " + ms(picked_up - outcome.finished) + ", state saved " + ms(saved - picked_up) + ", sent " +
           ms(sent - saved));
  if (simulation_) {
    if (failed) {
      // A revision that failed the check would blow up in ODE, and the previous one is no
      // longer what is published: no simulation runs until a revision passes.
      simulation_->remove(id);
      log_line("stopped the simulation of " + id + ": revision " + std::to_string(number) +
               " failed the dynamics check");
    } else {
      simulation_->load(id, record.revisions, record.live->content_hash, record.live->robot,
                        live_stepper(*record.live), after_quickstep_failed(*record.live));
    }
  }
  if (!kept) {
    // Once, after the revision's description: what changed since the revision it replaces.
    const DeltaHeader header{id, previous ? previous->revision : 0, previous ? previous->content_hash : "",
                             number, record.live->content_hash};
    for (const auto& part : make_deltas(header, changes, now_utime(), config_.max_chunk_bytes)) {
      publisher_->publish(channel(id, "DELTA"), part);
    }
  }
}

}  // namespace rdtf::daemon
