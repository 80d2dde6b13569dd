// Statistics for whole_process_bench: the median of per-pair ratios with a distribution-free
// confidence interval, and the outlier rule. Kept apart from the process handling so that
// tests/bench can check them on values with known answers.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <vector>

namespace rdtf::bench {

inline double median_of(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  if (n == 0) return std::nan("");
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// P(X <= k) for X ~ Binomial(n, 1/2), summed in logs (n up to thousands without overflow).
inline double binomial_half_cdf(std::size_t n, std::size_t k) {
  double sum = 0;
  const double log_half_n = static_cast<double>(n) * std::log(0.5);
  for (std::size_t i = 0; i <= k && i <= n; ++i) {
    const double log_choose = std::lgamma(static_cast<double>(n) + 1) - std::lgamma(static_cast<double>(i) + 1) -
                              std::lgamma(static_cast<double>(n - i) + 1);
    sum += std::exp(log_choose + log_half_n);
  }
  return std::min(sum, 1.0);
}

// The order-statistics confidence interval of a median: with the sample sorted, [x(k), x(n+1-k)]
// (1-based) holds the population median with probability 1 - 2 P(X <= k-1), X ~ Bin(n, 1/2),
// whatever the distribution (only independence of the samples is assumed). k is the largest
// rank whose coverage is still at least `confidence`; below 6 samples no 95 % interval exists.
struct MedianInterval {
  double median = 0;
  double low = 0;
  double high = 0;
  double coverage = 0;  // The interval's exact coverage (>= the confidence asked).
  std::size_t rank = 0; // k above.
};

inline std::optional<MedianInterval> median_interval(std::vector<double> values, double confidence) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  std::optional<MedianInterval> best;
  for (std::size_t k = 1; 2 * k <= n + 1; ++k) {
    const double coverage = 1 - 2 * binomial_half_cdf(n, k - 1);
    if (coverage < confidence) break;
    best = MedianInterval{median_of(values), values[k - 1], values[n - k], coverage, k};
  }
  return best;
}

// Tukey's far-out rule: above Q3 + 3 IQR (quartiles by the median of each half). Runs of a shared
// machine are only ever slowed, so only the slow side is flagged.
inline double far_out_limit(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  if (n < 4) return INFINITY;
  const std::vector<double> lower(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(n / 2));
  const std::vector<double> upper(values.begin() + static_cast<std::ptrdiff_t>((n + 1) / 2), values.end());
  const double q1 = median_of(lower);
  const double q3 = median_of(upper);
  return q3 + 3 * (q3 - q1);
}

}  // namespace rdtf::bench
