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
// `change_V` of the run's first sample.
inline std::vector<std::pair<std::size_t, std::size_t>> HeldLevels(const std::vector<double>& u,
                                                                   double change_V) {
  std::vector<std::pair<std::size_t, std::size_t>> levels;
  std::size_t begin = 0;
  for (std::size_t i = 1; i <= u.size(); ++i) {
    if (i == u.size() || std::fabs(u[i] - u[begin]) > change_V) {
      levels.push_back({begin, i});
      begin = i;
    }
  }
  return levels;
}

}  // namespace pneumaid::internal
