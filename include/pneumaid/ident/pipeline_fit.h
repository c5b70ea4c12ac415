// Identification of the tube lag delta (seed paper Eq. 5) from pipeline logs:
// the valve feeds a tube open at its far end, flows logged at both ends. The
// command may take any sequence of held levels (one step; on, hold, off; a
// staircase; valve left open or closed at the end): the valve's flow is one
// unknown constant per held level. Per tube log, delta is fitted by output
// error over the whole record through the declared flow-meter lags (a meter
// lag that is ignored biases delta low): a scan over delta with the levels
// solved exactly (linear least squares) gives the start, then one Ceres
// problem fits levels and delta together. Then a law delta(L) across lengths.
#pragma once

#include <string>
#include <vector>

#include "pneumaid/ident/fit_result.h"
#include "pneumaid/io/rig_data.h"

namespace pneumaid {

struct PipelineFitOptions {
  // Where the search for delta starts (identify passes the prior's); the scan
  // over [min_delta_per_s, max_delta_per_s] replaces it when the scan's best
  // point explains the log better.
  double initial_delta_per_s = 5.0;
  // The scan's range and its points per decade (log-spaced).
  double min_delta_per_s = 0.2;
  double max_delta_per_s = 2000.0;
  int scan_points_per_decade = 12;
  // A change of the logged command larger than this starts a new held level;
  // smaller changes are the logger's noise.
  double level_change_V = 0.01;
  // Each held level is an unknown valve flow. A log with more held levels
  // than this (a ramp, a sampled signal) is fitted from the two meters'
  // readings alone instead: L_in q_out = L_out L_delta q_in whatever the
  // valve's flow (src/ident/tube_from_meters.h).
  int max_levels = 60;
  // delta counts as determined when its standard error is below this fraction
  // of its value; otherwise the tube is reported as not fitted.
  double determined_relative_error = 0.25;
  int max_iterations = 100;
  // A tube log fitted to a reduced chi-square above this is "the model does
  // not explain these logs" (its delta still written, identify exits 3).
  // Calibrated on the robustness sweep: over the 124 tube logs of seeds 12
  // and 77 (step, on-off, two levels, staircase, ramp; smooth-stick rigs)
  // the median is 1.01, the 90th percentile 1.98 and the largest 42, every
  // delta within 5 %; a unit's logs joined end to end (the flow jumping at
  // each seam) fitted to 4.97e3 with delta 3 times its own.
  double max_reduced_chi_square = 100;
  bool IsValid(std::string* error) const;
};

// One tube log's fit: the one coefficient "pipeline.delta" at this tube's
// length (not fitted, with the reason, when the log does not determine it).
struct TubeFit : FitResult {
  std::string experiment;
  double tube_length_m = 0;
  double flow_kg_per_s = 0;       // the largest steady valve flow of the held levels
  int levels = 0;                 // held command levels in the log
  double valve_lag_s = 0;         // the valve's own opening lag, fitted as a nuisance
  double reduced_chi_square = 0;  // final cost per degree of freedom (1: noise alone)

  double delta_per_s() const { return coefficients.front().value; }
  double delta_standard_error() const { return coefficients.front().standard_error; }
};

// The one coefficient "pipeline.delta" at the rig's tube, from the law
// delta(L) through the tubes that were fitted; the rig's tube length's value
// of the law and its error. The tubes' own fits beside it.
struct PipelineFitResult : FitResult {
  std::vector<TubeFit> tubes;
  // delta(L) = intercept + slope L, weighted least squares over the fitted
  // tubes (slope 0 with one tube).
  double law_intercept_per_s = 0, law_slope_per_s_m = 0;
  std::string BriefReport() const;
};

PipelineFitResult FitPipeline(const Unit& unit, const PipelineFitOptions& options);

}  // namespace pneumaid
