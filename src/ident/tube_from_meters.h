// The tube fit of a log whose command is not held (a ramp, a sampled
// signal): no level flows to solve for, delta from the two meters' readings
// alone (tube_from_meters.cpp).
#pragma once

#include <algorithm>
#include <cmath>

#include "pneumaid/ident/pipeline_fit.h"
#include "pneumaid/io/rig_data.h"

namespace pneumaid::internal {

// The scan over delta both tube fits start from: points + 1 log-spaced
// values from min_delta_per_s to max_delta_per_s, scan_points_per_decade a
// decade; At(k) for any k in [0, points] (a search between scan points).
struct DeltaScan {
  explicit DeltaScan(const PipelineFitOptions& options)
      : low_per_s(options.min_delta_per_s),
        decades(std::log10(options.max_delta_per_s / options.min_delta_per_s)),
        points(std::max(2, static_cast<int>(std::ceil(decades * options.scan_points_per_decade)))) {
  }
  double At(double k) const { return low_per_s * std::pow(10.0, decades * k / points); }

  double low_per_s, decades;
  int points;
};

// Fits delta of the tube log `e` into `fit` (its status, reason, value and
// standard error). The standard error: the meters' white noise through the
// filters (the adjoint lags applied to the sensitivity), widened by the
// reduced chi-square when above 1, or the sandwich clustered by blocks of
// five correlation times (the residuals are filtered, so neighbours
// correlate) when that is larger. sigma_in and sigma_out are the meters'
// noise (declared or read off the log).
void FitTubeFromMeters(const Experiment& e, const Manifest& manifest,
                       const PipelineFitOptions& options, double sigma_in, double sigma_out,
                       TubeFit* fit);

}  // namespace pneumaid::internal
