// Refinement (refine.h), one stage's solve: the Ceres problem over the fitted
// runs (shared free parameters, each run's start offsets), Levenberg-Marquardt
// from every start with the stall rule, the best start kept, its costs and
// covariance.
#pragma once

#include <ceres/ceres.h>

#include <atomic>
#include <vector>

#include "pneumaid/ident/refine.h"
#include "refine_residual.h"

namespace pneumaid::refine_internal {

struct Problem {
  ceres::Problem problem;
  std::vector<double> theta;
  std::vector<StartOffsets> offsets;              // per experiment (used when it FitsStart)
  std::vector<const ExperimentResidual*> blocks;  // owned by problem
};

// Stops a start once its cost has improved by less than stall_tolerance
// (relative) over its last stall_iterations accepted steps, or after two
// rejected steps in a row once it has moved, or when `stop` (a batch unit's
// time limit, not owned, may be null) is raised: the caller then reports
// the fit not converged however it ended (StopRequested). The
// cost of an event-driven model is rough at about 1e-3 relative: each
// stick/slip switch is located to the integrator's tolerance, so the
// trajectories (and the cost) jitter at that level, far inside the
// parameters' confidence region. Levenberg-Marquardt otherwise keeps trying
// steps against that jitter until its radius collapses.
class StallCallback final : public ceres::IterationCallback {
 public:
  StallCallback(int iterations, double tolerance, const std::atomic<bool>* stop)
      : window_(iterations), tolerance_(tolerance), stop_(stop) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (stop_ != nullptr && stop_->load()) {
      // The point reached stays usable (the caller's best so far), but the
      // trial steps fail from here on: stop now, not by the rejection rule.
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    if (summary.iteration == 0) {
      accepted_.push_back(summary.cost);
      return ceres::SOLVER_CONTINUE;
    }
    if (!summary.step_is_successful) {
      // Rejected steps shrink the trust region; once the start has moved, a
      // run of them means the cost's jitter, not the model, limits progress.
      return accepted_.size() > 1 && ++rejected_in_a_row_ >= kMaxRejectedInARow
                 ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                 : ceres::SOLVER_CONTINUE;
    }
    rejected_in_a_row_ = 0;
    accepted_.push_back(summary.cost);
    const size_t n = accepted_.size();
    if (n > static_cast<size_t>(window_)) {
      const double before = accepted_[n - 1 - static_cast<size_t>(window_)];
      if (before - accepted_.back() < tolerance_ * before) {
        return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
      }
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  static constexpr int kMaxRejectedInARow = 2;
  int window_;
  double tolerance_;
  const std::atomic<bool>* stop_;
  int rejected_in_a_row_ = 0;
  std::vector<double> accepted_;  // cost after each accepted step (and at the start)
};

// The caller raised options.simulation.stop (a batch unit's time limit; it
// stays raised): no further start, stage or attempt runs.
bool StopRequested(const RefineOptions& options);

// `line` into the caller's log sink; a sink that throws loses the line (the
// fit goes on: nothing throws through Ceres).
void LogQuietly(const std::function<void(const std::string&)>& log, const std::string& line);

// One line per iteration into RefineOptions::log.
class ProgressCallback final : public ceres::IterationCallback {
 public:
  explicit ProgressCallback(const std::function<void(const std::string&)>& log) : log_(log) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override;

 private:
  const std::function<void(const std::string&)>& log_;
};

// Levenberg-Marquardt as the options and spec ask.
ceres::Solver::Options SolverOptions(const FitSpec& spec, const RefineOptions& options);

// One Levenberg-Marquardt fit of spec.parameters (all starts: the given one
// and spec.multistart Latin-hypercube points, plus `extra_starts` in the
// solver's coordinates; only those with extra_starts_only); held-out
// validation and provenance are the caller's. robust_runs: each run through
// a Cauchy loss on its whole squared residual, quadratic up to
// acceptable_reduced_chi_square times its residuals (RefineOptions::
// robust_refit), its information in the covariance weighted by the loss's
// slope; else plain least squares.
RefineResult RefineStage(const Parameters& start, const Unit& unit, const FitSpec& spec,
                         bool windows, bool last, const RefineOptions& options, bool robust_runs,
                         const std::vector<std::vector<double>>& extra_starts = {},
                         bool extra_starts_only = false);

}  // namespace pneumaid::refine_internal
