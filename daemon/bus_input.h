// What rdtfd takes from the bus (LCM has no authentication: anyone on the network may send it):
// requests, blob requests and joint commands. Each datagram is checked against its type's schema before it is
// decoded (lcmtypes/safe_decode.h); one that does not fit is dropped, counted and logged at most
// once a second. Requests for the same model are answered at most once per period.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <rdtf/blob_request_t.hpp>
#include <rdtf/joint_command_t.hpp>
#include <rdtf/request_t.hpp>

#include "safe_decode.h"

namespace rdtf::daemon {

class BusInput {
 public:
  using Clock = std::chrono::steady_clock;
  struct Handlers {
    std::function<void(const rdtf::request_t&)> request;
    // Returns "" when the command was taken, else why it was dropped (counted and logged).
    std::function<std::string(const rdtf::joint_command_t&)> command;
    std::function<void(const std::string&)> log;
    // As `command`: "" when the blob request was taken, else why it was dropped. Last, so that
    // handler sets written before it existed keep their meaning.
    std::function<std::string(const rdtf::blob_request_t&)> blob_request;
  };
  explicit BusInput(Handlers handlers) : handlers_(std::move(handlers)) {}

  // One datagram's payload received on `channel` (the subscription's pattern matched it). Never
  // throws: an exception from a handler is counted and logged as a drop (lcm_safe::guarded).
  void request_datagram(const std::string& channel, const void* data, std::size_t size);
  void command_datagram(const std::string& channel, const void* data, std::size_t size);
  void blob_request_datagram(const std::string& channel, const void* data, std::size_t size);

  std::uint64_t dropped() const { return drops_.total(); }
  // Logs the drops of a burst not logged yet once their period is over (DropCounter::flush).
  void flush_drops();
  // Blob requests that did not decode (in dropped() too).
  std::uint64_t blob_requests_undecodable() const { return blob_requests_undecodable_; }

  // Every datagram rdtfd subscribes to fits one UDP datagram: a larger message (LCM reassembles
  // up to 256 MiB from fragments) is dropped before it is decoded.
  static constexpr std::size_t kMaxInputBytes = 64 * 1024;

 private:
  void drop(const std::string& channel, const std::string& why);
  void take_command(const std::string& channel, const void* data, std::size_t size);
  template <typename Message>
  std::optional<Message> decode(const std::string& channel, const void* data, std::size_t size);

  Handlers handlers_;
  lcm_safe::DropCounter drops_;
  std::uint64_t blob_requests_undecodable_ = 0;
};

// Answers repeated requests at most once per period and model ("" for all): the first request of
// a period is answered at once, any more in it by one answer at the period's end, so a flood of
// requests costs one publication per period while a subscriber that asks late still gets its
// answer within a period.
class RequestThrottle {
 public:
  using Clock = std::chrono::steady_clock;
  explicit RequestThrottle(Clock::duration period) : period_(period) {}

  // True: answer now. False: an answer is already due later in this period.
  bool admit(const std::string& model_id, Clock::time_point now);
  // The model ids whose deferred answer is due at `now` (then answered: admit starts a period).
  std::vector<std::string> take_due(Clock::time_point now);
  std::optional<Clock::time_point> next_due() const;
  std::uint64_t coalesced() const { return coalesced_; }

 private:
  struct Entry {
    Clock::time_point period_end;
    bool deferred = false;
  };
  Clock::duration period_;
  std::map<std::string, Entry> entries_;
  std::uint64_t coalesced_ = 0;
};

}  // namespace rdtf::daemon
