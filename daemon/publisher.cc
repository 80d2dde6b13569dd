#include "publisher.h"

namespace rdtf::daemon {

std::optional<std::chrono::steady_clock::time_point> Publisher::drain(
    std::chrono::steady_clock::time_point now) {
  if (last_ != std::chrono::steady_clock::time_point{}) {
    allowance_ += rate_ * std::chrono::duration<double>(now - last_).count();
  } else {
    allowance_ = static_cast<double>(burst_);
  }
  allowance_ = std::min(allowance_, static_cast<double>(burst_));
  last_ = now;
  while (!queue_.empty()) {
    const auto size = static_cast<double>(queue_.front().bytes.size());
    // A message larger than the burst goes alone once the allowance is full.
    if (size > allowance_ && allowance_ < static_cast<double>(burst_)) break;
    const Pending& next = queue_.front();
    if (lcm_.publish(next.channel, next.bytes.data(), static_cast<unsigned int>(next.bytes.size())) != 0) {
      ++send_failures_;  // Reported in the status message; periodic republishing recovers.
    }
    allowance_ -= size;
    queue_.pop_front();
  }
  if (queue_.empty()) return std::nullopt;
  const double missing = std::min(static_cast<double>(queue_.front().bytes.size()),
                                  static_cast<double>(burst_)) - allowance_;
  return now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                   std::chrono::duration<double>(std::max(missing, 0.0) / rate_));
}

}  // namespace rdtf::daemon
