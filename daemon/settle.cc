#include "settle.h"

#include <algorithm>

namespace rdtf::daemon {

void SettleQueue::touch(const std::string& model, Clock::time_point now, bool still_open) {
  auto [it, inserted] = pending_.try_emplace(model, Pending{now, now, still_open});
  if (!inserted) {
    it->second.last_event = now;
    it->second.open_for_writing = it->second.open_for_writing || still_open;
  }
}

void SettleQueue::closed(const std::string& model, Clock::time_point now) {
  auto [it, inserted] = pending_.try_emplace(model, Pending{now, now, false});
  it->second.last_event = now;
  it->second.open_for_writing = false;
}

void SettleQueue::forget(const std::string& model) { pending_.erase(model); }

Clock::time_point SettleQueue::deadline(const Pending& pending) const {
  const Clock::time_point quiet = pending.last_event + settle_;
  if (!pending.open_for_writing) return quiet;
  // A writer still holds the file: wait for its close, but not forever (mmap writers, crashed
  // editors).
  return std::max(quiet, pending.first_event + max_open_wait_);
}

std::vector<std::string> SettleQueue::take_due(Clock::time_point now) {
  std::vector<std::string> due;
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (deadline(it->second) <= now) {
      due.push_back(it->first);
      it = pending_.erase(it);
    } else {
      ++it;
    }
  }
  return due;
}

std::optional<Clock::time_point> SettleQueue::next_deadline() const {
  std::optional<Clock::time_point> next;
  for (const auto& [model, pending] : pending_) {
    const auto d = deadline(pending);
    if (!next || d < *next) next = d;
  }
  return next;
}

}  // namespace rdtf::daemon
