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
#include "friction_starts.h"
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

// Widens the error of each `free` coefficient (columns of `covariance`) whose
// distance from its reading off the logs (friction_starts.h, ReadOffLogs: Fs
// from the breakaways, Fd, b and vs from the smooth slides' force balance)
// is more than the two errors together, by that chi-square's root (the
// Particle Data Group's scale factor between two readings of the same logs):
// the disagreement is a model error that the linearised covariance does not
// see (a Stribeck valley, stick the model does not have). With no error of
// its own (Fd, b, vs) a reading is a floor of the widened error; a
// coefficient the logs did not read is left as it is.
void WidenByDisagreement(const LogsReading (&reading)[2], const Block* const fitted[2],
                         const std::vector<int>& free, Eigen::MatrixXd* covariance);

// `free` and `covariance` restricted to the columns not `held`.
void KeepDetermined(const std::array<std::string, 2 * kDirectionParameters>& held,
                    std::vector<int>* free, Eigen::MatrixXd* covariance);

}  // namespace pneumaid::friction_internal
