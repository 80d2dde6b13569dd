#include "publisher.h"

#include <cerrno>
#include <cstring>

namespace rdtf::daemon {
namespace {

constexpr std::chrono::milliseconds kFirstBackoff{20};
constexpr std::chrono::milliseconds kLongestBackoff{500};

}  // namespace

Publisher::Publisher(lcm::LCM& lcm, double bytes_per_second, std::size_t burst_bytes)
    : Publisher(
          [&lcm](const std::string& channel, const std::uint8_t* data, unsigned int size) {
            return lcm.publish(channel, data, size);
          },
          bytes_per_second, burst_bytes) {}

Publisher::Publisher(SendFunction send, double bytes_per_second, std::size_t burst_bytes)
    : send_(std::move(send)), rate_(bytes_per_second), burst_(burst_bytes) {}

void Publisher::report(PublisherEvent::Kind kind, std::string text) {
  if (on_event_) on_event_(PublisherEvent{kind, std::move(text)});
}

void Publisher::drop_oldest(const char* why) {
  std::deque<Pending>& from = queue_.empty() ? urgent_ : queue_;
  ++dropped_;
  ++dropped_unreported_;
  const auto now = now_();
  // One line per second at most: under a flood, one per message would be a flood of its own.
  if (now >= next_drop_report_) {
    next_drop_report_ = now + std::chrono::seconds(1);
    report(PublisherEvent::Kind::kDropped,
           std::string("LCM send queue full (") + why + "): dropped " + std::to_string(dropped_unreported_) +
               " oldest message(s) (" + std::to_string(dropped_) + " since start), the latest on " +
               from.front().channel);
    dropped_unreported_ = 0;
  }
  queued_bytes_ -= from.front().bytes.size();
  if (&from == &queue_) ++departed_;
  from.pop_front();
}

void Publisher::enqueue(std::string channel, std::vector<std::uint8_t> bytes, Priority priority) {
  // LCM refuses a channel name longer than 63 characters on every try: queued, it would be retried
  // for ever and hold back everything behind it (s100java D6). Said, counted, not sent.
  if (channel.size() > kLcmMaxChannel) {
    ++dropped_;
    report(PublisherEvent::Kind::kUnencodable,
           "not sent: channel " + channel + " is " + std::to_string(channel.size()) +
               " characters, longer than LCM's 63 (a bug: please report it)");
    return;
  }
  // Only when LCM has refused every send for long, or more is queued than the rate sends.
  while (queued() >= kMaxQueued) drop_oldest("100,000 messages");
  while (queued() > 0 && queued_bytes_ + bytes.size() > kMaxQueuedBytes) drop_oldest("64 MiB");
  queued_bytes_ += bytes.size();
  if (priority != Priority::kUrgent) ++enqueued_;
  (priority == Priority::kUrgent ? urgent_ : queue_).push_back({std::move(channel), std::move(bytes)});
}

// Sends the head of the queue; false (message kept, retry scheduled) when LCM refuses it.
bool Publisher::send_front(Clock::time_point now) {
  const Pending& next = head_queue().front();
  errno = 0;
  if (send_(next.channel, next.bytes.data(), static_cast<unsigned int>(next.bytes.size())) != 0) {
    const int error = errno;
    ++send_failures_;
    if (failures_in_a_row_++ == 0) {
      failing_since_ = now;
      backoff_ = kFirstBackoff;
      report(PublisherEvent::Kind::kSendFailing,
             "LCM send failed on " + next.channel + ": " +
                 (error != 0 ? std::strerror(error) : "refused") + "; " + std::to_string(queued()) +
                 " messages kept, retrying");
    } else {
      backoff_ = std::min<Clock::duration>(backoff_ * 2, kLongestBackoff);
    }
    retry_at_ = now + backoff_;
    return false;
  }
  if (failures_in_a_row_ > 0) {
    const auto down = std::chrono::duration_cast<std::chrono::milliseconds>(now - failing_since_);
    report(PublisherEvent::Kind::kSendRecovered,
           "LCM sending works again after " + std::to_string(failures_in_a_row_) + " failed attempts over " +
               std::to_string(down.count()) + " ms; every queued message is being sent");
    failures_in_a_row_ = 0;
  }
  return true;
}

std::optional<Publisher::Clock::time_point> Publisher::drain(Clock::time_point now) {
  if (failures_in_a_row_ > 0 && now < retry_at_) return retry_at_;
  if (last_ != Clock::time_point{}) {
    allowance_ += rate_ * std::chrono::duration<double>(now - last_).count();
  } else {
    allowance_ = static_cast<double>(burst_);
  }
  allowance_ = std::min(allowance_, static_cast<double>(burst_));
  last_ = now;
  while (queued() > 0) {
    auto& head = head_queue();
    const double cost = receive_buffer_cost(head.front().bytes.size());
    // A message larger than the burst goes alone once the allowance is full.
    if (cost > allowance_ && allowance_ < static_cast<double>(burst_)) break;
    if (!send_front(now)) return retry_at_;
    allowance_ -= cost;
    queued_bytes_ -= head.front().bytes.size();
    if (&head == &queue_) ++departed_;
    head.pop_front();
  }
  if (queued() == 0) return std::nullopt;
  const double missing =
      std::min(receive_buffer_cost(head_queue().front().bytes.size()), static_cast<double>(burst_)) - allowance_;
  // Capped at an hour: a rate near zero would otherwise overflow the clock's
  // integer nanoseconds; the caller drains again by then anyway.
  const double wait_s = std::min(std::max(missing, 0.0) / rate_, 3600.0);
  return now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(wait_s));
}

}  // namespace rdtf::daemon
