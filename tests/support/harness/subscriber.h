// The tests' LCM subscriber: records every message on its channels (channel, bytes, JSON
// decoding by clients/echo/message_json.h, arrival time). Made before the daemon starts, so
// nothing is missed.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/harness/lcm_listener.h"

namespace rdtf::itest {

struct Message {
  std::string channel;
  std::vector<std::uint8_t> bytes;
  Clock::time_point received;

  // message_to_json(bytes), null when not an rdtf type. Decoded when asked: the receiving thread
  // only stores bytes, so that it keeps up with 50 Hz states of several models under ASan on a
  // loaded machine (decoding each to JSON there fell behind until the kernel dropped datagrams).
  Json json() const;

  template <typename T>
  T as() const {
    T message;
    if (message.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) {
      throw std::runtime_error("message on " + channel + " does not decode as the type asked for");
    }
    return message;
  }
  // "<prefix>/<model_id>/<KIND>": KIND and model_id ("" for STATUS and REQUEST).
  std::string kind() const { return kind_of(channel); }
  std::string model_id() const { return model_id_of(channel); }
};

class Subscriber {
 public:
  // `url` "" is LCM's default with a large receive buffer (subscriber.cc).
  explicit Subscriber(const std::string& channels = std::string(kPrefix) + "/.*", const std::string& url = "");
  Subscriber(const Subscriber&) = delete;
  Subscriber& operator=(const Subscriber&) = delete;

  std::vector<Message> messages() const;
  std::size_t size() const;

  template <typename T>
  void publish(const std::string& channel, const T& message) {
    listener_->publish(channel, message);
  }

  // Waits until `predicate(messages)` holds; false at the deadline (scaled: basics.h). The
  // predicate sees a copy of the messages so far, taken without holding up the receiving thread.
  bool wait_for(const std::function<bool(const std::vector<Message>&)>& predicate, Clock::duration timeout = 5s) const;

 private:
  void record(const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point received);

  std::vector<Message> messages_;  // Under the listener's lock.
  std::unique_ptr<LcmListener> listener_;  // Last: its thread stops before messages_ goes.
};

}  // namespace rdtf::itest
