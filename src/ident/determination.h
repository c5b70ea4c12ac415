// What the data determine: one rule for every fit (valve, tube, friction,
// refinement). A coefficient counts as determined by the logs when its
// standard error (with model error, and with whatever prior the fit states)
// is below both a fraction of its value and its tolerance; a fit reports
// every other coefficient by name as held, with the reason. Partial
// identifiability instead of all-or-nothing: one poorly determined
// coefficient never throws away the ones the data determine.
#pragma once

namespace pneumaid::internal {

// `floor`: below this standard error a coefficient is determined whatever its
// value (a force near zero is determined to 0.1 N, not to 50 % of itself).
inline bool IsDetermined(double value, double standard_error, double floor, double relative_limit) {
  const double limit = relative_limit * (value < 0 ? -value : value);
  return standard_error <= (limit > floor ? limit : floor);  // NaN: not determined
}

}  // namespace pneumaid::internal
