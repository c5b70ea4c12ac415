#include "pneumaid/eval/metrics.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pneumaid {
namespace {

TEST(MetricsTest, ClosedFormFitRmseAndMax) {
  std::vector<double> y, y_sim;
  for (int i = 0; i < 1000; ++i) {
    y.push_back(std::sin(2 * M_PI * i / 1000.0));
    y_sim.push_back(0.9 * y.back());
  }
  const ChannelMetrics m = CompareChannel(y, y_sim, std::nullopt);
  // ||y - 0.9 y|| / ||y - mean|| = 0.1 (mean 0): fit 90 %.
  ASSERT_TRUE(m.nrmse_fit_percent.has_value());
  EXPECT_NEAR(*m.nrmse_fit_percent, 90.0, 1e-9);
  EXPECT_NEAR(m.rmse, 0.1 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(m.max_abs, 0.1, 1e-5);
}

TEST(MetricsTest, FitIsUndefinedBelowTheNoise) {
  const std::vector<double> flat(100, 2.0);
  EXPECT_FALSE(CompareChannel(flat, flat, std::nullopt).nrmse_fit_percent.has_value());
  std::vector<double> wiggle = flat;
  wiggle[50] += 0.5;  // ||y - mean|| ~ 0.5, below 1.0 * sqrt(100)
  EXPECT_FALSE(CompareChannel(wiggle, flat, 1.0).nrmse_fit_percent.has_value());
  EXPECT_TRUE(CompareChannel(wiggle, flat, std::nullopt).nrmse_fit_percent.has_value());
}

TEST(MetricsTest, CompareRunsTakesTheChannelsBothHave) {
  Trajectory a, b;
  a.t_s = b.t_s = {0, 1, 2};
  a.x_m = {0, 1, 2};
  b.x_m = {0, 1, 3};
  a.p1_Pa = {1, 2, 3};  // b has no p1
  const auto channels = CompareRuns(a, b, {});
  ASSERT_EQ(channels.size(), 1u);
  EXPECT_NEAR(channels.at("x").rmse, std::sqrt(1.0 / 3.0), 1e-12);
}

TEST(MetricsTest, FirstOrderLagOnNonUniformSamples) {
  const std::vector<double> t = {0.0, 0.01, 0.03, 0.07};
  const std::vector<double> step = {1.0, 1.0, 1.0, 1.0};
  std::vector<double> u = {0.0, 1.0, 1.0, 1.0};
  const auto out = FirstOrderLag(t, u, 0.02);
  EXPECT_DOUBLE_EQ(out[1], 0.0);  // the step is held from t = 0.01 on
  EXPECT_NEAR(out[2], 1 - std::exp(-0.02 / 0.02), 1e-12);
  EXPECT_NEAR(out[3], 1 - std::exp(-0.06 / 0.02), 1e-12);
  EXPECT_EQ(FirstOrderLag(t, step, 0.0), step);
}

}  // namespace
}  // namespace pneumaid
