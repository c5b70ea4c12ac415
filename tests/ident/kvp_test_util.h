// How far a fitted K_vp is from the truth, for the valve fit's tests and the
// robustness sweep.
#pragma once

#include <algorithm>
#include <cmath>

#include "pneumaid/model/kvp.h"

namespace pneumaid::testing {

// The largest |K_vp fitted - K_vp true| / q_max over u in [0, 1] outside the
// gap (gap_low, gap_high] of the staircase that holds the true u_sat: no
// plateau there tells where the polynomial ends.
inline double WorstKvpError(const KvpBranchParams& fitted, const KvpBranchParams& real,
                            double gap_low = 1, double gap_high = 1) {
  const auto c_fit = MakeKvpCoefficients<double>(fitted);
  const auto c_true = MakeKvpCoefficients<double>(real);
  double worst = 0;
  for (int k = 0; k <= 1000; ++k) {
    const double u = k / 1000.0;
    if (u > gap_low && u <= gap_high) continue;
    worst = std::max(worst, std::fabs(Kvp(u, c_fit) - Kvp(u, c_true)) / real.q_max_kg_per_s);
  }
  return worst;
}

}  // namespace pneumaid::testing
