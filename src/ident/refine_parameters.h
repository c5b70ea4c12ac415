// Refinement (refine.h), its free parameters: the bounds map between the
// solver's unconstrained coordinates and the parameters' values, and the
// Latin-hypercube starting points inside the bounds.
#pragma once

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "pneumaid/ident/fit_spec.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid::refine_internal {

// The solver's coordinates theta for the free parameters. Each parameter's
// scale coordinate w (w = p for a linear scale, w = ln p for a log scale) is
// mapped onto its bounds by a logistic function,
//   w = w_lo + (w_hi - w_lo) / (1 + exp(-theta)),
// so the problem Ceres sees is unconstrained: no step is ever rejected for
// leaving the bounds, and no projected line search (which would evaluate a
// Jacobian, a sensitivity run, at every trial point) is needed. Near a lower
// bound of 0 a linear parameter moves multiplicatively, like a log scale.
struct ParameterMap {
  std::vector<FreeParameter> free;

  bool IsLog(int j) const { return free[j].scale == ParameterScale::kLog; }
  double Low(int j) const { return IsLog(j) ? std::log(free[j].lower) : free[j].lower; }
  double Span(int j) const { return (IsLog(j) ? std::log(free[j].upper) : free[j].upper) - Low(j); }
  static double Logistic(double theta) { return 1.0 / (1.0 + std::exp(-theta)); }

  double ToValue(int j, double theta) const {
    const double w = Low(j) + Span(j) * Logistic(theta);
    // exp(ln upper) can round one ulp above the bound: a set written so
    // would be refused as the next refinement's start.
    return std::clamp(IsLog(j) ? std::exp(w) : w, free[j].lower, free[j].upper);
  }
  double ToTheta(int j, double value) const {
    const double w = IsLog(j) ? std::log(value) : value;
    // A start on a bound is moved just inside (theta would be infinite).
    const double f = std::clamp((w - Low(j)) / Span(j), 1e-9, 1.0 - 1e-9);
    return std::log(f / (1.0 - f));
  }
  double ScaleCoordinate(int j, double theta) const { return Low(j) + Span(j) * Logistic(theta); }
  double ScaleDerivative(int j, double theta) const {  // dw/dtheta
    const double s = Logistic(theta);
    return Span(j) * s * (1.0 - s);
  }
  double Derivative(int j, double theta) const {  // dp/dtheta
    const double s = Logistic(theta);
    const double dw = Span(j) * s * (1.0 - s);
    return IsLog(j) ? ToValue(j, theta) * dw : dw;
  }
  // The coordinates of the free parameters' values in `params`.
  std::vector<double> ThetaOf(const Parameters& params) const {
    std::vector<double> theta;
    for (int j = 0; j < size(); ++j) {
      double value = 0;
      GetParameter(params, free[j].path, &value);
      theta.push_back(ToTheta(j, value));
    }
    return theta;
  }
  int size() const { return static_cast<int>(free.size()); }
};

// The map of spec.parameters; InputError for a parameter `start` lacks or a
// start outside its bounds.
ParameterMap MakeParameterMap(const Parameters& start, const FitSpec& spec);

// InputError naming the first of spec's parameters that `start` does not
// have (an effect's coefficient whose effect it lacks).
void CheckPathsIn(const Parameters& start, const FitSpec& spec);

// `base` with the free parameters at coordinates theta.
Parameters WithValues(const Parameters& base, const ParameterMap& map, const double* theta);

// Latin-hypercube points inside the bounds: each parameter's range (in its
// scale coordinate) cut into `count` strata, one point per stratum, strata
// shuffled per axis.
std::vector<std::vector<double>> LatinHypercube(const ParameterMap& map, int count,
                                                std::uint64_t seed);

// Latin-hypercube points in a trust box around `start`'s values, inside the
// bounds: each free parameter within (1 +- w) of its value (log scale:
// between value / (1 + w) and value (1 + w)), w the larger of `box` and 3
// standard errors (start.uncertainty) relative to the value, and 2 for a
// parameter without one (its fit did not determine it).
std::vector<std::vector<double>> TrustBox(const ParameterMap& map, const Parameters& start,
                                          int count, double box, std::uint64_t seed);

// The weak prior toward the start, or toward RefineOptions::
// start_prior_centre (RefineOptions::start_prior): per free parameter its
// centre in the scale coordinate w (p, or ln p) and a standard deviation
// there: the larger of start_prior_errors of its standard errors (the
// centre's uncertainty) and start_prior_fraction of its value, or, without a
// standard error (the component fits did not determine it), a factor 3 (log
// scale) or its own size (linear).
struct StartPrior {
  std::vector<double> w, sigma;
};
// Centred on `centre`; a free parameter it lacks (or lacks a positive value
// of, on a log scale) on `start`, as one without a standard error.
StartPrior MakeStartPrior(const ParameterMap& map, const Parameters& centre,
                          const Parameters& start, double errors, double fraction);

// (w_j(theta_j) - w_start_j) / sigma_j for every free parameter: keeps what
// the fitted runs do not determine near the start (instead of at a bound),
// negligible against runs that determine it.
class StartPriorCost final : public ceres::CostFunction {
 public:
  StartPriorCost(const ParameterMap* map, StartPrior prior);
  bool Evaluate(double const* const* theta, double* residuals, double** jacobians) const override;

 private:
  const ParameterMap* map_;
  StartPrior prior_;
};

// A free coefficient of `spec` that `p` moved from `start` loses its
// standard error in `p->uncertainty` (the component fit's no longer applies:
// the start prior treats it as undetermined).
void ForgetMoved(const Parameters& start, const FitSpec& spec, Parameters* p);

}  // namespace pneumaid::refine_internal
