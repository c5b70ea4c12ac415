// Identification of the tube lag delta (seed paper Eq. 5) from pipeline logs:
// a valve step from supply into a tube open at its far end, flows logged at
// both ends. Per tube length one Ceres problem fits the flow amplitude and
// delta by output error through the declared flow-meter lags (a meter lag
// that is ignored biases delta low), then a law delta(L) across lengths.
#pragma once

#include <string>
#include <vector>

#include "pneumaid/io/rig_data.h"

namespace pneumaid {

struct PipelineFitOptions {
  // Where the search for delta starts (identify passes the prior's).
  double initial_delta_per_s = 5.0;
  int max_iterations = 100;
  bool IsValid(std::string* error) const;
};

struct TubeFit {
  std::string experiment;
  double tube_length_m = 0;
  bool fitted = false;
  std::string note;
  double delta_per_s = 0, delta_standard_error = 0;
  double flow_kg_per_s = 0;  // the step's steady mass flow
  double final_cost = 0;
  int iterations = 0;
};

struct PipelineFitResult {
  std::vector<TubeFit> tubes;
  // delta(L) = intercept + slope L, weighted least squares over the fitted
  // tubes (slope 0 with one tube); the law's value and error at the rig's tube.
  double law_intercept_per_s = 0, law_slope_per_s_m = 0;
  double delta_at_rig_per_s = 0, delta_at_rig_standard_error = 0;
  bool fitted = false;
  std::string note;
  std::string BriefReport() const;
};

PipelineFitResult FitPipeline(const Unit& unit, const PipelineFitOptions& options);

}  // namespace pneumaid
