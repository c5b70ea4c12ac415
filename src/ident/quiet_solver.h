// Ceres' solver options as every fit of the identification starts from them
// (and how each counts its iterations):
// nothing logged. The library prints nothing (not even when the embedding
// program raises glog's verbosity); a fit that reports its progress does so
// through its own log sink (RefineOptions::log). One message escapes this:
// Ceres 2.1 logs an ERROR through glog when a Jacobian evaluation fails after
// an accepted step, whatever logging_type says; the fit reports that failure
// in its own result, and the pneumaid programs set glog's minloglevel to
// fatal (the library does not touch the embedding program's glog).
#pragma once

#include <ceres/ceres.h>

namespace pneumaid::internal {

inline ceres::Solver::Options QuietSolverOptions() {
  ceres::Solver::Options options;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  return options;
}

// The steps a solve tried (accepted or not): Summary::iterations also lists
// iteration 0, the evaluation at the start.
inline int StepsTried(const ceres::Solver::Summary& summary) {
  return summary.num_successful_steps + summary.num_unsuccessful_steps;
}

}  // namespace pneumaid::internal
