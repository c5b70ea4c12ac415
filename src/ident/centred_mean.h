// A centred moving mean, narrower but still centred at the ends: how the
// fits average out a logged signal's noise where a sample's neighbours on
// both sides are the same quantity (a lagged reading undone, meter_lag.h; a
// noisy command, held_levels.h).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace pneumaid::internal {

// The first `count` values of `v` (at most its size), each the mean of the
// 2 half + 1 values centred on it, fewer but centred where the ends are
// nearer (running sums: one pass).
inline std::vector<double> CentredMean(const std::vector<double>& v, std::size_t half,
                                       std::size_t count) {
  count = std::min(count, v.size());
  std::vector<double> sum(count + 1, 0.0);
  for (std::size_t i = 0; i < count; ++i) sum[i + 1] = sum[i] + v[i];
  std::vector<double> out(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t h = std::min({half, i, count - 1 - i});
    out[i] = (sum[i + h + 1] - sum[i - h]) / static_cast<double>(2 * h + 1);
  }
  return out;
}

}  // namespace pneumaid::internal
