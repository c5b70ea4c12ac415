// Refinement's uncertainty (src/ident/refine_covariance.h): the residuals'
// lag-one autocorrelation that widens the covariance when a misfit lasts
// many samples. Closed forms on seeded synthetic residuals.
#include "../../src/ident/refine_covariance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace pneumaid::refine_internal {
namespace {

constexpr int kSamples = 20000;

// A run of `samples` samples with the x and p1 channels.
FitExperiment TwoChannelRun(int samples = kSamples) {
  FitExperiment e;
  e.measured.t_s.resize(samples);
  for (int i = 0; i < samples; ++i) e.measured.t_s[i] = 1e-3 * i;
  e.channels = {kChannelTable[0], kChannelTable[1]};
  return e;
}

// Each channel an AR(1) series r_i = rho r_(i-1) + e_i (seeded).
Eigen::VectorXd Ar1(double rho, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  Eigen::VectorXd r(2 * kSamples);
  for (int c = 0; c < 2; ++c) {
    double previous = noise(random) / std::sqrt(1 - rho * rho);
    for (int i = 0; i < kSamples; ++i) {
      previous = rho * previous + noise(random);
      r[c * kSamples + i] = previous;
    }
  }
  return r;
}

TEST(ResidualCorrelationTest, WhiteResidualsDoNotWidenTheCovariance) {
  ResidualCorrelation correlation;
  correlation.Add(TwoChannelRun(), Ar1(0.0, 1));
  EXPECT_NEAR(correlation.Inflation(), 1.0, 0.03);
}

TEST(ResidualCorrelationTest, AnAr1MisfitWidensItByOnePlusRhoOverOneMinusRho) {
  ResidualCorrelation correlation;
  correlation.Add(TwoChannelRun(), Ar1(0.9, 2));
  EXPECT_NEAR(correlation.Inflation(), 19.0, 0.1 * 19.0);
}

TEST(ResidualCorrelationTest, PoolsRunsAndNeverNarrowsIt) {
  ResidualCorrelation correlation;
  Eigen::VectorXd alternating(2 * kSamples);
  for (int i = 0; i < 2 * kSamples; ++i) alternating[i] = i % 2 ? 1.0 : -1.0;
  correlation.Add(TwoChannelRun(), alternating);
  EXPECT_DOUBLE_EQ(correlation.Inflation(), 1.0);  // rho = -1: no narrowing
  // The pooled rho weighs each run by its squared residuals: an AR(1) run
  // of ten times the innovation (variance 100 / (1 - 0.81) per sample)
  // dominates the alternating one (variance 1, lag product -1).
  correlation.Add(TwoChannelRun(), 10.0 * Ar1(0.9, 3));
  const double variance = 100.0 / (1 - 0.81);
  const double rho = (0.9 * variance - 1) / (variance + 1);
  EXPECT_NEAR(correlation.Inflation(), (1 + rho) / (1 - rho), 0.1 * (1 + rho) / (1 - rho));
}

// A run the robust loss down-weights counts with its weight: at weight 0
// an AR(1) run leaves the white one's factor.
TEST(ResidualCorrelationTest, ARunCountsWithItsWeight) {
  ResidualCorrelation correlation;
  correlation.Add(TwoChannelRun(), Ar1(0.0, 4));
  correlation.Add(TwoChannelRun(), 10.0 * Ar1(0.95, 5), 0.0);
  EXPECT_NEAR(correlation.Inflation(), 1.0, 0.03);
  correlation.Add(TwoChannelRun(), 10.0 * Ar1(0.95, 5), 1.0);
  EXPECT_GT(correlation.Inflation(), 20.0);
}

// Where the channels meet, the last sample of one and the first of the next
// are not neighbours: channels (1, 1) and (-1, -1) give rho = 2 / 4 (the
// seam's product -1 would make it 1 / 4).
TEST(ResidualCorrelationTest, ChannelsAreNotNeighbours) {
  ResidualCorrelation correlation;
  Eigen::VectorXd steps(4);
  steps << 1.0, 1.0, -1.0, -1.0;
  correlation.Add(TwoChannelRun(2), steps);
  EXPECT_DOUBLE_EQ(correlation.Inflation(), (1 + 0.5) / (1 - 0.5));
}

}  // namespace
}  // namespace pneumaid::refine_internal
