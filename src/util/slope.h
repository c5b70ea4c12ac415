// The least-squares slope of a sampled signal over its first samples: the
// one home of that sum (a moving start's speed, a command's rate).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace pneumaid::internal {

// The sums of a least-squares line through samples [0, n) of v(t).
struct LeadingLine {
  double t_mean = 0, v_mean = 0;
  double tt = 0, tv = 0;  // sums of (t - t_mean)^2 and (t - t_mean)(v - v_mean)
  double slope() const { return tt > 0 ? tv / tt : 0.0; }
};

inline LeadingLine FitLeadingLine(const std::vector<double>& t, const std::vector<double>& v,
                                  std::size_t n) {
  LeadingLine line;
  for (std::size_t i = 0; i < n; ++i) line.t_mean += t[i], line.v_mean += v[i];
  line.t_mean /= static_cast<double>(n);
  line.v_mean /= static_cast<double>(n);
  for (std::size_t i = 0; i < n; ++i) {
    line.tv += (t[i] - line.t_mean) * (v[i] - line.v_mean);
    line.tt += (t[i] - line.t_mean) * (t[i] - line.t_mean);
  }
  return line;
}

// d v / d t fitted over samples [0, n) (0 when they span no time).
inline double LeadingSlope(const std::vector<double>& t, const std::vector<double>& v,
                           std::size_t n) {
  return FitLeadingLine(t, v, n).slope();
}

// |d v / d t| over samples [0, n) in standard errors of the slope (the
// residuals' spread about the line, at least `floor` per sample); 0 for
// fewer than three samples.
inline double LeadingSlopeSigmas(const std::vector<double>& t, const std::vector<double>& v,
                                 std::size_t n, double floor) {
  if (n < 3) return 0.0;
  const LeadingLine line = FitLeadingLine(t, v, n);
  if (!(line.tt > 0)) return 0.0;
  double squares = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = v[i] - line.v_mean - line.slope() * (t[i] - line.t_mean);
    squares += r * r;
  }
  const double variance = std::max(floor * floor, squares / static_cast<double>(n - 2));
  return std::fabs(line.slope()) / std::sqrt(variance / line.tt);
}

}  // namespace pneumaid::internal
