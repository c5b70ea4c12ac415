// The friction fit's uncertainty (src/ident/friction_covariance.h): the
// widening by the readings off the logs, in closed form.
#include "../../src/ident/friction_covariance.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>

namespace pneumaid {
namespace {

using friction_internal::Block;
using friction_internal::LogsReading;
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

}  // namespace
}  // namespace pneumaid
