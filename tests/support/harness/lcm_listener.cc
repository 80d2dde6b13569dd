#include "support/harness/lcm_listener.h"

#include <stdexcept>

namespace rdtf::itest {

std::string kind_of(const std::string& channel) { return channel.substr(channel.rfind('/') + 1); }

std::string model_id_of(const std::string& channel) {
  const auto first = channel.find('/');
  const auto last = channel.rfind('/');
  return first == last ? "" : channel.substr(first + 1, last - first - 1);
}

LcmListener::LcmListener(const std::string& channels, const std::string& url, int queue, Handler handler)
    : handler_(std::move(handler)), lcm_(url) {
  if (!lcm_.good()) throw std::runtime_error("cannot open LCM (is this running in tests/support/in_netns.sh?)");
  auto* subscription = lcm_.subscribe(channels, &LcmListener::on_message, this);
  subscription->setQueueCapacity(queue);
  thread_ = std::thread([this] {
    for (;;) {
      {
        std::lock_guard lock(mutex_);
        if (stop_) return;
      }
      lcm_.handleTimeout(20);
    }
  });
}

LcmListener::~LcmListener() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  thread_.join();
}

void LcmListener::on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  const auto received = Clock::now();
  {
    std::lock_guard lock(mutex_);
    handler_(channel, *buffer, received);
  }
  changed_.notify_all();
}

bool LcmListener::wait(const std::function<bool()>& done, Clock::duration timeout) const {
  const auto deadline = Clock::now() + timeout;
  std::unique_lock lock(mutex_);
  for (;;) {
    if (done()) return true;
    const auto now = Clock::now();
    if (now >= deadline) return false;
    changed_.wait_for(lock, std::min<Clock::duration>(deadline - now, 5ms));
  }
}

void LcmListener::locked(const std::function<void()>& f) const {
  std::lock_guard lock(mutex_);
  f();
}

}  // namespace rdtf::itest
