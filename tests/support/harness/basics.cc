#include "support/harness/basics.h"

#include <thread>

#ifndef RDTF_TEST_DEADLINE_SCALE
#define RDTF_TEST_DEADLINE_SCALE 1
#endif

namespace rdtf::itest {

int deadline_scale() { return RDTF_TEST_DEADLINE_SCALE; }

bool wait_until(const std::function<bool()>& predicate, Clock::duration timeout) {
  const auto deadline = Clock::now() + timeout * deadline_scale();
  for (;;) {
    if (predicate()) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(5ms);
  }
}

}  // namespace rdtf::itest
