// The one shape of every fit's outcome: the valve branches, each tube, the
// pipeline, friction and refinement all return a FitResult (with their own
// diagnostics beside it). A consumer (identify, batch, reports) reads the
// coefficients by params-v1 path, their standard errors and covariance, which
// of them the data did not determine and why, and one status with its reason.
#pragma once

#include <Eigen/Core>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "pneumaid/model/parameters.h"

namespace pneumaid {

enum class FitStatus {
  kConverged,     // the solver stopped and, where the fit judges its misfit, the verdict holds
  kNotExplained,  // the best point found leaves more misfit than the noise and the acceptable
                  // model error explain (refinement's and the tube fit's verdicts); its values
                  // are still written
  kNotConverged,  // the solver ran out of iterations; its values are its best point
  kNotFitted,     // nothing fitted: every coefficient keeps its start (reason says why)
};

// "converged", "the model does not explain these logs", "NOT converged", "not fitted".
const char* ToString(FitStatus status);

struct FittedCoefficient {
  std::string path;           // params-v1 dotted path, e.g. "friction.positive.Fs"
  double start = 0;           // where the fit started (the prior, or a start read off the data)
  double value = 0;           // what the fit gives; for a held coefficient what it was held at
  double standard_error = 0;  // with model error where the fit estimates it; for a held
                              // coefficient 0 (component fits) or the error with the
                              // prior it was held by (refinement)
  std::string held;           // empty: determined by the data; otherwise why it is not
  bool at_bound = false;      // the value sits on one of the fit's bounds (refinement: then
                              // no standard error, its uncertainty is one-sided)

  bool determined() const { return held.empty(); }
};

// The one rule for FittedCoefficient::at_bound: `value` lies within 1e-6 of
// the span of [lower, upper] from either end (a solver stops on a bound up to
// its rounding, or on the bound of a mapped coordinate up to the map's).
bool AtBound(double value, double lower, double upper);

struct FitResult {
  FitStatus status = FitStatus::kNotFitted;
  std::string reason;  // why not converged / not fitted; otherwise warnings, or empty
  std::vector<FittedCoefficient> coefficients;
  // Of `coefficients`, in their order (rows and columns of held ones zero);
  // empty when the fit gives none.
  Eigen::MatrixXd covariance;
  double initial_cost = 0, final_cost = 0;  // 0.5 sum of squared weighted residuals
  int iterations = 0;

  // There are values to write (every status but kNotFitted).
  bool has_values() const { return status != FitStatus::kNotFitted; }
  // The coefficients not determined (path -> why): every one of a fit with
  // no values (why: its own word, else the fit's reason, else its status);
  // none of a fit that did not run (it has no coefficients).
  std::map<std::string, std::string> Held() const;
  // nullptr when no coefficient has this path.
  const FittedCoefficient* Find(const std::string& path) const;
  // The correlation of coefficients i and j; NaN where the covariance is not available.
  double Correlation(std::size_t i, std::size_t j) const;
  // Pairs of determined coefficients whose |correlation| exceeds `threshold`.
  std::vector<std::pair<std::size_t, std::size_t>> Correlated(double threshold) const;
  // Writes every coefficient's value into `params` (when has_values()).
  void ApplyTo(Parameters* params) const;
  // One line per coefficient (value +- error, or held and why) and the
  // poorly separable pairs, each line indented by `indent`.
  std::string CoefficientReport(const std::string& indent = "  ",
                                double correlation_flag = 0.95) const;
};

// Appends `part`'s coefficients (block-diagonal covariance), costs and
// iterations to `whole`, and combines the statuses: not fitted only when every
// part is; otherwise the worst status of the parts that fitted. Reasons are
// joined with `name` in front.
void AppendFit(const FitResult& part, const std::string& name, FitResult* whole);

// A fit gave a result that cannot be used (a non-physical identified set, a
// solver failure with nothing to write): the data or the model, not the
// user's input, are at fault. The CLI maps it to exit status 3.
class FitError : public std::runtime_error {
 public:
  FitError(std::string object, std::string message);
  const std::string& object() const { return object_; }  // what failed: "identified set of unit X"
  const std::string& message() const { return message_; }

 private:
  std::string object_;
  std::string message_;
};

}  // namespace pneumaid
