// The friction fit's uncertainty (src/ident/friction_covariance.h): the
// covariance with few and with many clusters and the widening by the
// readings off the logs, in closed form.
#include "../../src/ident/friction_covariance.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace pneumaid {
namespace {

using friction_internal::Block;
using friction_internal::LogsReading;
using friction_internal::RobustCovariance;
using friction_internal::SegmentJacobian;
using friction_internal::WidenByDisagreement;

// Fitted positive Fs 10 +- 0.1 N, positive vs 10 +- 1 mm/s and negative Fs
// 5 +- 0.1 N, the first two correlated 0.5.
struct Case {
  Block positive = {10.0, 1.0, 5.0, 0.01}, negative = {5.0, 1.0, 5.0, 0.01};
  const Block* fitted[2] = {&positive, &negative};
  std::vector<int> free = {0, 3, 4};  // positive Fs, positive vs, negative Fs
  Eigen::MatrixXd covariance{
      {0.01, 0.5 * 0.1 * 1e-3, 0.0}, {0.5 * 0.1 * 1e-3, 1e-6, 0.0}, {0.0, 0.0, 0.01}};
  LogsReading reading[2];
};

// Each error grows by sqrt(d^2 / (se^2 + se_read^2)) where that exceeds 1,
// with its covariances; a reading that agrees leaves it.
TEST(FrictionCovarianceTest, AnErrorGrowsByTheDisagreementsChiSquareRoot) {
  Case c;
  c.reading[0].value = {11.0, 1.0, 5.0, 0.01};  // Fs 1 N off, vs the same
  c.reading[0].read = {true, true, true, true};
  c.reading[0].error = {std::sqrt(0.03), 0, 0, 0};  // chi2 = 1 / (0.01 + 0.03) = 25
  c.reading[1].value = {5.05, 1.0, 5.0, 0.01};      // within the errors
  c.reading[1].read = {true, true, true, true};
  const Eigen::MatrixXd before = c.covariance;
  WidenByDisagreement(c.reading, c.fitted, c.free, &c.covariance);
  EXPECT_NEAR(c.covariance(0, 0), 25 * before(0, 0), 1e-12);
  EXPECT_NEAR(c.covariance(0, 1), 5 * before(0, 1), 1e-15);
  EXPECT_NEAR(c.covariance(1, 0), 5 * before(1, 0), 1e-15);
  EXPECT_DOUBLE_EQ(c.covariance(1, 1), before(1, 1));
  EXPECT_DOUBLE_EQ(c.covariance(2, 2), before(2, 2));  // 0.05 N for an error of 0.1
}

// A coefficient the logs did not read is left as it is however far its
// fallback value lies; one they did read is widened whatever its value,
// also where the reading happens to equal the prior.
TEST(FrictionCovarianceTest, OnlyWhatTheLogsReadWidensAnError) {
  Case c;
  c.reading[0].value = {20.0, 1.0, 5.0, 0.01};  // not read: the prior's 20 N
  c.reading[1].value = {10.0, 1.0, 5.0, 0.01};  // read: 5 N off, no error of its own
  c.reading[1].read = {true, false, false, false};
  const Eigen::MatrixXd before = c.covariance;
  WidenByDisagreement(c.reading, c.fitted, c.free, &c.covariance);
  EXPECT_DOUBLE_EQ(c.covariance(0, 0), before(0, 0));
  EXPECT_DOUBLE_EQ(c.covariance(1, 1), before(1, 1));
  EXPECT_NEAR(std::sqrt(c.covariance(2, 2)), 5.0, 1e-12);  // no error of its own: the distance
}

// `clusters` segments of 400 rows informing the positive Fs and Fd, their
// residuals white with a spread of 2 (a reduced chi-square of 4).
std::vector<SegmentJacobian> Segments(int clusters) {
  std::mt19937 random(7);
  std::normal_distribution<double> normal;
  std::vector<SegmentJacobian> segments(clusters);
  for (SegmentJacobian& s : segments) {
    s.friction = Eigen::MatrixXd(400, 2);
    s.residuals = Eigen::VectorXd(400);
    for (int i = 0; i < 400; ++i) {
      s.friction(i, 0) = 1.0 + 0.01 * i;
      s.friction(i, 1) = 2.0 - 0.003 * i + 0.1 * normal(random);
      s.residuals(i) = 2.0 * normal(random);
    }
  }
  return segments;
}

// Gauss-Newton's (J'J + P)^-1 (J'J s^2 c + P) (J'J + P)^-1, s^2 the reduced
// chi-square and c the residuals' correlation inflation (1 + rho)/(1 - rho).
Eigen::MatrixXd ModelCovariance(const std::vector<SegmentJacobian>& segments,
                                const std::array<double, 4>& sigma) {
  Eigen::MatrixXd data = Eigen::MatrixXd::Zero(2, 2);
  double squared = 0, lagged = 0;
  long n = 0;
  for (const SegmentJacobian& s : segments) {
    data += s.friction.transpose() * s.friction;
    squared += s.residuals.squaredNorm();
    lagged += s.residuals.head(399).dot(s.residuals.tail(399));
    n += 400;
  }
  const double rho = lagged / squared, chi2 = squared / (n - 2);
  const double inflation = std::max(1.0, chi2) * (rho > 0 ? (1 + rho) / (1 - rho) : 1.0);
  Eigen::MatrixXd prior = Eigen::MatrixXd::Zero(2, 2);
  prior(0, 0) = 1 / (sigma[0] * sigma[0]);
  prior(1, 1) = 1 / (sigma[1] * sigma[1]);
  const Eigen::MatrixXd inverse = (data + prior).inverse();
  return inverse * (inflation * data + prior) * inverse;
}

// The cluster-robust sandwich (J'J + P)^-1 (G/(G-1) sum_k s_k s_k' + P)
// (J'J + P)^-1, s_k = J_k' r_k the segments' scores.
Eigen::MatrixXd Sandwich(const std::vector<SegmentJacobian>& segments,
                         const std::array<double, 4>& sigma) {
  Eigen::MatrixXd data = Eigen::MatrixXd::Zero(2, 2), meat = Eigen::MatrixXd::Zero(2, 2);
  for (const SegmentJacobian& s : segments) {
    data += s.friction.transpose() * s.friction;
    const Eigen::VectorXd score = s.friction.transpose() * s.residuals;
    meat += score * score.transpose();
  }
  const double g = static_cast<double>(segments.size());
  meat *= g / std::max(g - 1, 1.0);
  Eigen::MatrixXd prior = Eigen::MatrixXd::Zero(2, 2);
  prior(0, 0) = 1 / (sigma[0] * sigma[0]);
  prior(1, 1) = 1 / (sigma[1] * sigma[1]);
  const Eigen::MatrixXd inverse = (data + prior).inverse();
  return inverse * (meat + prior) * inverse;
}

// One segment for two coefficients: the sandwich has rank one, so the
// errors are Gauss-Newton's inflated by the misfit, with its correlation,
// each widened to the sandwich's where that is larger; with 40 segments they
// are the sandwich's.
TEST(FrictionCovarianceTest, TooFewClustersForTheSandwichGiveTheModelsInflatedErrors) {
  const Block positive = {10.0, 1.0, 5.0, 0.01}, negative = positive;
  const Block* blocks[2] = {&positive, &negative};
  const std::array<double, 4> sigma = {100.0, 100.0, 100.0, 10.0};
  const std::vector<int> columns = {0, 1}, free = {0, 1};
  const std::vector<SegmentJacobian> one = Segments(1);
  const Eigen::MatrixXd few = RobustCovariance(one, columns, free, blocks, sigma);
  const Eigen::MatrixXd model = ModelCovariance(one, sigma), rank_one = Sandwich(one, sigma);
  for (int a = 0; a < 2; ++a) {
    const double expected = std::max(model(a, a), rank_one(a, a));
    EXPECT_NEAR(few(a, a), expected, 1e-9 * expected) << a;
  }
  // The model's wider on one coefficient at least (here by 1.19 in variance):
  // the rank-one sandwich alone is not the answer.
  EXPECT_GT(std::max(model(0, 0) / rank_one(0, 0), model(1, 1) / rank_one(1, 1)), 1.1);
  const auto correlation = [](const Eigen::MatrixXd& c) {
    return c(0, 1) / std::sqrt(c(0, 0) * c(1, 1));
  };
  EXPECT_NEAR(correlation(few), correlation(model), 1e-9);

  const std::vector<SegmentJacobian> forty = Segments(40);
  const Eigen::MatrixXd many = RobustCovariance(forty, columns, free, blocks, sigma);
  const Eigen::MatrixXd sandwich = Sandwich(forty, sigma);
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      EXPECT_NEAR(many(a, b), sandwich(a, b), 1e-9 * std::sqrt(sandwich(a, a) * sandwich(b, b)));
}

}  // namespace
}  // namespace pneumaid
