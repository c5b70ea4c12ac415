#include <cmath>

#include "pneumaid/ident/friction_fit.h"

namespace pneumaid {

bool FrictionFitOptions::IsValid(std::string* error) const {
  const auto fail = [error](const char* what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (!(stuck_band_m > 0)) return fail("stuck_band_m must be > 0");
  if (min_stuck_samples < 2) return fail("min_stuck_samples must be >= 2");
  if (max_stuck_samples < 2) return fail("max_stuck_samples must be >= 2");
  if (arrest_samples < 0) return fail("arrest_samples must be >= 0");
  if (stuck_force_samples < 3) return fail("stuck_force_samples must be >= 3");
  if (!(end_margin_m >= 0)) return fail("end_margin_m must be >= 0");
  if (!(end_slide_m >= 0)) return fail("end_slide_m must be >= 0");
  if (max_substeps < 1) return fail("max_substeps must be >= 1");
  if (!(replay_step_s > 0)) return fail("replay_step_s must be > 0");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(outlier_ratio > 1)) return fail("outlier_ratio must be > 1");
  if (!(identifiable_relative_error > 0)) return fail("identifiable_relative_error must be > 0");
  if (!(prior_static_sigma_N > 0) || !(prior_dynamic_sigma_N > 0) ||
      !(prior_viscous_sigma_N_s_per_m > 0) || !(prior_stribeck_log_sigma > 0))
    return fail("prior_*_sigma must be > 0");
  if (!(min_stuck_s >= 0)) return fail("min_stuck_s must be >= 0");
  if (!(max_stuck_speed_m_per_s > 0)) return fail("max_stuck_speed_m_per_s must be > 0");
  if (!(max_stuck_acceleration_m_per_s2 > 0))
    return fail("max_stuck_acceleration_m_per_s2 must be > 0");
  if (!(max_slide_s > 0)) return fail("max_slide_s must be > 0");
  if (!(breakaway_timing_per_s >= 0) || !std::isfinite(breakaway_timing_per_s))
    return fail("breakaway_timing_per_s must be finite and >= 0");
  return true;
}

}  // namespace pneumaid
