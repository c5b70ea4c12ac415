// The held levels of a logged command: the valve and tube fits both read
// their experiments as a sequence of commands held for a while. A logger's
// noise on the command (a measured voltage, a rounding) does not start a new
// level; a step larger than the threshold does.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include "../util/median.h"
#include "centred_mean.h"

namespace pneumaid::internal {

// [begin, end) sample ranges of the runs whose command stays within
// `change_V` of the run's mean so far: a new level starts where two samples
// in a row leave it by more (one sample's noise does not; compared with the
// run's first sample instead, a logged command with 2 mV of noise split a
// 0.3 s level at 2 kHz one time in four, and the valve fit took the second
// half for the other branch).
inline std::vector<std::pair<std::size_t, std::size_t>> HeldLevels(const std::vector<double>& u,
                                                                   double change_V) {
  std::vector<std::pair<std::size_t, std::size_t>> levels;
  if (u.empty()) return levels;
  std::size_t begin = 0;
  double sum = u[0];
  const auto leaves = [&](std::size_t i, double mean) {
    return i < u.size() && std::fabs(u[i] - mean) > change_V;
  };
  for (std::size_t i = 1; i <= u.size(); ++i) {
    const double mean = sum / static_cast<double>(i - begin);
    if (i == u.size() || (leaves(i, mean) && (i + 1 == u.size() || leaves(i + 1, mean)))) {
      levels.push_back({begin, i});
      begin = i;
      sum = 0;
    }
    if (i < u.size()) sum += u[i];
  }
  return levels;
}

// The command as set, for latching the valve's branch (BranchLatch): a
// logged command's noise, read off its second differences (1.4826 x their
// median absolute value / sqrt 6: a ramp's slope cancels, a staircase's steps
// are too few to move it), averaged out by a centred mean over as many
// samples as bring it below 0.5 mV, a twentieth of the latch's 0.01 V. A
// command logged as set (noise below 0.1 mV: the log's rounding) is returned
// as it is. Latching each logged sample of a valve ramp with 2 mV of noise
// took a sweep unit's decreasing branch to a cost of 2.8e4 for 91 and its
// u_sat to 0.94 for 0.62.
inline std::vector<double> CommandAsSet(const std::vector<double>& u) {
  if (u.size() < 3) return u;
  std::vector<double> curvature(u.size() - 2);
  for (std::size_t i = 1; i + 1 < u.size(); ++i)
    curvature[i - 1] = std::fabs(u[i + 1] - 2 * u[i] + u[i - 1]);
  const double sigma_V = 1.4826 * Median(std::move(curvature)) / std::sqrt(6.0);
  if (!(sigma_V > 1e-4)) return u;
  const double ratio = sigma_V / 5e-4;
  const std::size_t half =
      std::min<std::size_t>(static_cast<std::size_t>(std::ceil(0.5 * ratio * ratio)), u.size() / 2);
  return CentredMean(u, half, u.size());
}

}  // namespace pneumaid::internal
