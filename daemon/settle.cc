#include "settle.h"

#include <algorithm>

namespace rdtf::daemon {

Clock::time_point SettleWindow::deadline(const SettlePolicy& policy) const {
  const Clock::time_point quiet = last_event + policy.settle;
  if (!open_for_writing) return quiet;
  // A writer still holds the file: wait for its close, but not forever (mmap writers, crashed
  // editors).
  return std::max(quiet, first_event + policy.max_open_wait);
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
