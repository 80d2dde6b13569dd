// liblcm 1.3.1 kept every channel name a process received in a table until lcm_destroy, whether
// or not anything subscribed to it (about 100 bytes a name): rdtfd's own messages, looped back by
// multicast under a channel per model id, and any peer sending on ever new names grew every rdtf
// process without bound. scripts/lcm/lcm-1.3.1-handlers-map-bound.patch remembers only channels a
// subscription matches, at most 4,096 of them. Checked here through liblcm's in-process provider
// (memq://, whose publish asks the same table), by the heap the process holds.
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

// An in-process bus subscribed to every model's JOINT_COMMAND, as rdtfd is.
struct Bus {
  Bus() : lcm(lcm_create("memq://")) {
    if (lcm != nullptr) subscription = lcm_subscribe(lcm, "RDTF/.*/JOINT_COMMAND", count_message, &received);
  }
  ~Bus() {
    if (subscription != nullptr) lcm_unsubscribe(lcm, subscription);
    if (lcm != nullptr) lcm_destroy(lcm);
  }
  // The heap `names` fresh channels of "RDTF/m<i><suffix>" leave behind, after a warm-up.
  std::ptrdiff_t growth(const std::string& suffix, int warm_up, int names) {
    publish_fresh(lcm, "RDTF/warm", suffix, warm_up);
    const std::size_t before = heap_in_use();
    publish_fresh(lcm, "RDTF/m", suffix, names);
    return static_cast<std::ptrdiff_t>(heap_in_use()) - static_cast<std::ptrdiff_t>(before);
  }
  lcm_t* lcm;
  lcm_subscription_t* subscription = nullptr;
  int received = 0;
};

// 100,000 names: the unpatched table grew the heap by 6.8 MB; a bound of 1 MB leaves the heap's own
// noise (a few pages) and fails any growth of 10 bytes a name or more.
TEST(LcmChannels, ChannelsNothingSubscribesToAreNotRemembered) {
  Bus bus;
  ASSERT_NE(bus.subscription, nullptr);
  EXPECT_LT(bus.growth("/ERROR", 1000, 100000), 1 << 20);
  EXPECT_EQ(bus.received, 0);
}

// Channels a subscription matches are remembered, at most 4,096 (about 100 bytes each, 0.4 MB):
// 100,000 fresh JOINT_COMMAND names are all delivered, and the heap grows by less than 1 MB.
TEST(LcmChannels, MatchedChannelsAreDeliveredAndRememberedUpToABound) {
  Bus bus;
  ASSERT_NE(bus.subscription, nullptr);
  EXPECT_LT(bus.growth("/JOINT_COMMAND", 5000, 100000), 1 << 20);
  EXPECT_EQ(bus.received, 105000);
  // A subscription made after the table was emptied and refilled still sees its channels.
  int late = 0;
  lcm_subscription_t* second = lcm_subscribe(bus.lcm, "RDTF/m7/JOINT_COMMAND", count_message, &late);
  publish_fresh(bus.lcm, "RDTF/m", "/JOINT_COMMAND", 10);
  EXPECT_EQ(late, 1);
  EXPECT_EQ(bus.received, 105010);
  lcm_unsubscribe(bus.lcm, second);
}

}  // namespace
}  // namespace rdtf
