// Logs read through the declared meter lags undone: the friction fit drives
// its replays with the logged pressures and reads breakaways off them, so an
// instrument's lag (the manifest's sensors: tau) would pass for friction (a
// 2 ms lag on both pressures of a 1 kHz unit took its Fs 12 and 24 % low).
// The refinement needs none of this: it lags its simulation instead.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "pneumaid/io/rig_data.h"

namespace pneumaid::internal {

// The largest factor by which LagUndone may multiply a reading's noise.
constexpr double kMaxLagNoiseGain = 3.0;

// How LagUndone reads a signal sampled every period_s through a lag tau_s:
// the exact inverse's noise gain sqrt(1 + k^2) / (1 - k), k = exp(-period_s /
// tau_s), brought to at most kMaxLagNoiseGain by averaging `samples` of it.
struct LagInverse {
  int samples = 1;
  double noise_gain = 1;  // of the result, for the fit's weights
};
LagInverse PlanLagInverse(double period_s, double tau_s);

// What an instrument with first-order lag tau_s saw, from its reading (the
// exact inverse of ApplyFirstOrderLag, eval/lag.h), averaged over
// PlanLagInverse's samples centred on each (at the median sampling interval);
// the reading itself where tau_s <= 0.
std::vector<double> LagUndone(const std::vector<double>& t_s, const std::vector<double>& reading,
                              double tau_s);

// `e` with LagUndone applied to each of `columns` whose instrument `manifest`
// declares a lag; nullptr when none of them has one.
std::shared_ptr<const Experiment> WithLagsUndone(const Experiment& e, const Manifest& manifest,
                                                 const std::vector<std::string>& columns);

}  // namespace pneumaid::internal
