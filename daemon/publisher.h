// Sends LCM messages without ever blocking the event loop on a burst: everything goes through one
// queue, drained at a byte rate that a subscriber with the kernel's default receive buffer keeps
// up with (facts.md: back-to-back fragments of 1 MB messages were lost). Order is kept.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

namespace rdtf::daemon {

class Publisher {
 public:
  Publisher(lcm::LCM& lcm, double bytes_per_second, std::size_t burst_bytes)
      : lcm_(lcm), rate_(bytes_per_second), burst_(burst_bytes) {}

  template <typename Message>
  void publish(const std::string& channel, const Message& message) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
    message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    queue_.push_back({channel, std::move(bytes)});
  }

  // Sends what the rate allows now; returns when the next message may go (or nothing queued).
  std::optional<std::chrono::steady_clock::time_point> drain(std::chrono::steady_clock::time_point now);

  std::size_t queued() const { return queue_.size(); }
  std::uint64_t send_failures() const { return send_failures_; }
  void set_rate(double bytes_per_second) { rate_ = bytes_per_second; }

 private:
  struct Pending {
    std::string channel;
    std::vector<std::uint8_t> bytes;
  };
  lcm::LCM& lcm_;
  double rate_;
  std::size_t burst_;
  double allowance_ = 0;
  std::chrono::steady_clock::time_point last_{};
  std::deque<Pending> queue_;
  std::uint64_t send_failures_ = 0;
};

}  // namespace rdtf::daemon
