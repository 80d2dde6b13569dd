// What rdtfd sends and answers on the bus: descriptions, STATUS, errors, requests.
#include <unistd.h>

#include <rdtf/model_error_t.hpp>
#include <rdtf/status_t.hpp>

#include "daemon.h"
#include "daemon_internal.h"
#include "rdtf/version.h"
#include "messages.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::daemon {

std::unique_ptr<Bus> Daemon::make_bus(const DaemonConfig& config, std::string& error) {
  BusHandlers handlers{
      [this](const std::string& channel, const void* data, std::size_t size) { bus_.request_datagram(channel, data, size); },
      [this](const std::string& channel, const void* data, std::size_t size) { bus_.command_datagram(channel, data, size); },
      [this](const std::string& channel, const void* data, std::size_t size) {
        bus_.blob_request_datagram(channel, data, size);
      }};
  return ports_.bus(config, std::move(handlers), error);
}

void Daemon::install_bus(std::unique_ptr<Bus> bus) {
  Bus* sender = bus.get();
  publisher_ = std::make_unique<Publisher>(
      [sender](const std::string& channel, const std::uint8_t* data, unsigned int size) {
        return sender->send(channel, data, size);
      },
      config_.chunk_rate_bytes_per_s, kBurstReceiveBufferBytes);
  publisher_->set_clock([clock = clock_] { return clock->now(); });
  publisher_->on_event([this](const PublisherEvent& event) { on_publisher_event(event); });
  blobs_.publisher_replaced();
  lcm_ = std::move(bus);
}

void Daemon::publish_daemon_error(const std::string& code, const std::string& file, const std::string& message) {
  Diagnostics diag(file);
  diag.error(code, "", message);
  rdtf::model_error_t error;
  error.utime = now_utime();
  error.source_path = file;
  error.live_revision = 0;
  error.diagnostics = to_messages(diag);
  publisher_->publish(config_.channel_prefix + "/ERROR", error);
}

void Daemon::publish_error(ModelRecord& record, rdtf::model_error_t error) {
  publisher_->publish(channel(record.id, "ERROR"), error);
  if (!record.live) record.refusal = std::make_shared<const rdtf::model_error_t>(std::move(error));
}

void Daemon::on_publisher_event(const PublisherEvent& event) {
  log_line(event.text);
  // While sends fail nothing can be told over LCM; once they work, the outage is reported.
  if (event.kind == PublisherEvent::Kind::kSendRecovered) publish_daemon_error(codes::LCM_SEND_FAILED, "", event.text);
}

std::string Daemon::channel(const std::string& model_id, const char* kind) const {
  return config_.channel_prefix + "/" + model_id + "/" + kind;
}

std::size_t Daemon::publish_model(const ModelRecord& record, std::string* unpublished) {
  if (!record.live) return 0;
  LiveTexts texts;
  std::string why;
  if (!live_texts(record, texts, why)) {
    why = "not publishing " + record.id + " revision " + std::to_string(record.revisions) + ": " + why;
    if (unpublished != nullptr) {
      *unpublished = std::move(why);
    } else {
      log_line(why);
    }
    return 0;
  }
  // The report comes first: a description is only ever published with its verdict.
  if (record.live->validation) {
    publisher_->publish(channel(record.id, "VALIDATION"),
                        make_validation_report(record.id, record.revisions, record.live->content_hash,
                                               *record.live->validation, config_.max_chunk_bytes));
  }
  // The manifest before the description: a subscriber that has the description knows what to fetch.
  if (!record.live->files.empty()) {
    for (const auto& part : make_manifests(record.id, record.revisions, record.live->content_hash, record.live->files,
                                           config_.max_chunk_bytes)) {
      publisher_->publish(channel(record.id, "MANIFEST"), part);
    }
  }
  const auto messages = make_description(record, texts, config_.max_chunk_bytes);
  for (const auto& chunk : messages.json_chunks) publisher_->publish(channel(record.id, "DESCRIPTION_CHUNK"), chunk);
  for (const auto& chunk : messages.urdf_chunks) publisher_->publish(channel(record.id, "URDF_CHUNK"), chunk);
  publisher_->publish(channel(record.id, "DESCRIPTION"), messages.description);
  for (const auto& table : make_inertia_tables(record, config_.max_chunk_bytes)) {
    publisher_->publish(channel(record.id, "INERTIA"), table);
  }
  return 1;
}

std::size_t Daemon::publish_all() {
  std::size_t count = 0;
  std::size_t failed = 0;
  std::string first_failure;
  for (const auto& [source, record] : registry_.all()) {
    std::string why;
    const std::size_t published = publish_model(record, &why);
    count += published;
    if (published == 0 && !why.empty() && failed++ == 0) first_failure = std::move(why);
  }
  // One line a republication, not one a model: out of descriptors, every model's texts fail to
  // read at once (s106fd D5: 66 lines every period).
  if (failed > 0) {
    log_line(first_failure + (failed > 1 ? " (and " + std::to_string(failed - 1) + " more models not published now)" : ""));
  }
  return count;
}

void Daemon::publish_status() {
  rdtf::status_t status;
  status.utime = now_utime();
  status.version = version_line("rdtfd");
  status.pid = static_cast<std::int32_t>(::getpid());
  status.uptime = std::chrono::duration<double>(clock_->now() - started_).count();
  status.num_watched_dirs = static_cast<std::int32_t>(config_.watch.size());
  status.conversions = counters_.conversions;
  status.rejections = counters_.rejections;
  status.skipped_unchanged = counters_.skipped_unchanged;
  status.rescans = counters_.rescans;
  std::int32_t pending = 0;  // Models settling, waiting for a writer or a retry, or converting.
  for (const auto& [source, record] : registry_.all()) {
    if (record.live) status.model_ids.push_back(record.id);
    if (record.schedule.pending()) ++pending;
  }
  status.pending = pending;
  status.num_models = static_cast<std::int32_t>(status.model_ids.size());
  status.dropped_messages = static_cast<std::int64_t>(bus_.dropped());
  status.coalesced_requests = static_cast<std::int64_t>(request_throttle_.coalesced());
  status.send_queue_bytes = static_cast<std::int64_t>(publisher_->queued_bytes());
  status.send_dropped = static_cast<std::int64_t>(publisher_->dropped());
  status.live_real_time_factor = 0;  // lcm-gen leaves fields uninitialised.
  status.simulations_behind = 0;
  status.simulations_failed = 0;
  const BlobCounters& blobs = blobs_.counters();
  status.blob_requests = blobs.requests;
  status.blob_chunks_sent = blobs.chunks_sent;
  status.blob_bytes_sent = blobs.bytes_sent;
  status.blob_unavailable = blobs.unavailable;
  status.blob_requests_dropped = blobs.dropped + static_cast<std::int64_t>(bus_.blob_requests_undecodable());
  if (simulation_) {
    const LiveTiming timing = simulation_->timing();
    status.live_real_time_factor = timing.real_time_factor;
    status.simulations_behind = timing.behind;
    status.simulations_failed = static_cast<std::int64_t>(timing.failed);
  }
  // Ahead of anything queued: the heartbeat stays on time under any backlog.
  publisher_->publish(config_.channel_prefix + "/STATUS", status, Publisher::Priority::kUrgent);
}

// BusInput catches what its handlers throw (counted and logged as drops); these catch the rest, so
// that no exception unwinds through liblcm's C frames.
void Daemon::on_request(const rdtf::request_t& request) {
  // Only ids of models that exist are remembered by the throttle, so a flood of made-up ids
  // costs nothing.
  if (!request.model_id.empty() && registry_.find_id(request.model_id) == nullptr) return;
  if (!request_throttle_.admit(request.model_id, clock_->now())) return;
  // Cut, not escaped: log_line escapes every line it writes (escaping here too would double it).
  answer_request(request.model_id, request.requester.substr(0, 80));
}

void Daemon::republish_refusal(const ModelRecord& record) {
  rdtf::model_error_t again = *record.refusal;
  again.utime = now_utime();
  publisher_->publish(channel(record.id, "ERROR"), again);
}

// `requester` is already escaped for the log (it comes from the bus).
void Daemon::answer_request(const std::string& model_id, const std::string& requester) {
  const auto start = clock_->now();
  if (model_id.empty()) {
    const std::size_t count = publish_all();
    std::size_t refusals = 0;
    for (auto& [source, record] : registry_.all()) {
      if (!record.live && record.refusal) {
        republish_refusal(record);
        ++refusals;
      }
    }
    log_line("republished every model on request of '" + requester + "' (" + std::to_string(count) + " models" +
             (refusals > 0 ? ", and the ERROR of " + std::to_string(refusals) + " with no live revision" : std::string()) +
             "), queued in " + since(start));
    return;
  }
  if (ModelRecord* record = registry_.find_id(model_id)) {
    if (!record->live && record->refusal) {
      republish_refusal(*record);
      log_line("answered the request of '" + requester + "' for " + record->id +
               " with the ERROR of its last save (no revision of it is live)");
      return;
    }
    if (record->schedule.request().publish_live) publish_model(*record);
    log_line("republished " + record->id + " on request of '" + requester + "', queued in " + since(start));
  }
}

// Requests that came while the same model's last answer was recent: one answer for all of them.
void Daemon::answer_deferred_requests(Clock::time_point now) {
  for (const std::string& model_id : request_throttle_.take_due(now)) {
    answer_request(model_id, "(repeated requests, " + std::to_string(request_throttle_.coalesced()) +
                                 " answered together since start)");
  }
}

}  // namespace rdtf::daemon
