// When to convert: a model is converted once its files have been quiet for the settle period,
// so a burst of saves gives one conversion of the final content. Pure values over times given
// by the caller, so tests drive them directly.
#pragma once

#include <chrono>
#include <filesystem>
#include <map>
#include <vector>

namespace rdtf::daemon {

using Clock = std::chrono::steady_clock;

// settle: quiet time after the last event. max_open_wait: how long a file that is still open for
// writing (modified, not yet closed) may hold its model back before it is converted anyway.
struct SettlePolicy {
  Clock::duration settle{};
  Clock::duration max_open_wait{};
};

// The events of one model since it last settled: when its deadline falls.
struct SettleWindow {
  Clock::time_point first_event;
  Clock::time_point last_event;
  bool open_for_writing = false;

  // A window opened by an event at `now`. `still_open`: the file was modified and not yet closed
  // by its writer (an in-place save in progress).
  static SettleWindow opened(Clock::time_point now, bool still_open) { return {now, now, still_open}; }
  // Another event: re-arms the quiet period; a file still open stays so until its close.
  void touch(Clock::time_point now, bool still_open) {
    last_event = now;
    open_for_writing = open_for_writing || still_open;
  }
  void closed(Clock::time_point now) {  // Its writer closed the file.
    last_event = now;
    open_for_writing = false;
  }
  Clock::time_point deadline(const SettlePolicy& policy) const;
};

// Files modified and not yet closed by their writer, since when; indexed by folder too, so that
// asking whether a model waits for a writer costs a few lookups, not a pass over every open file
// (a burst of 20,000 new files is 20,000 open files and 20,000 models asking).
class OpenWrites {
 public:
  void opened(const std::filesystem::path& file, Clock::time_point now);  // Keeps the first time.
  void closed(const std::filesystem::path& file);
  void clear();
  // A file of `files`, or (when `any_in_folder` is given) any file in that folder, is open and has
  // been for at most `max_wait` (a writer that never closes holds nothing back for longer).
  bool holds(const std::vector<std::filesystem::path>& files, const std::filesystem::path* any_in_folder,
             Clock::time_point now, Clock::duration max_wait) const;
  std::size_t size() const { return files_.size(); }

 private:
  std::map<std::filesystem::path, Clock::time_point> files_;
  std::map<std::filesystem::path, std::map<std::filesystem::path, Clock::time_point>> by_folder_;
};

}  // namespace rdtf::daemon
