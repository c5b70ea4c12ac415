#include "refine_covariance.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace pneumaid::refine_internal {

Eigen::MatrixXd ParameterInformation(const EvaluationCache& at, int m) {
  const auto a = at.jacobian.leftCols(m);
  Eigen::MatrixXd information = a.transpose() * a;
  if (at.jacobian.cols() == m) return information;
  const auto b = at.jacobian.rightCols(at.jacobian.cols() - m);
  const Eigen::MatrixXd cross = a.transpose() * b;
  const Eigen::MatrixXd start = b.transpose() * b;  // >= identity: the priors
  information -= cross * start.ldlt().solve(cross.transpose());
  return information;
}

Eigen::VectorXd ParameterScore(const EvaluationCache& at, int m) {
  const auto a = at.jacobian.leftCols(m);
  Eigen::VectorXd score = a.transpose() * at.residuals;
  if (at.jacobian.cols() == m) return score;
  const auto b = at.jacobian.rightCols(at.jacobian.cols() - m);
  const Eigen::MatrixXd cross = a.transpose() * b;
  const Eigen::MatrixXd start = b.transpose() * b;
  score -= cross * start.ldlt().solve(b.transpose() * at.residuals);
  return score;
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
  const double rho = squared > 0 ? std::min(lagged / squared, 0.999) : 0.0;
  return rho > 0 ? (1 + rho) / (1 - rho) : 1.0;
}

Eigen::MatrixXd ParameterCovariance(const Eigen::MatrixXd& normal, const ParameterMap& map,
                                    const std::vector<double>& theta, double cost, long residuals,
                                    double correlation_inflation, double cost_resolution,
                                    const Eigen::MatrixXd& run_meat, int runs) {
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
  if (runs >= 2 && run_meat.rows() == m && run_meat.cols() == m) {
    // The sandwich holds the noise too (a correct model's scores give about
    // N^-1 s^2), so it is not added: each parameter's error is widened to the
    // sandwich's where that is larger, the correlations kept.
    const Eigen::MatrixXd sandwich = theta_cov * run_meat * theta_cov * (runs / (runs - 1.0));
    Eigen::VectorXd widen = Eigen::VectorXd::Ones(m);
    for (int j = 0; j < m; ++j) {
      if (cov(j, j) > 0 && sandwich(j, j) > cov(j, j))
        widen[j] = std::sqrt(sandwich(j, j) / cov(j, j));
    }
    cov = widen.asDiagonal() * cov * widen.asDiagonal();
  }
  Eigen::VectorXd d(m);
  for (int j = 0; j < m; ++j) d[j] = map.Derivative(j, theta[j]);
  return d.asDiagonal() * cov * d.asDiagonal();
}

void Summarise(const Eigen::MatrixXd& cov, const ParameterMap& map, const RefineOptions& options,
               RefineResult* r) {
  const int m = map.size();
  if (cov.rows() != m) return;
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
    // logs: the scale factor only.
    const bool independent = c.path.rfind("friction.", 0) != 0;
    const double scale =
        independent ? std::sqrt(1.0 + std::max(0.0, difference * difference - se2 - start2) / se2)
                    : std::sqrt(chi2);
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
