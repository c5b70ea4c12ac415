// The friction fit (friction_fit.h), its uncertainty: the cluster-robust
// covariance of the fitted coefficients (segments and force-balance slides
// as the clusters, each arrest time eliminated inside its own segment) and
// what it leaves undetermined.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "friction_segments.h"
#include "pneumaid/ident/friction_fit.h"

namespace pneumaid::friction_internal {

// Per segment: its residuals, the Jacobian's friction columns (the free
// blocks, positive first) and its arrest-time column (empty when one-sided),
// robust loss applied.
struct SegmentJacobian {
  Eigen::VectorXd residuals;
  Eigen::MatrixXd friction;
  Eigen::VectorXd stop_time;
};

// The cluster-robust covariance of the `free` columns at `blocks`
// (`columns`: those of the fitted blocks, in the problem's order), the weak
// prior (PriorSigmas) included, so that where the logs say nothing the error
// is the prior's, not zero.
Eigen::MatrixXd RobustCovariance(const std::vector<SegmentJacobian>& jacobians,
                                 const std::vector<int>& columns, const std::vector<int>& free,
                                 const Block* const blocks[2],
                                 const std::array<double, kDirectionParameters>& sigma);

// Marks in `held` (columns 0-3 positive, 4-7 negative) each free coefficient
// the logs do not determine, with why, and the vs of a direction whose
// fitted Fs they do not determine.
void MarkUndetermined(const Eigen::MatrixXd& covariance, const std::vector<int>& free,
                      const Block* const blocks[2], const FrictionFitOptions& options,
                      std::array<std::string, 2 * kDirectionParameters>* held);

// `free` and `covariance` restricted to the columns not `held`.
void KeepDetermined(const std::array<std::string, 2 * kDirectionParameters>& held,
                    std::vector<int>* free, Eigen::MatrixXd* covariance);

}  // namespace pneumaid::friction_internal
