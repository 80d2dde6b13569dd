// liblcm 1.3.1 kept every channel name a process received in a table until lcm_destroy, whether
// or not anything subscribed to it (about 100 bytes a name): rdtfd's own messages, looped back by
// multicast under a channel per model id, and any peer sending on ever new names grew every rdtf
// process without bound. scripts/lcm/lcm-1.3.1-handlers-map-bound.patch remembers only channels a
// subscription matches, at most 4,096 of them. Checked here through liblcm's in-process provider
// (memq://, whose publish asks the same table), by the heap the process holds.
#include <gtest/gtest.h>
#include <lcm/lcm.h>
#include <malloc.h>

#include <cstdint>
#include <string>

#if defined(__SANITIZE_ADDRESS__)
#define RDTF_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RDTF_TEST_ASAN 1
#endif
#endif
#ifdef RDTF_TEST_ASAN
#include <sanitizer/allocator_interface.h>
#endif

namespace rdtf {
namespace {

// Bytes of heap in use: AddressSanitizer's allocator in such a build, glibc's otherwise.
std::int64_t heap_in_use() {
#ifdef RDTF_TEST_ASAN
  return static_cast<std::int64_t>(__sanitizer_get_current_allocated_bytes());
#else
  return static_cast<std::int64_t>(mallinfo2().uordblks);
#endif
}

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

// 100,000 names: the unpatched table grew the heap by 6.8 MB; a bound of 1 MB leaves the heap's own
// noise (a few pages) and fails any growth of 10 bytes a name or more.
TEST(LcmChannels, ChannelsNothingSubscribesToAreNotRemembered) {
  lcm_t* lcm = lcm_create("memq://");
  ASSERT_NE(lcm, nullptr);
  int received = 0;
  lcm_subscription_t* subscription = lcm_subscribe(lcm, "RDTF/.*/JOINT_COMMAND", count_message, &received);
  ASSERT_NE(subscription, nullptr);
  publish_fresh(lcm, "RDTF/warm", "/ERROR", 1000);
  const std::int64_t before = heap_in_use();
  publish_fresh(lcm, "RDTF/m", "/ERROR", 100000);
  EXPECT_LT(heap_in_use() - before, 1 << 20);
  EXPECT_EQ(received, 0);
  lcm_unsubscribe(lcm, subscription);
  lcm_destroy(lcm);
}

// Channels a subscription matches are remembered, at most 4,096 (about 100 bytes each, 0.4 MB):
// 100,000 fresh JOINT_COMMAND names are all delivered, and the heap grows by less than 1 MB.
TEST(LcmChannels, MatchedChannelsAreDeliveredAndRememberedUpToABound) {
  lcm_t* lcm = lcm_create("memq://");
  ASSERT_NE(lcm, nullptr);
  int received = 0;
  lcm_subscription_t* subscription = lcm_subscribe(lcm, "RDTF/.*/JOINT_COMMAND", count_message, &received);
  ASSERT_NE(subscription, nullptr);
  publish_fresh(lcm, "RDTF/warm", "/JOINT_COMMAND", 5000);
  const std::int64_t before = heap_in_use();
  publish_fresh(lcm, "RDTF/m", "/JOINT_COMMAND", 100000);
  EXPECT_LT(heap_in_use() - before, 1 << 20);
  EXPECT_EQ(received, 105000);
  // A subscription made after the table was emptied and refilled still sees its channels.
  int late = 0;
  lcm_subscription_t* second = lcm_subscribe(lcm, "RDTF/m7/JOINT_COMMAND", count_message, &late);
  publish_fresh(lcm, "RDTF/m", "/JOINT_COMMAND", 10);
  EXPECT_EQ(late, 1);
  EXPECT_EQ(received, 105010);
  lcm_unsubscribe(lcm, second);
  lcm_unsubscribe(lcm, subscription);
  lcm_destroy(lcm);
}

}  // namespace
}  // namespace rdtf
