// The publisher keeps messages that LCM refuses and sends them, in order, once it accepts again;
// the first failure and the recovery are reported. Driven with a fake send and a stepped clock.
#include <cerrno>

#include <gtest/gtest.h>

#include <rdtf/request_t.hpp>

#include "publisher.h"

namespace rdtf::daemon {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

struct FakeLcm {
  bool refuse = false;
  int attempts = 0;
  std::vector<std::string> sent;  // Channel and requester, in order.
  int send(const std::string& channel, const std::uint8_t* data, unsigned int size) {
    ++attempts;
    if (refuse) {
      errno = ENETUNREACH;
      return -1;
    }
    rdtf::request_t request;
    EXPECT_GE(request.decode(data, 0, static_cast<int>(size)), 0);
    sent.push_back(channel + " " + request.requester);
    return 0;
  }
};

rdtf::request_t request(const std::string& requester) {
  rdtf::request_t message;
  message.utime = 0;
  message.requester = requester;
  return message;
}

TEST(Publisher, RefusedMessagesAreKeptAndSentInOrderWhenLcmAcceptsAgain) {
  FakeLcm lcm;
  Publisher publisher([&](const std::string& c, const std::uint8_t* d, unsigned int n) { return lcm.send(c, d, n); },
                      1e9, 1 << 20);
  std::vector<PublisherEvent> events;
  publisher.on_event([&](const PublisherEvent& e) { events.push_back(e); });
  auto now = Clock::time_point{} + 1h;

  lcm.refuse = true;
  publisher.publish("A", request("1"));
  publisher.publish("B", request("2"));
  const auto retry = publisher.drain(now);
  ASSERT_TRUE(retry.has_value());
  EXPECT_EQ(*retry, now + 20ms);  // The first back-off.
  EXPECT_EQ(publisher.queued(), 2u);
  EXPECT_TRUE(publisher.failing());
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, PublisherEvent::Kind::kSendFailing);
  EXPECT_EQ(events[0].text, "LCM send failed on A: Network is unreachable; 2 messages kept, retrying");

  // Before the back-off ends nothing is tried; each further failure doubles it.
  EXPECT_EQ(publisher.drain(now + 10ms), now + 20ms);
  EXPECT_EQ(lcm.attempts, 1);
  EXPECT_EQ(publisher.drain(now + 20ms), now + 20ms + 40ms);
  EXPECT_EQ(lcm.attempts, 2);
  EXPECT_EQ(events.size(), 1u);  // One report per outage.

  publisher.publish("C", request("3"));
  lcm.refuse = false;
  EXPECT_EQ(publisher.drain(now + 60ms), std::nullopt);
  EXPECT_EQ(lcm.sent, (std::vector<std::string>{"A 1", "B 2", "C 3"}));
  EXPECT_EQ(publisher.queued(), 0u);
  EXPECT_FALSE(publisher.failing());
  EXPECT_EQ(publisher.send_failures(), 2u);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].kind, PublisherEvent::Kind::kSendRecovered);
  EXPECT_EQ(events[1].text,
            "LCM sending works again after 2 failed attempts over 60 ms; every queued message is being sent");
}

// LCM writes a string up to its first NUL but sizes it whole: sent, such a message would be bytes
// no subscriber decodes. It is not sent, the log says so, and what comes after goes as usual.
TEST(Publisher, AMessageWithANulInAStringIsNotSentAndIsReported) {
  FakeLcm lcm;
  Publisher publisher([&](const std::string& c, const std::uint8_t* d, unsigned int n) { return lcm.send(c, d, n); },
                      1e9, 1 << 20);
  std::vector<PublisherEvent> events;
  publisher.on_event([&](const PublisherEvent& e) { events.push_back(e); });
  publisher.publish("A", request(std::string("x\0y", 3)));
  publisher.publish("B", request("2"));
  EXPECT_EQ(publisher.drain(Clock::time_point{} + 1h), std::nullopt);
  EXPECT_EQ(lcm.sent, (std::vector<std::string>{"B 2"}));
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, PublisherEvent::Kind::kUnencodable);
  EXPECT_EQ(events[0].text, "not sent on A: a text field of the message holds a NUL byte, which LCM cannot carry");
}

// LCM refuses a channel of more than 63 characters on every try: kept and retried, it held back
// everything queued behind it for ever (s100java D6). It is not sent, and said so.
TEST(Publisher, AChannelLongerThanLcmAllowsIsNotSentAndHoldsNothingBack) {
  FakeLcm lcm;
  Publisher publisher([&](const std::string& c, const std::uint8_t* d, unsigned int n) { return lcm.send(c, d, n); },
                      1e9, 1 << 20);
  std::vector<PublisherEvent> events;
  publisher.on_event([&](const PublisherEvent& e) { events.push_back(e); });
  const std::string longest(63, 'c'), too_long(64, 'c');
  publisher.publish(too_long, request("1"));
  publisher.publish(longest, request("2"));
  EXPECT_EQ(publisher.drain(Clock::time_point{} + 1h), std::nullopt);
  EXPECT_EQ(lcm.sent, (std::vector<std::string>{longest + " 2"}));
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, PublisherEvent::Kind::kUnencodable);
  EXPECT_NE(events[0].text.find("is 64 characters, longer than LCM's 63"), std::string::npos) << events[0].text;
}

TEST(Publisher, BackOffStopsGrowingAtHalfASecond) {
  FakeLcm lcm;
  lcm.refuse = true;
  Publisher publisher([&](const std::string& c, const std::uint8_t* d, unsigned int n) { return lcm.send(c, d, n); },
                      1e9, 1 << 20);
  publisher.publish("A", request("1"));
  auto now = Clock::time_point{} + 1h;
  std::vector<Clock::duration> waits;
  for (int i = 0; i < 8; ++i) {
    const auto next = publisher.drain(now);
    ASSERT_TRUE(next.has_value());
    waits.push_back(*next - now);
    now = *next;
  }
  const std::vector<Clock::duration> expected = {20ms, 40ms, 80ms, 160ms, 320ms, 500ms, 500ms, 500ms};
  EXPECT_EQ(waits, expected);
}

}  // namespace
}  // namespace rdtf::daemon
