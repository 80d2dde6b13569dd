// Sends LCM messages without ever blocking the event loop on a burst: everything goes through one
// queue, drained at a byte rate that a subscriber with the kernel's default receive buffer keeps
// up with (facts.md: back-to-back fragments of 1 MB messages were lost). Order is kept.
//
// The rate and the burst count what a datagram costs the receiving socket's buffer, not its
// payload: Linux charges the whole allocation, so the default 212,992-byte buffer holds only 12
// datagrams of 8,000 bytes or 166 of 300 bytes (measured on loopback; docs/lcm.md). A burst
// counted in payload bytes overflowed it with 8,000-byte chunks.
//
// The queue is bounded in bytes (kMaxQueuedBytes; also kMaxQueued messages): beyond it the oldest
// messages go, counted, and reported at most once a second. Messages published `urgent` (STATUS)
// go before everything else queued, so a backlog never delays the heartbeat.
//
// A send that LCM refuses (no route, no buffer space) is not dropped: the message stays at the
// head of the queue and is tried again after a back-off, so nothing is lost once sending works
// again. The first failure and the recovery are reported through `on_event`.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "counts.h"

namespace rdtf::daemon {

// One LCM send: 0 on success, as lcm::LCM::publish. A seam for tests of the publisher itself.
using SendFunction = std::function<int(const std::string& channel, const std::uint8_t* data, unsigned int size)>;

struct PublisherEvent {
  enum class Kind { kSendFailing, kSendRecovered, kDropped, kUnencodable };
  Kind kind;
  std::string text;  // One line for the log, naming the channel and the error.
};

// The longest channel name LCM sends (LCM_MAX_CHANNEL_NAME_LENGTH).
inline constexpr std::size_t kLcmMaxChannel = 63;

// An upper bound of what a receiving socket's buffer is charged for one datagram of `size`
// payload bytes (above every size class measured on loopback, from 1 to 64,000 bytes).
constexpr double receive_buffer_cost(std::size_t size) {
  return static_cast<double>(size + std::min<std::size_t>(size, 16384) + 2048);
}

class Publisher {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::size_t kMaxQueued = 100000;  // Beyond this (LCM down for long) the oldest go.
  static constexpr std::size_t kMaxQueuedBytes = 64 * 1024 * 1024;  // Encoded bytes, both queues.
  enum class Priority { kNormal, kUrgent };

  // Both in receive-buffer bytes (receive_buffer_cost).
  Publisher(lcm::LCM& lcm, double bytes_per_second, std::size_t burst_bytes);
  Publisher(SendFunction send, double bytes_per_second, std::size_t burst_bytes);

  // The message's length fields are set here from its arrays (lcmtypes/counts.h), never by callers.
  template <typename Message>
  void publish(const std::string& channel, Message message, Priority priority = Priority::kNormal) {
    set_counts(message);
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
    // LCM writes a string up to its first NUL but sizes it whole (lcm_coretypes.h): a NUL would
    // leave bytes that no subscriber decodes. Texts from models are escaped before (lcm_text);
    // should one still hold a NUL, nothing undecodable goes out, and the log says what was not sent.
    if (message.encode(bytes.data(), 0, static_cast<int>(bytes.size())) != static_cast<int>(bytes.size())) {
      report(PublisherEvent::Kind::kUnencodable,
             "not sent on " + channel + ": a text field of the message holds a NUL byte, which LCM cannot carry");
      return;
    }
    enqueue(channel, std::move(bytes), priority);
  }

  // Sends what the rate allows now; returns when the next message may go (or nothing queued).
  std::optional<Clock::time_point> drain(Clock::time_point now);

  std::size_t queued() const { return queue_.size() + urgent_.size(); }
  // Messages of normal priority queued since start, and those that left the queue (sent or
  // dropped) since start: they leave in order, so the n-th is still waiting while departed() < n
  // (the blob server skips chunks a request asks for that are still waiting to go).
  std::uint64_t enqueued() const { return enqueued_; }
  std::uint64_t departed() const { return departed_; }
  std::size_t queued_bytes() const { return queued_bytes_; }
  std::uint64_t send_failures() const { return send_failures_; }
  std::uint64_t dropped() const { return dropped_; }
  bool failing() const { return failures_in_a_row_ > 0; }
  void set_rate(double bytes_per_second) { rate_ = bytes_per_second; }
  void on_event(std::function<void(const PublisherEvent&)> handler) { on_event_ = std::move(handler); }
  // The clock that paces the drop reports (tests inject one; drain() takes its time as argument).
  void set_clock(std::function<Clock::time_point()> now) { now_ = std::move(now); }

 private:
  struct Pending {
    std::string channel;
    std::vector<std::uint8_t> bytes;
  };
  void enqueue(std::string channel, std::vector<std::uint8_t> bytes, Priority priority);
  void drop_oldest(const char* why);
  std::deque<Pending>& head_queue() { return urgent_.empty() ? queue_ : urgent_; }
  bool send_front(Clock::time_point now);
  void report(PublisherEvent::Kind kind, std::string text);

  SendFunction send_;
  double rate_;
  std::size_t burst_;
  double allowance_ = 0;
  Clock::time_point last_{};
  std::deque<Pending> queue_;
  std::deque<Pending> urgent_;
  std::size_t queued_bytes_ = 0;
  std::uint64_t enqueued_ = 0;
  std::uint64_t departed_ = 0;
  std::uint64_t send_failures_ = 0;
  std::uint64_t dropped_ = 0;
  std::uint64_t dropped_unreported_ = 0;
  Clock::time_point next_drop_report_{};
  // The current run of failed sends: how many, since when, and when to try again.
  std::uint64_t failures_in_a_row_ = 0;
  Clock::time_point failing_since_{};
  Clock::time_point retry_at_{};
  Clock::duration backoff_{};
  std::function<void(const PublisherEvent&)> on_event_;
  std::function<Clock::time_point()> now_ = [] { return Clock::now(); };
};

}  // namespace rdtf::daemon
