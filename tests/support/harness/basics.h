// What every part of the daemon test harness shares: names, the clock, and waiting with a deadline.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>

#include <nlohmann/json.hpp>

#include "support/test_support.h"

namespace rdtf::itest {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;
using namespace std::chrono_literals;
using testing::TempDir;

inline constexpr const char* kPrefix = "RDTF";

// Polls `predicate` every 5 ms until it holds (true) or `timeout` passes (false). Deadlines only
// bound how long a failing test hangs; sanitizer builds run several times slower, so their
// deadlines stretch by deadline_scale() (RDTF_TEST_DEADLINE_SCALE, set by CMake).
bool wait_until(const std::function<bool()>& predicate, Clock::duration timeout);
int deadline_scale();

}  // namespace rdtf::itest
