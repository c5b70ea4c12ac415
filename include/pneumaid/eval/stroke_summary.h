// Landmarks of a stroke: when the rod crosses mid-stroke, when it reaches the
// end, and the pressure peaks. Used to summarise simulated and measured steps.
#pragma once

#include <optional>
#include <string>

#include "pneumaid/trajectory.h"

namespace pneumaid {

struct StrokeSummary {
  std::optional<double> mid_stroke_time_s;  // first crossing of x = 0 (either way)
  std::optional<double>
      end_reached_time_s;  // first time within `end_margin` of an end it was not at
  double peak_p1_Pa = 0;
  double peak_p2_Pa = 0;
  double final_x_m = 0;

  std::string Describe() const;
};

// `half_stroke_m` = L/2; an end counts as reached within end_margin_m of it.
StrokeSummary SummarizeStroke(const Trajectory& run, double half_stroke_m,
                              double end_margin_m = 1e-4);

}  // namespace pneumaid
