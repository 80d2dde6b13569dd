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

void OpenWrites::opened(const std::filesystem::path& file, Clock::time_point now) {
  if (files_.try_emplace(file, now).second) by_folder_[file.parent_path()].emplace(file, now);
}

void OpenWrites::closed(const std::filesystem::path& file) {
  if (files_.erase(file) == 0) return;
  const auto folder = by_folder_.find(file.parent_path());
  if (folder == by_folder_.end()) return;
  folder->second.erase(file);
  if (folder->second.empty()) by_folder_.erase(folder);
}

void OpenWrites::clear() {
  files_.clear();
  by_folder_.clear();
}

bool OpenWrites::holds(const std::vector<std::filesystem::path>& files, const std::filesystem::path* any_in_folder,
                       Clock::time_point now, Clock::duration max_wait) const {
  for (const auto& file : files) {
    const auto it = files_.find(file);
    if (it != files_.end() && now - it->second <= max_wait) return true;
  }
  if (any_in_folder == nullptr) return false;
  const auto folder = by_folder_.find(*any_in_folder);
  if (folder == by_folder_.end()) return false;
  for (const auto& [file, since] : folder->second) {
    if (now - since <= max_wait) return true;
  }
  return false;
}

}  // namespace rdtf::daemon
