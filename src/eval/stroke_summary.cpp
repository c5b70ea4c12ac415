#include "pneumaid/eval/stroke_summary.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace pneumaid {

StrokeSummary SummarizeStroke(const Trajectory& run, double half_stroke_m, double end_margin_m) {
  StrokeSummary out;
  if (run.size() == 0) return out;
  const double x0 = run.x_m.front();
  const double start_side = x0 >= 0 ? 1.0 : -1.0;
  const double far_end = -start_side * half_stroke_m;
  for (std::size_t i = 0; i < run.size(); ++i) {
    const double x = run.x_m[i];
    if (!out.mid_stroke_time_s && x0 != 0 && x * start_side <= 0)
      out.mid_stroke_time_s = run.t_s[i];
    if (!out.end_reached_time_s && std::fabs(x - far_end) <= end_margin_m) {
      out.end_reached_time_s = run.t_s[i];
    }
  }
  out.peak_p1_Pa = *std::max_element(run.p1_Pa.begin(), run.p1_Pa.end());
  out.peak_p2_Pa = *std::max_element(run.p2_Pa.begin(), run.p2_Pa.end());
  out.final_x_m = run.x_m.back();
  return out;
}

std::string StrokeSummary::Describe() const {
  std::ostringstream out;
  if (mid_stroke_time_s)
    out << "mid-stroke crossed at " << *mid_stroke_time_s << " s";
  else
    out << "mid-stroke never crossed";
  if (end_reached_time_s)
    out << ", far end reached at " << *end_reached_time_s << " s";
  else
    out << ", far end never reached";
  out << ", peak p1 " << peak_p1_Pa / 1e5 << " bar, peak p2 " << peak_p2_Pa / 1e5
      << " bar (absolute), final x " << final_x_m * 1e3 << " mm";
  return out.str();
}

}  // namespace pneumaid
