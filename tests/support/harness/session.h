// A watched folder, an output folder, a subscriber started first, and rdtfd: what most
// integration tests start from.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <rdtf/status_t.hpp>

#include "support/harness/process.h"
#include "support/harness/subscriber.h"

namespace rdtf::itest {

struct Session {
  // prefix: the daemon's channel prefix (give the daemon --channel-prefix too when not RDTF).
  explicit Session(std::string channel_prefix = kPrefix);
  ~Session();  // Prints the daemon's log when the test failed.
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  std::string prefix;
  TempDir root;
  fs::path watch = root / "models";
  fs::path output = root / "out";
  Subscriber subscriber;
  std::unique_ptr<DaemonProcess> daemon;

  // Starts rdtfd (on `watch` and `output` unless the options name folders) and waits for its
  // first heartbeat.
  DaemonProcess& start(DaemonOptions options = {});

  std::vector<Message> messages() const { return subscriber.messages(); }

  // Waits for a condition on the recorded messages.
  bool wait_for(const std::function<bool(const std::vector<Message>&)>& predicate, Clock::duration timeout = 5s) {
    return subscriber.wait_for(predicate, timeout);
  }
  // Waits for the DESCRIPTION and the INERTIA of this revision and hash: a test that reads the
  // table next must not see the previous revision's.
  bool wait_revision(const std::string& id, std::int64_t revision, const std::string& hash,
                     Clock::duration timeout = 5s);

  // Waits until the daemon is idle: `quiet` consecutive STATUS messages, all received after
  // this call, with nothing pending and the same counters. Returns the last of them.
  std::optional<rdtf::status_t> wait_idle(int quiet = 3, Clock::duration timeout = 5s);

  // Waits until an lcm-logger started on `log` records: a probe published on ITEST_PROBE until
  // the file has bytes (the logger subscribes a moment after it starts).
  bool wait_logger_recording(const fs::path& log, Clock::duration timeout = 5s);

  void request(const std::string& model_id = "", const std::string& requester = "itest");
};

}  // namespace rdtf::itest
