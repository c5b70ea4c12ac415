// The least-squares slope of a sampled signal over its first samples: the
// one home of that sum (a moving start's speed, a command's rate).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace pneumaid::internal {

// d v / d t fitted over samples [0, n) (0 when they span no time).
inline double LeadingSlope(const std::vector<double>& t, const std::vector<double>& v,
                           std::size_t n) {
  double t_mean = 0, v_mean = 0;
  for (std::size_t i = 0; i < n; ++i) t_mean += t[i], v_mean += v[i];
  t_mean /= static_cast<double>(n);
  v_mean /= static_cast<double>(n);
  double tv = 0, tt = 0;
  for (std::size_t i = 0; i < n; ++i) {
    tv += (t[i] - t_mean) * (v[i] - v_mean);
    tt += (t[i] - t_mean) * (t[i] - t_mean);
  }
  return tt > 0 ? tv / tt : 0.0;
}

// |d v / d t| over samples [0, n) in standard errors of the slope (the
// residuals' spread about the line, at least `floor` per sample); 0 for
// fewer than three samples.
inline double LeadingSlopeSigmas(const std::vector<double>& t, const std::vector<double>& v,
                                 std::size_t n, double floor) {
  if (n < 3) return 0.0;
  double t_mean = 0, v_mean = 0;
  for (std::size_t i = 0; i < n; ++i) t_mean += t[i], v_mean += v[i];
  t_mean /= static_cast<double>(n);
  v_mean /= static_cast<double>(n);
  double tt = 0;
  for (std::size_t i = 0; i < n; ++i) tt += (t[i] - t_mean) * (t[i] - t_mean);
  if (!(tt > 0)) return 0.0;
  const double slope = LeadingSlope(t, v, n);
  double squares = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = v[i] - v_mean - slope * (t[i] - t_mean);
    squares += r * r;
  }
  const double variance = std::max(floor * floor, squares / static_cast<double>(n - 2));
  return std::fabs(slope) / std::sqrt(variance / tt);
}

}  // namespace pneumaid::internal
