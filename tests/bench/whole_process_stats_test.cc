// The statistics whole_process_bench reports its verdicts with (bench/whole_process_bench_stats.h),
// against values worked out by hand from the binomial distribution.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "../../bench/whole_process_bench_stats.h"

namespace rdtf::bench {
namespace {

std::vector<double> one_to(int n) {
  std::vector<double> v;
  for (int i = n; i >= 1; --i) v.push_back(i);  // Unsorted on purpose.
  return v;
}

// Summed through lgamma and exp (a few ulps each, on logs below 30): relative 1e-12.
TEST(WholeProcessStats, BinomialHalfCdfExact) {
  EXPECT_NEAR(binomial_half_cdf(11, 1), 12.0 / 2048.0, 1e-12 * 12.0 / 2048.0);  // (1 + 11) / 2^11
  EXPECT_NEAR(binomial_half_cdf(11, 2), 67.0 / 2048.0, 1e-12 * 67.0 / 2048.0);  // (1 + 11 + 55) / 2^11
  EXPECT_NEAR(binomial_half_cdf(41, 40), 1.0 - std::ldexp(1.0, -41), 1e-12);
}

TEST(WholeProcessStats, MedianIntervalRanks) {
  // n = 11: ranks 2 and 10 cover 1 - 2 * 12/2048 = 0.98828; ranks 3 and 9 only 0.9346.
  const auto eleven = median_interval(one_to(11), 0.95);
  ASSERT_TRUE(eleven.has_value());
  EXPECT_EQ(eleven->rank, 2u);
  EXPECT_DOUBLE_EQ(eleven->low, 2);
  EXPECT_DOUBLE_EQ(eleven->high, 10);
  EXPECT_DOUBLE_EQ(eleven->median, 6);
  EXPECT_NEAR(eleven->coverage, 1 - 2 * 12.0 / 2048.0, 1e-12);
  // n = 41: the tabulated 95 % ranks are 14 and 28 (coverage 0.97247).
  const auto forty_one = median_interval(one_to(41), 0.95);
  ASSERT_TRUE(forty_one.has_value());
  EXPECT_EQ(forty_one->rank, 14u);
  EXPECT_DOUBLE_EQ(forty_one->low, 14);
  EXPECT_DOUBLE_EQ(forty_one->high, 28);
  EXPECT_NEAR(forty_one->coverage, 0.9724668441704125, 1e-12);
  // n = 5: even the extremes cover only 1 - 2/32 = 0.9375, so there is no 95 % interval.
  EXPECT_FALSE(median_interval(one_to(5), 0.95).has_value());
  const auto six = median_interval(one_to(6), 0.95);
  ASSERT_TRUE(six.has_value());
  EXPECT_DOUBLE_EQ(six->low, 1);
  EXPECT_DOUBLE_EQ(six->high, 6);
  EXPECT_DOUBLE_EQ(six->median, 3.5);
}

TEST(WholeProcessStats, FarOutLimit) {
  // 1..8: lower half 1..4 (Q1 2.5), upper half 5..8 (Q3 6.5), IQR 4: limit 6.5 + 12.
  EXPECT_DOUBLE_EQ(far_out_limit(one_to(8)), 18.5);
  // 1..9: halves 1..4 and 6..9 (the median left out): Q1 2.5, Q3 7.5, limit 22.5.
  EXPECT_DOUBLE_EQ(far_out_limit(one_to(9)), 22.5);
  EXPECT_TRUE(std::isinf(far_out_limit({1, 2, 3})));
}

}  // namespace
}  // namespace rdtf::bench
