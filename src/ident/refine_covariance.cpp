#include "refine_covariance.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>

#include "determination.h"

namespace pneumaid::refine_internal {

namespace {

// The estimated start offsets' columns B of an experiment's Jacobian against
// the free parameters' A: A^T B and the factored B^T B (>= identity: the
// priors), from which each elimination below takes its Schur complement.
struct StartOffsetColumns {
  StartOffsetColumns(const EvaluationCache& at, int m) {
    const auto b = at.jacobian.rightCols(at.jacobian.cols() - m);
    cross = at.jacobian.leftCols(m).transpose() * b;
    start.compute(b.transpose() * b);
  }

  Eigen::MatrixXd cross;               // A^T B
  Eigen::LDLT<Eigen::MatrixXd> start;  // B^T B
};

}  // namespace

Eigen::MatrixXd ParameterInformation(const EvaluationCache& at, int m) {
  const auto a = at.jacobian.leftCols(m);
  Eigen::MatrixXd information = a.transpose() * a;
  if (at.jacobian.cols() == m) return information;
  const StartOffsetColumns offsets(at, m);
  information -= offsets.cross * offsets.start.solve(offsets.cross.transpose());
  return information;
}

Eigen::VectorXd ParameterScore(const EvaluationCache& at, int m) {
  const auto a = at.jacobian.leftCols(m);
  Eigen::VectorXd score = a.transpose() * at.residuals;
  if (at.jacobian.cols() == m) return score;
  const StartOffsetColumns offsets(at, m);
  const auto b = at.jacobian.rightCols(at.jacobian.cols() - m);
  score -= offsets.cross * offsets.start.solve(b.transpose() * at.residuals);
  return score;
}

std::vector<Eigen::VectorXd> BlockScores(const FitExperiment& e, const EvaluationCache& at, int m,
                                         double block_s) {
  const Eigen::Index n = static_cast<Eigen::Index>(e.measured.size());
  const Eigen::Index channels = static_cast<Eigen::Index>(e.channels.size());
  if (n < 2 || !(block_s > 0)) return {ParameterScore(at, m)};
  const double span_s = e.measured.t_s.back() - e.measured.t_s.front();
  const Eigen::Index length = std::max<Eigen::Index>(
      1, std::lround(block_s / std::max(span_s / static_cast<double>(n - 1), 1e-12)));
  const auto a = at.jacobian.leftCols(m);
  const Eigen::Index k = at.jacobian.cols() - m;
  Eigen::MatrixXd eliminate;  // A^T B (B^T B)^-1: the start offsets' share of a score
  if (k > 0) {
    const StartOffsetColumns offsets(at, m);
    eliminate = offsets.start.solve(offsets.cross.transpose()).transpose();
  }
  std::vector<Eigen::VectorXd> scores;
  for (Eigen::Index first = 0; first < n; first += length) {
    // A short last block joins the one before it.
    Eigen::Index end = std::min(n, first + length);
    if (2 * (n - end) < length) end = n;
    Eigen::VectorXd score = Eigen::VectorXd::Zero(m);
    Eigen::VectorXd start_score = Eigen::VectorXd::Zero(k);
    for (Eigen::Index c = 0; c < channels; ++c) {
      const Eigen::Index row = c * n + first, rows = end - first;
      score += a.middleRows(row, rows).transpose() * at.residuals.segment(row, rows);
      if (k > 0)
        start_score += at.jacobian.rightCols(k).middleRows(row, rows).transpose() *
                       at.residuals.segment(row, rows);
    }
    if (first == 0 && at.residuals.size() > channels * n) {
      // The start priors' rows go with the first block.
      const Eigen::Index prior = at.residuals.size() - channels * n;
      score += a.bottomRows(prior).transpose() * at.residuals.tail(prior);
      if (k > 0)
        start_score +=
            at.jacobian.rightCols(k).bottomRows(prior).transpose() * at.residuals.tail(prior);
    }
    if (k > 0) score -= eliminate * start_score;
    scores.push_back(score);
    if (end == n) break;
  }
  return scores;
}

void ResidualCorrelation::Add(const FitExperiment& e, const Eigen::VectorXd& residuals,
                              double weight) {
  const Eigen::Index n = static_cast<Eigen::Index>(e.measured.size());
  for (std::size_t c = 0; c < e.channels.size(); ++c) {
    const auto r = residuals.segment(static_cast<Eigen::Index>(c) * n, n);
    if (n < 2) continue;
    lagged += weight * r.head(n - 1).dot(r.tail(n - 1));
    squared += weight * r.squaredNorm();
  }
}

double ResidualCorrelation::Inflation() const {
  return internal::CorrelationInflation(lagged, squared);
}

Eigen::MatrixXd ParameterCovariance(const Eigen::MatrixXd& normal, const ParameterMap& map,
                                    const std::vector<double>& theta, double cost, long residuals,
                                    double correlation_inflation, double cost_resolution,
                                    const std::vector<ClusteredMeat>& clusterings) {
  const int m = map.size();
  if (normal.rows() != m) return {};
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(normal);
  if (eigen.info() != Eigen::Success) return {};
  const Eigen::VectorXd values = eigen.eigenvalues();
  Eigen::VectorXd inverse = Eigen::VectorXd::Zero(m);
  const double floor = 1e-14 * values.maxCoeff();
  for (int i = 0; i < m; ++i) inverse[i] = values[i] > floor ? 1.0 / values[i] : 0.0;
  const Eigen::MatrixXd theta_cov =
      eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose();
  const double dof = std::max(1.0, static_cast<double>(residuals - m));
  const double inflation =
      std::max(1.0, 2.0 * cost / dof) * correlation_inflation + 2.0 * cost_resolution * cost;
  Eigen::MatrixXd cov = inflation * theta_cov;
  // The sandwich holds the noise too (a correct model's scores give about
  // N^-1 s^2), so it is not added: each parameter's error is widened to the
  // largest sandwich's where that is larger, the correlations kept.
  Eigen::VectorXd widen = Eigen::VectorXd::Ones(m);
  for (const ClusteredMeat& c : clusterings) {
    if (c.clusters < 2 || c.meat.rows() != m || c.meat.cols() != m) continue;
    const double g = c.clusters;
    const Eigen::MatrixXd sandwich = theta_cov * c.meat * theta_cov * (g / (g - 1.0));
    for (int j = 0; j < m; ++j) {
      if (cov(j, j) > 0 && sandwich(j, j) > cov(j, j))
        widen[j] = std::max(widen[j], std::sqrt(sandwich(j, j) / cov(j, j)));
    }
  }
  cov = widen.asDiagonal() * cov * widen.asDiagonal();
  Eigen::VectorXd d(m);
  for (int j = 0; j < m; ++j) d[j] = map.Derivative(j, theta[j]);
  return d.asDiagonal() * cov * d.asDiagonal();
}

double StencilJitter(const std::function<double(const std::vector<double>&)>& cost,
                     const std::vector<double>& theta, double cost_at_theta,
                     const Eigen::MatrixXd& theta_cov, const Eigen::MatrixXd& normal,
                     int directions) {
  const Eigen::Index m = static_cast<Eigen::Index>(theta.size());
  if (m == 0 || theta_cov.rows() != m || normal.rows() != m || !std::isfinite(cost_at_theta))
    return 0;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(theta_cov);
  if (eigen.info() != Eigen::Success) return 0;
  const Eigen::VectorXd spread = eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  const Eigen::MatrixXd root =
      eigen.eigenvectors() * spread.asDiagonal() * eigen.eigenvectors().transpose();
  std::mt19937_64 signs(20261124);  // the standard fixes its sequence: same stencil everywhere
  double sum = 0;
  int points = 0;
  for (int d = 0; d < directions; ++d) {
    // A corner of the unit cube, scaled to one standard deviation
    // (Mahalanobis length 1).
    Eigen::VectorXd corner(m);
    for (Eigen::Index j = 0; j < m; ++j) corner[j] = (signs() & 1) ? 1.0 : -1.0;
    const Eigen::VectorXd step = root * corner / std::sqrt(static_cast<double>(m));
    const double predicted = 0.5 * step.dot(normal * step);
    // The pair's mean rise: a slope (a stall, the prior's pull) cancels.
    double rise = 0;
    for (const double sign : {1.0, -1.0}) {
      std::vector<double> at = theta;
      for (Eigen::Index j = 0; j < m; ++j) at[j] += sign * step[j];
      rise += 0.5 * (cost(at) - cost_at_theta);
    }
    if (!std::isfinite(rise)) continue;
    const double shortfall = std::max(0.0, predicted - rise);
    sum += shortfall * shortfall;
    ++points;
  }
  return points > 0 ? std::sqrt(sum / points) : 0.0;
}

void Summarise(const Eigen::MatrixXd& cov, const ParameterMap& map, const RefineOptions& options,
               RefineResult* r) {
  const int m = map.size();
  if (cov.rows() != m) {
    // No covariance: no standard errors, not the start's left on new values.
    for (const FreeParameter& p : map.free) r->params.uncertainty.erase(p.path);
    return;
  }
  r->covariance = cov;
  r->correlation_flag = options.correlation_flag;
  for (int i = 0; i < m; ++i) {
    FittedCoefficient& c = r->coefficients[i];
    // At a bound the mapped coordinate's slope vanishes, and so would the
    // error (1e-111 on a sweep unit): the runs would take the value past its
    // range, its uncertainty is one-sided. No standard error, then.
    if (c.at_bound) {
      c.standard_error = 0;
      r->params.uncertainty.erase(map.free[i].path);
      r->covariance.row(i).setZero();
      r->covariance.col(i).setZero();
      continue;
    }
    c.standard_error = std::sqrt(std::max(0.0, cov(i, i)));
    r->params.uncertainty[map.free[i].path] = c.standard_error;
  }
}

void WidenByStartDisagreement(const Parameters& start, RefineResult* r) {
  const bool with_covariance =
      r->covariance.rows() == static_cast<Eigen::Index>(r->coefficients.size());
  for (std::size_t i = 0; i < r->coefficients.size(); ++i) {
    FittedCoefficient& c = r->coefficients[i];
    if (c.at_bound || !c.determined() || !(c.standard_error > 0)) continue;
    const auto start_error = start.uncertainty.find(c.path);
    if (start_error == start.uncertainty.end()) continue;
    const double difference = c.value - c.start;
    const double se2 = c.standard_error * c.standard_error;
    const double start2 = start_error->second * start_error->second;
    const double chi2 = difference * difference / (se2 + start2);
    if (!(chi2 > 1.0)) continue;
    // An experiment of its own (the valve staircase, the tube tests, any
    // coefficient but friction): the excess of the difference over both
    // errors is a between-method variance added to the refined one
    // (DerSimonian-Laird's tau^2). The friction replay reads the same stroke
    // logs: the refined error grows to the distance, |d| / se > sqrt(chi2).
    const bool independent = c.path.rfind("friction.", 0) != 0;
    const double scale =
        independent ? std::sqrt(1.0 + std::max(0.0, difference * difference - se2 - start2) / se2)
                    : std::fabs(difference) / c.standard_error;
    c.standard_error *= scale;
    r->params.uncertainty[c.path] = c.standard_error;
    if (with_covariance) {
      const auto k = static_cast<Eigen::Index>(i);
      r->covariance.row(k) *= scale;
      r->covariance.col(k) *= scale;
    }
  }
}

}  // namespace pneumaid::refine_internal
