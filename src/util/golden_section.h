// Golden-section search for the minimum of a one-dimensional function on an
// interval: the one home of that loop (the tube's delta from its meters, a
// valve meter's lag, a log's lag start).
#pragma once

#include <cmath>

namespace pneumaid::internal {

struct GoldenSectionMinimum {
  double x = 0;              // the better of the last two interior points
  double value = 0;          // f there
  double low = 0, high = 0;  // the last bracket
};

// `iterations` steps of golden section on [low, high] (each shrinks it by
// 0.618): f evaluated iterations + 2 times.
template <typename F>
GoldenSectionMinimum GoldenSection(F&& f, double low, double high, int iterations) {
  const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = high - golden * (high - low), b = low + golden * (high - low);
  double fa = f(a), fb = f(b);
  for (int i = 0; i < iterations; ++i) {
    if (fa < fb) {
      high = b, b = a, fb = fa;
      a = high - golden * (high - low), fa = f(a);
    } else {
      low = a, a = b, fa = fb;
      b = low + golden * (high - low), fb = f(b);
    }
  }
  return fa < fb ? GoldenSectionMinimum{a, fa, low, high} : GoldenSectionMinimum{b, fb, low, high};
}

}  // namespace pneumaid::internal
