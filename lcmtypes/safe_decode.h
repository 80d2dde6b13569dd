// Decoding of LCM datagrams from an untrusted bus. lcm-gen 1.3.1's C++ decoders trust the length
// fields they read: a string length of 0 or below calls assign(ptr, len - 1), an array count of -1
// or 2^31-1 calls resize() with it before a single element is checked against the buffer (an
// exception out of the LCM handler, or gigabytes for a 111-byte datagram). So every rdtf program
// that subscribes walks a datagram against its type's schema first (parsed from lcmtypes/*.lcm,
// compiled in) and decodes only what fits: every string 1 <= length <= the bytes left,
// NUL-terminated and with no other NUL, every array count >= 0 with all its elements present, no byte left over.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstring>
#include <exception>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rdtf::lcm_safe {

// Largest message any rdtf subscriber decodes (LCM itself accepts 256 MiB in fragments).
constexpr std::size_t kMaxMessageBytes = 4 * 1024 * 1024;

// The outcome of checking one encoded message (with its 8-byte fingerprint) against the rdtf type
// named `type_name` (e.g. "joint_command_t"). Empty when it may be decoded; else why not.
std::string check_encoded(std::string_view type_name, std::int64_t fingerprint, const void* data, std::size_t size);

// Whether `type_name` is an rdtf message type: an rdtf struct no other rdtf struct contains.
bool is_message_type(std::string_view type_name);

// The names of every rdtf struct in lcmtypes/ (message types and nested ones).
std::vector<std::string_view> lcm_type_names();

// The rdtf message type whose fingerprint starts `data`, or "" for none (not an rdtf message;
// a nested struct's fingerprint, e.g. diagnostic_t's, is none either).
std::string_view type_of(const void* data, std::size_t size);

// For a message whose fingerprint names an rdtf type: check_encoded against that type.
std::string check_known(const void* data, std::size_t size);

// `message` decoded from `data`, or nullopt with `why` set.
template <typename Message>
std::optional<Message> decode(const void* data, std::size_t size, std::string& why) {
  why = check_encoded(Message::getTypeName(), Message::getHash(), data, size);
  if (!why.empty()) return std::nullopt;
  Message message;
  try {
    if (message.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size)) {
      why = "LCM decoder refused it after the schema check";
      return std::nullopt;
    }
  } catch (const std::exception& error) {
    why = std::string("LCM decoder failed: ") + error.what();
    return std::nullopt;
  }
  return message;
}

// `text` from the bus made safe for a one-line log: printable ASCII kept (backslash doubled),
// every other byte as \xNN, at most `max_bytes` of the input (then "...(N bytes)").
std::string printable(std::string_view text, std::size_t max_bytes = 200);

// printable(), but a backslash is kept as it is: for text made of pieces printable() made already
// (a second pass would show a bus byte 0xff as "\\\\xff"); any other byte is still escaped.
std::string printable_kept(std::string_view text, std::size_t max_bytes = 200);

// Counts dropped datagrams and says when to log: the first drop at once, then at most one line
// per `period` with the number dropped since the last line. The line is printable ASCII: the
// channel made printable(), the reason (the caller's text, bus text in it printable() already)
// printable_kept().
class DropCounter {
 public:
  using Clock = std::chrono::steady_clock;
  explicit DropCounter(Clock::duration period = std::chrono::seconds(1)) : period_(period) {}

  // Notes one drop on `channel` for `why`; returns the line to log now, if one is due.
  std::optional<std::string> drop(std::string_view channel, std::string_view why, Clock::time_point now);
  // The line for drops not yet logged, once their period is over: without it the end of a burst
  // would be logged only when the next drop came, perhaps never. Call it now and then (rdtfd:
  // each turn of its loop).
  std::optional<std::string> flush(Clock::time_point now);
  std::uint64_t total() const { return total_; }

 private:
  std::string line(Clock::time_point now);

  Clock::duration period_;
  Clock::time_point next_line_{};
  std::uint64_t total_ = 0;
  std::uint64_t unreported_ = 0;
  std::string latest_channel_;  // printable() already
  std::string latest_why_;      // printable_kept() already
};

// Runs `handler` for one datagram of `channel`. An exception from it must never unwind through
// liblcm's C frames (undefined behaviour, and the end of the process): it is counted in `drops`
// as that datagram's drop, with its message; the log line due, if any, goes to `log`. Even a
// failure to count it (bad_alloc) stops here.
template <typename Handler, typename Log>
void guarded(DropCounter& drops, std::string_view channel, Handler&& handler, Log&& log) noexcept {
  std::string why;
  try {
    handler();
    return;
  } catch (const std::exception& e) {
    why = "handler failed: ";
    why += e.what();
  } catch (...) {
    why = "handler failed: unknown exception";
  }
  try {
    if (auto line = drops.drop(channel, why, std::chrono::steady_clock::now())) log(*line);
  } catch (...) {
  }
}

}  // namespace rdtf::lcm_safe
