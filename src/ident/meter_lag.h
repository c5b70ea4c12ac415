// Logs read through the declared meter lags undone: the friction fit drives
// its replays with the logged pressures, reads breakaways off them and
// compares the replayed rod with the logged position, so an instrument's lag
// (the manifest's sensors: tau) would pass for friction (a 2 ms lag on both
// pressures of a 0.15 kg rod at 1 kHz took its positive and negative Fs 12
// and 24 % low; a 3 ms lag on x left its replays 0.23 mm RMS off the log,
// 0.016 with the lag undone). Everything that reads the strokes through
// PrepareStrokes reads them so: the friction fit, the refinement's friction
// screen (the slides' force balance) and FrictionFromSlides. The refinement's
// own residuals lag the simulation instead.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "pneumaid/io/rig_data.h"

namespace pneumaid::internal {

// The largest factor by which LagUndone may multiply a reading's noise.
constexpr double kMaxLagNoiseGain = 3.0;

// How LagUndone reads a signal sampled every period_s through a lag tau_s:
// the exact inverse's noise gain is G = sqrt(1 + k^2) / (1 - k), k =
// exp(-period_s / tau_s); a centred mean of an odd number m of its values
// has gain sqrt(G^2 + m - 1) / m (their sum telescopes but for its ends), m
// the smallest that brings it to at most kMaxLagNoiseGain. The gain is the
// per-sample noise's: a sum over many samples keeps the reading's (the
// inverse passes a constant unchanged).
struct LagInverse {
  int samples = 1;
  double noise_gain = 1;
};
LagInverse PlanLagInverse(double period_s, double tau_s);

// What an instrument with first-order lag tau_s saw, from its reading: the
// exact inverse of ApplyFirstOrderLag (eval/lag.h: the rig's lag of a signal
// held between samples; a transmitter that lags a continuous signal comes
// back half a sample to a sample early), averaged over PlanLagInverse's
// samples at the median interval, centred on each (fewer, still centred, at
// the ends). The reading itself where tau_s <= 0; `t_s` and `reading` must be
// equally long and `t_s` increasing.
std::vector<double> LagUndone(const std::vector<double>& t_s, const std::vector<double>& reading,
                              double tau_s);

// `e` with LagUndone applied to each of `columns` whose instrument `manifest`
// declares a lag; nullptr when none of them has one.
std::shared_ptr<const Experiment> WithLagsUndone(const Experiment& e, const Manifest& manifest,
                                                 const std::vector<std::string>& columns);

}  // namespace pneumaid::internal
