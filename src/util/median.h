// The median of a sample, as the fits, the noise estimates and validation
// read a typical value (the upper one of the two middle values for an even
// count): the one home of that rule.
#pragma once

#include <algorithm>
#include <vector>

namespace pneumaid::internal {

// The median of `values` (not empty).
inline double Median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace pneumaid::internal
