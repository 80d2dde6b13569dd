// An LCM subscriber on its own thread, shared by the integration tests (Subscriber records every
// message) and the daemon benchmarks (a handler keeps only what it measures, at high rates).
#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "support/harness/basics.h"

namespace rdtf::itest {

// "<prefix>/<model_id>/<KIND>": KIND, and model_id ("" for STATUS and REQUEST).
std::string kind_of(const std::string& channel);
std::string model_id_of(const std::string& channel);

class LcmListener {
 public:
  // Called for each message under the lock, with its arrival time.
  using Handler = std::function<void(const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point received)>;

  // `channels`: a regular expression; `url`: "" for LCM's default; `queue`: messages LCM may hold
  // for this subscription before it drops one.
  LcmListener(const std::string& channels, const std::string& url, int queue, Handler handler);
  ~LcmListener();
  LcmListener(const LcmListener&) = delete;
  LcmListener& operator=(const LcmListener&) = delete;

  // Waits until `done()` (evaluated under the lock after each message, and at least every 5 ms for
  // conditions on anything else) holds; false when `timeout` passes. No deadline scaling.
  bool wait(const std::function<bool()>& done, Clock::duration timeout) const;
  // Runs `f` under the lock (to read what the handler recorded).
  void locked(const std::function<void()>& f) const;
  template <typename T>
  void publish(const std::string& channel, const T& message) {
    if (lcm_.publish(channel, &message) != 0) throw std::runtime_error("publish failed on " + channel);
  }

 private:
  void on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel);

  Handler handler_;
  lcm::LCM lcm_;
  bool stop_ = false;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::thread thread_;
};

}  // namespace rdtf::itest
