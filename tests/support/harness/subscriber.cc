#include "support/harness/subscriber.h"

#include "message_json.h"

namespace rdtf::itest {

Subscriber::Subscriber(const std::string& channels, const std::string& url)
    : listener_(std::make_unique<LcmListener>(
          channels, url, 100000,
          [this](const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point received) {
            record(channel, buffer, received);
          })) {}

void Subscriber::record(const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point received) {
  Message message;
  message.channel = channel;
  const auto* data = static_cast<const std::uint8_t*>(buffer.data);
  message.bytes.assign(data, data + buffer.data_size);
  if (auto json = rdtf::clients::message_to_json(buffer.data, buffer.data_size)) {
    message.json = Json::parse(json->dump());
  }
  message.received = received;
  messages_.push_back(std::move(message));
}

std::vector<Message> Subscriber::messages() const {
  std::vector<Message> copy;
  listener_->locked([&] { copy = messages_; });
  return copy;
}

std::size_t Subscriber::size() const {
  std::size_t size = 0;
  listener_->locked([&] { size = messages_.size(); });
  return size;
}

bool Subscriber::wait_for(const std::function<bool(const std::vector<Message>&)>& predicate,
                          Clock::duration timeout) const {
  return listener_->wait([&] { return predicate(messages_); }, timeout * deadline_scale());
}

}  // namespace rdtf::itest
