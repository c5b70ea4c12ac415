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

Eigen::MatrixXd ParameterCovariance(const Eigen::MatrixXd& normal, const ParameterMap& map,
                                    const std::vector<double>& theta, double cost, long residuals,
                                    double cost_resolution) {
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
  const double inflation = std::max(1.0, 2.0 * cost / dof) + 2.0 * cost_resolution * cost;
  Eigen::VectorXd d(m);
  for (int j = 0; j < m; ++j) d[j] = map.Derivative(j, theta[j]);
  return inflation * (d.asDiagonal() * theta_cov * d.asDiagonal());
}

void Summarise(const Eigen::MatrixXd& cov, const ParameterMap& map, const RefineOptions& options,
               RefineResult* r) {
  const int m = map.size();
  if (cov.rows() != m) return;
  r->correlation = Eigen::MatrixXd::Identity(m, m);
  for (int i = 0; i < m; ++i) {
    r->parameters[i].standard_error = std::sqrt(std::max(0.0, cov(i, i)));
    r->params.uncertainty[map.free[i].path] = r->parameters[i].standard_error;
    for (int j = 0; j < i; ++j) {
      const double denominator = std::sqrt(cov(i, i) * cov(j, j));
      const double rho = denominator > 0 ? cov(i, j) / denominator : 0.0;
      r->correlation(i, j) = r->correlation(j, i) = rho;
      if (std::fabs(rho) > options.correlation_flag) {
        r->poorly_separable.emplace_back(map.free[j].path, map.free[i].path);
        r->poorly_separable_correlation.push_back(rho);
      }
    }
  }
}

}  // namespace pneumaid::refine_internal
