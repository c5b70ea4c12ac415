// What the data determine: the one rule of the tube and friction fits (the
// valve fit and refinement have their own, to be brought here). A coefficient
// counts as determined by the logs when its standard error (the fit's own:
// with model error as the fit scales it, and with whatever prior the fit
// states; the friction fit's widening where it disagrees with its reading
// off the logs comes after) is below a fraction of its value or
// below its tolerance, whichever is larger; a fit reports every other
// coefficient by name as held, with the reason. Partial
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

// How much a residual's correlation from sample to sample widens a
// Gauss-Newton covariance: (1 + rho) / (1 - rho) for the lag-one
// autocorrelation rho = lagged / squared (sum r_i r_(i+1) over sum r_i^2)
// when positive, else 1; rho capped at 0.999. An AR(1) residual carries that
// many times less information than as many white ones: white noise gives
// about 1, a model error that lasts many samples nearly 2000.
inline double CorrelationInflation(double lagged, double squared) {
  double rho = squared > 0 ? lagged / squared : 0.0;
  if (rho > 0.999) rho = 0.999;
  return rho > 0 ? (1 + rho) / (1 - rho) : 1.0;
}

}  // namespace pneumaid::internal
