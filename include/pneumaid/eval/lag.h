// The first-order lag of a sampled signal held between samples (exact for
// such a signal): what an instrument with a lag reads, and Eq. 5 between a
// tube's ends. One implementation for the synthetic rig, validation and the
// fits (templated so that Ceres can differentiate through it).
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace pneumaid {

// Lags `signal` in place with time constant tau_s from the output `start`
// at the first sample (the lag's state there); interval_s(i) is the time from
// sample i - 1 to sample i.
template <typename T, typename Interval>
void ApplyFirstOrderLagFrom(const Interval& interval_s, const T& tau_s, const T& start,
                            std::vector<T>* signal) {
  using std::exp;
  if (signal->empty()) return;
  T previous_input = (*signal)[0];
  (*signal)[0] = start;
  for (std::size_t i = 1; i < signal->size(); ++i) {
    const T keep = exp(-T(interval_s(i)) / tau_s);
    const T input = (*signal)[i];
    (*signal)[i] = keep * (*signal)[i - 1] + (T(1.0) - keep) * previous_input;
    previous_input = input;
  }
}

// The same, settled for the first input.
template <typename T, typename Interval>
void ApplyFirstOrderLag(const Interval& interval_s, const T& tau_s, std::vector<T>* signal) {
  if (signal->empty()) return;
  const T start = (*signal)[0];
  ApplyFirstOrderLagFrom(interval_s, tau_s, start, signal);
}

}  // namespace pneumaid
