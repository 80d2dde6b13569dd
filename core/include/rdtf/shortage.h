// A system call that failed for want of the system's resources rather than because of what it was
// asked to do: the process is out of descriptors (EMFILE), the system is (ENFILE), or memory or
// buffer space is short (ENOMEM, ENOBUFS). The same call may well succeed a moment later, so what
// failed so is tried again: never refused for good, never taken for a missing file.
//
// One rule for every place that decides it (reading a model and the files it names, reading a
// revision state, syncing a revision's files in batches, rdtf-view's accept), so that they do not
// drift apart.
#pragma once

#include <cerrno>

namespace rdtf {

inline bool is_shortage(int error) noexcept {
  return error == EMFILE || error == ENFILE || error == ENOMEM || error == ENOBUFS;
}

}  // namespace rdtf
