// The held levels of a logged command: the valve and tube fits both read
// their experiments as a sequence of commands held for a while. A logger's
// noise on the command (a measured voltage, a rounding) does not start a new
// level; a step larger than the threshold does.
#pragma once

#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

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

}  // namespace pneumaid::internal
