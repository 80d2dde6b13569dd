// liblcm 1.3.1 kept every channel name a process received in a table until lcm_destroy, whether
// or not anything subscribed to it (110 to 160 bytes a name): rdtfd's own messages, looped back by
// multicast under a channel per model id, and any peer sending on ever new names grew every rdtf
// process without bound. scripts/lcm/lcm-1.3.1-handlers-map-bound.patch empties the table when it
// holds 131,072 channels. Checked here through liblcm's in-process provider (memq://, whose
// publish asks the same table), by the heap the process holds.
#include <gtest/gtest.h>
#include <lcm/lcm.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "support/heap_in_use.h"

namespace rdtf {
namespace {

using testing::heap_in_use;

void count_message(const lcm_recv_buf_t*, const char*, void* count) { ++*static_cast<int*>(count); }


// Publishes `names` messages of one byte, each on a channel of its own, handling each at once.
void publish_fresh(lcm_t* lcm, const std::string& prefix, const std::string& suffix, int names) {
  const std::uint8_t byte = 0;
  for (int i = 0; i < names; ++i) {
    const std::string channel = prefix + std::to_string(i) + suffix;
    ASSERT_EQ(lcm_publish(lcm, channel.c_str(), &byte, 1), 0);
    lcm_handle_timeout(lcm, 0);
  }
}

// The patch's bound: the table is emptied when it holds this many channels.
constexpr int kCachedChannels = 131072;

// An in-process bus subscribed to every model's JOINT_COMMAND, as rdtfd is.
struct Bus {
  Bus() : lcm(lcm_create("memq://")) {
    if (lcm != nullptr) subscription = lcm_subscribe(lcm, "RDTF/.*/JOINT_COMMAND", count_message, &received);
  }
  ~Bus() {
    if (subscription != nullptr) lcm_unsubscribe(lcm, subscription);
    if (lcm != nullptr) lcm_destroy(lcm);
  }
  lcm_t* lcm;
  lcm_subscription_t* subscription = nullptr;
  int received = 0;
};

// The heap a full table holds (kCachedChannels fresh names, `first`), against what three times as
// many leave (`after_three`): unpatched, the table keeps every name, three times the first; with
// the bound, the table was emptied twice and holds at most a full table's worth again. The bound
// is the full table's own measured size, so no byte count is assumed.
void expect_bounded(Bus& bus, const std::string& suffix) {
  const std::size_t start = heap_in_use();
  publish_fresh(bus.lcm, "RDTF/a", suffix, kCachedChannels - 1);
  const auto first = static_cast<double>(heap_in_use() - start);
  publish_fresh(bus.lcm, "RDTF/b", suffix, 2 * kCachedChannels);
  const auto after_three = static_cast<double>(heap_in_use()) - static_cast<double>(start);
  EXPECT_GT(first, 20.0 * kCachedChannels);  // The table's entries are there to be bounded.
  EXPECT_LT(after_three, 1.25 * first) << "first " << first << " bytes";
}

TEST(LcmChannels, ChannelsNothingSubscribesToAreForgottenBeyondABound) {
  Bus bus;
  ASSERT_NE(bus.subscription, nullptr);
  expect_bounded(bus, "/ERROR");
  EXPECT_EQ(bus.received, 0);
}

// Channels a subscription matches are delivered whether or not the table still holds them, and a
// subscription made after the table was emptied and refilled sees its channels.
TEST(LcmChannels, MatchedChannelsAreDeliveredAndForgottenBeyondABound) {
  Bus bus;
  ASSERT_NE(bus.subscription, nullptr);
  expect_bounded(bus, "/JOINT_COMMAND");
  EXPECT_EQ(bus.received, 3 * kCachedChannels - 1);
  int late = 0;
  lcm_subscription_t* second = lcm_subscribe(bus.lcm, "RDTF/m7/JOINT_COMMAND", count_message, &late);
  publish_fresh(bus.lcm, "RDTF/m", "/JOINT_COMMAND", 10);
  EXPECT_EQ(late, 1);
  EXPECT_EQ(bus.received, 3 * kCachedChannels + 9);
  lcm_unsubscribe(bus.lcm, second);
}

}  // namespace
}  // namespace rdtf
