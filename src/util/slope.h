// The least-squares slope of a sampled signal over its first samples: the
// one home of that sum (a moving start's speed, a command's rate).
#pragma once

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

}  // namespace pneumaid::internal
