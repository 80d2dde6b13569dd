#include "support/harness/subscriber.h"

#include <algorithm>
#include <cstdlib>

#include "message_json.h"

namespace rdtf::itest {

namespace {

// LCM's default URL (or LCM_DEFAULT_URL's) with a 4 MiB socket receive buffer, as docs/lcm.md
// tells subscribers of large descriptions: the kernel's default (208 KiB) holds three 60 KB
// chunks, and a test's thread that records each message as JSON may fall that far behind a burst
// on a loaded machine. Tests of small buffers pass their own URL.
std::string with_large_receive_buffer(const std::string& url) {
  if (!url.empty()) return url;
  const char* env = std::getenv("LCM_DEFAULT_URL");
  const std::string base = env && *env ? env : "udpm://239.255.76.67:7667?ttl=0";
  if (base.rfind("udpm://", 0) != 0 || base.find("recv_buf_size=") != std::string::npos) return base;
  return base + (base.find('?') == std::string::npos ? "?" : "&") + "recv_buf_size=4194304";
}

}  // namespace

Subscriber::Subscriber(const std::string& channels, const std::string& url)
    : listener_(std::make_unique<LcmListener>(
          channels, with_large_receive_buffer(url), 100000,
          [this](const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point received) {
            record(channel, buffer, received);
          })) {}

void Subscriber::record(const std::string& channel, const lcm::ReceiveBuffer& buffer, Clock::time_point received) {
  Message message;
  message.channel = channel;
  const auto* data = static_cast<const std::uint8_t*>(buffer.data);
  message.bytes.assign(data, data + buffer.data_size);
  message.received = received;
  messages_.push_back(std::move(message));
}

Json Message::json() const {
  auto json = rdtf::clients::message_to_json(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  if (!json) return nullptr;
  // Any peer may send strings that are not UTF-8 (Echo.StringsThatAreNotUtf8PrintReplaced): kept
  // with U+FFFD in their place, as rdtf-echo prints them.
  return Json::parse(json->dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace));
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
  // The predicate runs on this waiter's own copy, outside the lock: many predicates decode every
  // message so far, and evaluated under the lock they held the receiving thread back until LCM's
  // ring buffer overflowed and dropped datagrams (seen under ASan with 50 Hz states). Messages are
  // only appended, so the copy grows by what arrived since the last look.
  const auto deadline = Clock::now() + timeout * deadline_scale();
  std::vector<Message> seen;
  for (;;) {
    listener_->locked([&] { seen.insert(seen.end(), messages_.begin() + static_cast<std::ptrdiff_t>(seen.size()), messages_.end()); });
    if (predicate(seen)) return true;
    const auto now = Clock::now();
    if (now >= deadline) return false;
    // Until a new message, or 5 ms for conditions on anything else.
    listener_->wait([&] { return messages_.size() > seen.size(); }, std::min<Clock::duration>(deadline - now, 5ms));
  }
}

}  // namespace rdtf::itest
