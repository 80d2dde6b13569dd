#include "ports.h"

#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>

#include <lcm/lcm-cpp.hpp>

#include "config.h"
#include "lcm_ready.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::daemon {

void log_line(const std::string& text);

ConversionOutcome run_job(const ConversionJob& job) {
  try {
    return run_conversion(job);
  } catch (const std::exception& error) {
    // No exception crosses a thread: an internal failure becomes a rejection with its reason.
    ConversionOutcome outcome;
    outcome.model_id = job.model_id;
    outcome.source = job.source;
    outcome.cache_key = job.cache_key;
    outcome.kind = ConversionOutcome::Kind::kRejected;
    outcome.prepared = job.prepare;  // The model's schedule waits for a prepared job's end as such.
    outcome.diagnostics.set_file(job.source.string());
    outcome.diagnostics.error(codes::INTERNAL_ERROR, "", error.what());
    return outcome;
  }
}

void run_after_handover(const std::function<void()>& after) noexcept {
  if (!after) return;
  try {
    after();
  } catch (const std::exception& error) {
    // Only an optimisation failed (the result cache): the revision stands; say so and go on.
    try {
      log_line(std::string("work after a conversion failed: ") + error.what());
    } catch (...) {
    }
  } catch (...) {
  }
}

ThreadJobRunner::ThreadJobRunner(int workers, bool express_worker)
    : wake_fd_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  for (int i = 0; i < workers; ++i) workers_.emplace_back([this] { worker_loop(false); });
  if (express_worker) workers_.emplace_back([this] { worker_loop(true); });
}

ThreadJobRunner::~ThreadJobRunner() {
  stop();
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

void ThreadJobRunner::submit(ConversionJob job) {
  {
    std::lock_guard lock(mutex_);
    // A commit is all a settled save still waits for: it goes before the conversions queued (in a
    // first scan of thousands of models, nothing would be published until every one was converted,
    // and their results would wait in memory).
    if (job.commit) {
      jobs_.push_front(std::move(job));
    } else {
      jobs_.push_back(std::move(job));
    }
  }
  // Every worker: the one woken by notify_one might be the express one, which may not take it.
  work_ready_.notify_all();
}

std::deque<ConversionJob>::iterator ThreadJobRunner::next_job(bool express_only) {
  if (!express_only) return jobs_.begin();
  return std::find_if(jobs_.begin(), jobs_.end(), [](const ConversionJob& job) { return job.express; });
}

void ThreadJobRunner::wake() {
  const std::uint64_t one = 1;
  [[maybe_unused]] auto written = ::write(wake_fd_, &one, sizeof(one));
}

std::vector<ConversionOutcome> ThreadJobRunner::take(std::size_t max, bool& more) {
  std::uint64_t value = 0;
  [[maybe_unused]] auto read = ::read(wake_fd_, &value, sizeof(value));
  std::vector<ConversionOutcome> outcomes;
  {
    std::lock_guard lock(mutex_);
    while (!outcomes_.empty() && outcomes.size() < max) {
      outcomes.push_back(std::move(outcomes_.front()));
      outcomes_.pop_front();
    }
    more = !outcomes_.empty();
  }
  // The rest in the next turns of the loop, between requests and heartbeats.
  if (more) wake();
  return outcomes;
}

void ThreadJobRunner::stop() {
  {
    std::lock_guard lock(mutex_);
    jobs_.clear();
    stopping_ = true;
  }
  work_ready_.notify_all();
  for (auto& worker : workers_) worker.join();
  workers_.clear();
}

void ThreadJobRunner::worker_loop(bool express_only) {
  for (;;) {
    ConversionJob job;
    {
      std::unique_lock lock(mutex_);
      work_ready_.wait(lock, [&] { return stopping_ || next_job(express_only) != jobs_.end(); });
      const auto next = next_job(express_only);
      if (next == jobs_.end()) return;  // Stopping, and nothing left it may finish.
      job = std::move(*next);
      jobs_.erase(next);
    }
    ConversionOutcome outcome = run_job(job);
    std::function<void()> after = std::move(outcome.after_handover);
    outcome.after_handover = nullptr;
    {
      std::lock_guard lock(mutex_);
      outcomes_.push_back(std::move(outcome));
    }
    wake();
    // The loop publishes the revision meanwhile (the other processor, on a machine of two).
    run_after_handover(after);
  }
}

namespace {

// LCM, subscribed to the daemon's channels. Handlers get the raw bytes: BusInput decodes them
// only after its schema check (never lcm-gen's decoder alone).
class LcmBus final : public Bus {
 public:
  LcmBus(std::unique_ptr<lcm::LCM> lcm, BusHandlers handlers) : lcm_(std::move(lcm)), handlers_(std::move(handlers)) {}

  void subscribe(const std::string& prefix) {
    // LCM's channel argument is a regular expression: the prefix's '.' (the one character of a
    // prefix that means something there, check_config) must match itself only.
    std::string literal;
    for (const char c : prefix) literal += c == '.' ? std::string("\\.") : std::string(1, c);
    lcm_->subscribe(literal + "/REQUEST", &LcmBus::on_request, this);
    lcm_->subscribe(literal + "/.*/JOINT_COMMAND", &LcmBus::on_command, this);
    lcm_->subscribe(literal + "/BLOB_REQUEST", &LcmBus::on_blob_request, this);
  }
  int send(const std::string& channel, const std::uint8_t* data, unsigned int size) override {
    return lcm_->publish(channel, data, size);
  }
  int fd() const override { return lcm_->getFileno(); }
  std::size_t receive(std::size_t max) override {
    std::size_t handled = 0;
    while (handled < max && lcm_->handleTimeout(0) > 0) ++handled;
    return handled;
  }

 private:
  // BusInput catches what its handlers throw (counted and logged as drops); these catch the rest,
  // so that no exception unwinds through liblcm's C frames.
  void dispatch(const BusHandlers::Datagram& handler, const lcm::ReceiveBuffer* buffer,
                const std::string& channel) noexcept {
    try {
      handler(channel, buffer->data, buffer->data_size);
    } catch (...) {
      ++failures_;
      try {
        log_line("an LCM handler failed outside the bus input (" + std::to_string(failures_) + " since start)");
      } catch (...) {
      }
    }
  }
  void on_request(const lcm::ReceiveBuffer* buffer, const std::string& channel) noexcept {
    dispatch(handlers_.request, buffer, channel);
  }
  void on_command(const lcm::ReceiveBuffer* buffer, const std::string& channel) noexcept {
    dispatch(handlers_.command, buffer, channel);
  }
  void on_blob_request(const lcm::ReceiveBuffer* buffer, const std::string& channel) noexcept {
    dispatch(handlers_.blob_request, buffer, channel);
  }

  std::unique_ptr<lcm::LCM> lcm_;
  BusHandlers handlers_;
  std::uint64_t failures_ = 0;
};

}  // namespace

std::unique_ptr<Bus> open_lcm_bus(const DaemonConfig& config, BusHandlers handlers, std::string& error) {
  auto lcm = std::make_unique<lcm::LCM>(config.lcm_url);
  error = lcm_safe::lcm_receive_problem(*lcm, config.lcm_url);
  if (!error.empty()) return nullptr;
  auto bus = std::make_unique<LcmBus>(std::move(lcm), std::move(handlers));
  bus->subscribe(config.channel_prefix);
  return bus;
}

}  // namespace rdtf::daemon
