// Pieces the daemon's files share (daemon*.cc); not part of its interface.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

#include "rdtf/diagnostics.h"

namespace rdtf::daemon {

// LCM channel names are at most 63 characters: "<prefix>/<id>/DESCRIPTION_CHUNK" must fit.
constexpr std::size_t kMaxChannelLength = 63;
constexpr std::size_t kLongestKind = sizeof("/DESCRIPTION_CHUNK") - 1;

// How often folders that could not be watched are tried again.
constexpr std::chrono::milliseconds kWatchRetryPeriod{1000};
constexpr std::chrono::milliseconds kWatchRetryLongest{60000};

// The publisher's burst, in receive-buffer bytes: 60% of Linux's default 212,992-byte socket
// buffer, so that a subscriber that wakes late still holds a whole burst, with room left for
// the joint and link states that the simulation sends alongside.
constexpr std::size_t kBurstReceiveBufferBytes = 128 * 1024;

// Requests for the same model (or for all) are answered at most once per this period
// (RequestThrottle): a flood of requests costs one publication per model and period.
constexpr std::chrono::milliseconds kRequestAnswerPeriod{1000};

// Work one turn of the loop does at most, so that a burst of files (tens of thousands) never
// holds back requests, commands and heartbeats: this many file events are handled and finished
// conversions applied per turn (reading the events is cheap; handling them is not).
constexpr std::size_t kOutcomesPerTurn = 64;
// Datagrams handled per turn (each is cheap: a request is answered by queueing messages).
constexpr std::size_t kDatagramsPerTurn = 256;
// File events handled per turn (a new folder of 20,000 files is listed at once: 20,000 events).
constexpr std::size_t kFileEventsPerTurn = 2048;

std::string milliseconds(std::chrono::microseconds duration);
std::string first_error(const Diagnostics& diag);

}  // namespace rdtf::daemon
