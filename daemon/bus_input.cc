#include "bus_input.h"

namespace rdtf::daemon {

void BusInput::drop(const std::string& channel, const std::string& why) {
  if (auto line = drops_.drop(channel, why, Clock::now()); line && handlers_.log) handlers_.log(*line);
}

void BusInput::flush_drops() {
  if (auto line = drops_.flush(Clock::now()); line && handlers_.log) handlers_.log(*line);
}

template <typename Message>
std::optional<Message> BusInput::decode(const std::string& channel, const void* data, std::size_t size) {
  if (size > kMaxInputBytes) {
    drop(channel, std::to_string(size) + " bytes, above rdtfd's input limit of " + std::to_string(kMaxInputBytes));
    return std::nullopt;
  }
  std::string why;
  auto message = lcm_safe::decode<Message>(data, size, why);
  if (!message) drop(channel, why);
  return message;
}

void BusInput::request_datagram(const std::string& channel, const void* data, std::size_t size) {
  lcm_safe::guarded(
      drops_, channel,
      [&] {
        if (auto request = decode<rdtf::request_t>(channel, data, size); request && handlers_.request) {
          handlers_.request(*request);
        }
      },
      [&](const std::string& line) {
        if (handlers_.log) handlers_.log(line);
      });
}

void BusInput::command_datagram(const std::string& channel, const void* data, std::size_t size) {
  lcm_safe::guarded(
      drops_, channel, [&] { take_command(channel, data, size); },
      [&](const std::string& line) {
        if (handlers_.log) handlers_.log(line);
      });
}

void BusInput::blob_request_datagram(const std::string& channel, const void* data, std::size_t size) {
  lcm_safe::guarded(
      drops_, channel,
      [&] {
        auto request = decode<rdtf::blob_request_t>(channel, data, size);
        if (!request) ++blob_requests_undecodable_;
        if (!request || !handlers_.blob_request) return;
        if (const std::string why = handlers_.blob_request(*request); !why.empty()) drop(channel, why);
      },
      [&](const std::string& line) {
        if (handlers_.log) handlers_.log(line);
      });
}

void BusInput::take_command(const std::string& channel, const void* data, std::size_t size) {
  auto command = decode<rdtf::joint_command_t>(channel, data, size);
  if (!command) return;
  // The channel is the model's: a command naming another model would reach a simulation its
  // sender does not claim to address.
  const std::string expected_suffix = "/" + command->model_id + "/JOINT_COMMAND";
  if (channel.size() < expected_suffix.size() ||
      channel.compare(channel.size() - expected_suffix.size(), expected_suffix.size(), expected_suffix) != 0) {
    drop(channel, "joint_command_t for model '" + lcm_safe::printable(command->model_id, 80) +
                      "' on another model's channel");
    return;
  }
  if (handlers_.command) {
    if (const std::string why = handlers_.command(*command); !why.empty()) drop(channel, why);
  }
}

bool RequestThrottle::admit(const std::string& model_id, Clock::time_point now) {
  auto [it, fresh] = entries_.try_emplace(model_id);
  Entry& entry = it->second;
  if (fresh || now >= entry.period_end) {
    entry.period_end = now + period_;
    entry.deferred = false;
    return true;
  }
  ++coalesced_;
  entry.deferred = true;
  return false;
}

std::vector<std::string> RequestThrottle::take_due(Clock::time_point now) {
  std::vector<std::string> due;
  for (auto it = entries_.begin(); it != entries_.end();) {
    if (now < it->second.period_end) {
      ++it;
    } else if (it->second.deferred) {
      due.push_back(it->first);
      it->second = Entry{now + period_, false};
      ++it;
    } else {
      it = entries_.erase(it);  // A quiet period: forget the model id.
    }
  }
  return due;
}

std::optional<RequestThrottle::Clock::time_point> RequestThrottle::next_due() const {
  std::optional<Clock::time_point> next;
  for (const auto& [id, entry] : entries_) {
    if (entry.deferred && (!next || entry.period_end < *next)) next = entry.period_end;
  }
  return next;
}

}  // namespace rdtf::daemon
