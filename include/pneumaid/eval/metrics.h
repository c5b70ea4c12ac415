// How far a simulated run is from a measured one, per channel. Plain data:
// the report writers and the discrepancy workflow read these structs.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "pneumaid/trajectory.h"

namespace pneumaid {

struct ChannelMetrics {
  double rmse = 0.0;     // SI units of the channel
  double max_abs = 0.0;  // SI units of the channel
  // 100 (1 - ||y - y_sim|| / ||y - mean(y)||); empty where ||y - mean(y)|| is
  // below the channel's noise (sigma sqrt(N)): a flat signal has no fit.
  std::optional<double> nrmse_fit_percent;
};

// Compares two equally long signals; `noise_sigma` (SI) when the instrument
// declared one.
ChannelMetrics CompareChannel(const std::vector<double>& measured,
                              const std::vector<double>& simulated,
                              std::optional<double> noise_sigma);

// The channels both runs have (x, p1, p2, q1, q2), by name. Runs must share
// their sample times.
std::map<std::string, ChannelMetrics> CompareRuns(const Trajectory& measured,
                                                  const Trajectory& simulated,
                                                  const std::map<std::string, double>& noise_sigma);

// A first-order lag (time constant tau) applied to a signal sampled at times
// t and held between samples: what an instrument with that lag reads.
std::vector<double> FirstOrderLag(const std::vector<double>& t_s, const std::vector<double>& signal,
                                  double tau_s);

}  // namespace pneumaid
