// Ceres' solver options as every fit of the identification starts from them:
// nothing logged. The library prints nothing (not even when the embedding
// program raises glog's verbosity); a fit that reports its progress does so
// through its own log sink (RefineOptions::log).
#pragma once

#include <ceres/ceres.h>

namespace pneumaid::internal {

inline ceres::Solver::Options QuietSolverOptions() {
  ceres::Solver::Options options;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  return options;
}

}  // namespace pneumaid::internal
