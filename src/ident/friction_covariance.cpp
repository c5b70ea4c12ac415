#include "friction_covariance.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "determination.h"
#include "friction_cost.h"

namespace pneumaid::friction_internal {
namespace {

// The information J'J of the friction columns and the sum of the clusters'
// score outer products (J_k' r_k)(J_k' r_k)', segments and force-balance
// slides being the clusters and each arrest time eliminated inside its own
// segment (the Schur complement): the bread and meat of the cluster-robust
// covariance (J'J)^-1 meat (J'J)^-1.
void Information(const std::vector<SegmentJacobian>& segments, Eigen::MatrixXd* information,
                 Eigen::MatrixXd* meat) {
  const Eigen::Index m = segments.front().friction.cols();
  *information = Eigen::MatrixXd::Zero(m, m);
  *meat = Eigen::MatrixXd::Zero(m, m);
  for (const SegmentJacobian& j : segments) {
    Eigen::MatrixXd a = j.friction;
    Eigen::VectorXd r = j.residuals;
    const double norm = j.stop_time.size() ? j.stop_time.squaredNorm() : 0.0;
    if (norm > 0) {
      a -= j.stop_time * (j.stop_time.transpose() * a) / norm;
      r -= j.stop_time * (j.stop_time.dot(r) / norm);
    }
    *information += a.transpose() * a;
    const Eigen::VectorXd score = a.transpose() * r;
    *meat += score * score.transpose();
  }
}

}  // namespace

// The cluster-robust covariance of the `free` columns at `blocks`
// (`columns`: those of the fitted blocks, in Evaluate's order): the data's
// information plus the prior's in the bread, the clusters' scores and the
// prior (one more independent observation of each coefficient) in the meat,
// so that where the logs say nothing the error is the prior's, not zero.
Eigen::MatrixXd RobustCovariance(const std::vector<SegmentJacobian>& jacobians,
                                 const std::vector<int>& columns, const std::vector<int>& free,
                                 const Block* const blocks[2],
                                 const std::array<double, kDirectionParameters>& sigma) {
  Eigen::MatrixXd information, meat;
  Information(jacobians, &information, &meat);
  const double clusters = static_cast<double>(jacobians.size());
  meat *= clusters / std::max(clusters - 1.0, 1.0);
  std::vector<Eigen::Index> index;  // of each free column in `columns`
  for (int c : free)
    index.push_back(std::find(columns.begin(), columns.end(), c) - columns.begin());
  const Eigen::Index m = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd bread(m, m), score(m, m);
  for (Eigen::Index a = 0; a < m; ++a) {
    for (Eigen::Index b = 0; b < m; ++b) {
      bread(a, b) = information(index[a], index[b]);
      score(a, b) = meat(index[a], index[b]);
    }
    const int i = free[a] % kDirectionParameters;
    const double slope = PriorSlope(i, (*blocks[free[a] / kDirectionParameters])[i], sigma);
    bread(a, a) += slope * slope;
    score(a, a) += slope * slope;
  }
  const Eigen::MatrixXd inverse = bread.inverse();
  return inverse * score * inverse;
}

// Marks in `held` each free coefficient the logs do not determine
// (determination.h); vs means something only through the Stribeck drop
// Fs - Fd, so it goes with an undetermined Fs.
void MarkUndetermined(const Eigen::MatrixXd& covariance, const std::vector<int>& free,
                      const Block* const blocks[2], const FrictionFitOptions& options,
                      std::array<std::string, 2 * kDirectionParameters>* held) {
  const char* what = options.held_at_prior ? "held at the prior" : "regularised toward the prior";
  for (Eigen::Index a = 0; a < static_cast<Eigen::Index>(free.size()); ++a) {
    const int c = free[a], i = c % kDirectionParameters;
    const double value = (*blocks[c / kDirectionParameters])[i];
    const double error = std::sqrt(std::max(covariance(a, a), 0.0));
    if (internal::IsDetermined(value, error, kDeterminedFloor[i],
                               options.identifiable_relative_error)) {
      continue;
    }
    char why[200];
    std::snprintf(why, sizeof(why), "not determined by these logs (%.4g +- %.2g); %s", value, error,
                  what);
    (*held)[c] = why;
  }
  for (int d = 0; d < 2; ++d) {
    const int fs = d * kDirectionParameters, vs = fs + 3;
    const bool fs_fitted = std::find(free.begin(), free.end(), fs) != free.end();
    if (fs_fitted && !(*held)[fs].empty() && (*held)[vs].empty()) {
      (*held)[vs] =
          std::string("not determined by these logs: Fs, which sets the Stribeck drop, is not; ") +
          what;
    }
  }
}

void WidenByDisagreement(const LogsReading (&reading)[2], const Block* const fitted[2],
                         const std::vector<int>& free, Eigen::MatrixXd* covariance) {
  for (Eigen::Index a = 0; a < static_cast<Eigen::Index>(free.size()); ++a) {
    const int d = free[a] / kDirectionParameters, i = free[a] % kDirectionParameters;
    if (!reading[d].read[i]) continue;
    const double error2 = std::max((*covariance)(a, a), 0.0);
    if (!(error2 > 0)) continue;
    const double distance = (*fitted[d])[i] - reading[d].value[i];
    const double read_error = reading[d].error[i];
    const double chi2 = distance * distance / (error2 + read_error * read_error);
    if (!(chi2 > 1)) continue;
    const double scale = std::sqrt(chi2);
    covariance->row(a) *= scale;
    covariance->col(a) *= scale;
  }
}

// `free` and `covariance` restricted to the columns not `held`.
void KeepDetermined(const std::array<std::string, 2 * kDirectionParameters>& held,
                    std::vector<int>* free, Eigen::MatrixXd* covariance) {
  std::vector<Eigen::Index> at;  // each kept column's row in `covariance`
  std::vector<int> still;
  for (std::size_t a = 0; a < free->size(); ++a) {
    if (held[(*free)[a]].empty()) {
      still.push_back((*free)[a]);
      at.push_back(static_cast<Eigen::Index>(a));
    }
  }
  Eigen::MatrixXd kept(still.size(), still.size());
  for (std::size_t a = 0; a < still.size(); ++a)
    for (std::size_t b = 0; b < still.size(); ++b) kept(a, b) = (*covariance)(at[a], at[b]);
  *free = std::move(still);
  *covariance = std::move(kept);
}

}  // namespace pneumaid::friction_internal
