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
// covariance (J'J)^-1 meat (J'J)^-1. Also, per direction, how many clusters
// inform it, and the residuals' sums for their misfit and correlation.
struct Clustered {
  Eigen::MatrixXd information, meat;
  int clusters[2] = {0, 0};        // informing the positive, the negative columns
  double lagged = 0, squared = 0;  // sum r_i r_(i+1), sum r_i^2
  long residuals = 0;              // measured rows less the arrest times
};

Clustered Information(const std::vector<SegmentJacobian>& segments,
                      const std::vector<int>& columns) {
  Clustered c;
  const Eigen::Index m = segments.front().friction.cols();
  c.information = Eigen::MatrixXd::Zero(m, m);
  c.meat = Eigen::MatrixXd::Zero(m, m);
  for (const SegmentJacobian& j : segments) {
    Eigen::MatrixXd a = j.friction;
    Eigen::VectorXd r = j.residuals;
    const double norm = j.stop_time.size() ? j.stop_time.squaredNorm() : 0.0;
    if (norm > 0) {
      a -= j.stop_time * (j.stop_time.transpose() * a) / norm;
      r -= j.stop_time * (j.stop_time.dot(r) / norm);
    }
    c.information += a.transpose() * a;
    const Eigen::VectorXd score = a.transpose() * r;
    c.meat += score * score.transpose();
    bool informs[2] = {false, false};
    for (Eigen::Index k = 0; k < m; ++k)
      informs[columns[k] / kDirectionParameters] |= a.col(k).squaredNorm() > 0;
    for (int d = 0; d < 2; ++d) c.clusters[d] += informs[d];
    const Eigen::Index n = j.residuals.size();
    c.squared += j.residuals.squaredNorm();
    if (n > 1) c.lagged += j.residuals.head(n - 1).dot(j.residuals.tail(n - 1));
    // Rows in a gap of the log weigh 0 (no measurement); an arrest time
    // eliminated inside the segment is one unknown more.
    c.residuals += (j.residuals.array() != 0.0).count() - (norm > 0 ? 1 : 0);
  }
  return c;
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
  Clustered c = Information(jacobians, columns);
  const double clusters = static_cast<double>(jacobians.size());
  c.meat *= clusters / std::max(clusters - 1.0, 1.0);
  std::vector<Eigen::Index> index;  // of each free column in `columns`
  int free_in[2] = {0, 0};          // free coefficients per direction
  for (int k : free) {
    index.push_back(std::find(columns.begin(), columns.end(), k) - columns.begin());
    ++free_in[k / kDirectionParameters];
  }
  const Eigen::Index m = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd data(m, m), prior = Eigen::MatrixXd::Zero(m, m), score(m, m);
  for (Eigen::Index a = 0; a < m; ++a) {
    for (Eigen::Index b = 0; b < m; ++b) {
      data(a, b) = c.information(index[a], index[b]);
      score(a, b) = c.meat(index[a], index[b]);
    }
    const int i = free[a] % kDirectionParameters;
    const double slope = PriorSlope(i, (*blocks[free[a] / kDirectionParameters])[i], sigma);
    prior(a, a) = slope * slope;
  }
  const Eigen::MatrixXd inverse = (data + prior).inverse();
  const Eigen::MatrixXd robust = inverse * (score + prior) * inverse;
  bool few = false;
  for (int d = 0; d < 2; ++d) few |= free_in[d] > 0 && c.clusters[d] < 2 * free_in[d];
  if (!few) return robust;
  // Too few clusters for the sandwich (one stroke level: a segment per
  // direction for four coefficients): its rank is below the coefficients'
  // count and its errors are far too small. The model's own covariance,
  // inflated by the misfit and the residuals' correlation as refinement's
  // (refine_covariance.h), each error widened to the sandwich's where that
  // is larger.
  const double chi_square = c.squared / std::max(1.0, static_cast<double>(c.residuals - m));
  const double inflation =
      std::max(1.0, chi_square) * internal::CorrelationInflation(c.lagged, c.squared);
  Eigen::MatrixXd model = inverse * (inflation * data + prior) * inverse;
  for (Eigen::Index a = 0; a < m; ++a) {
    const double widen =
        model(a, a) > 0 ? std::sqrt(std::max(1.0, robust(a, a) / model(a, a))) : 1.0;
    model.row(a) *= widen;
    model.col(a) *= widen;
  }
  return model;
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
