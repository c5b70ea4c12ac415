#include "pneumaid/model/orifice.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

namespace pneumaid {
namespace {

OrificeCoefficients<double> Paper() {
  return MakeOrificeCoefficients<double>(1.4, 287.0, 293.0, 1181.0);
}

TEST(OrificeTest, ChokedAndSubsonicBranchesMeetAtCriticalRatio) {
  const auto c = Paper();
  const double below = FlowShape(c.critical_ratio - 1e-12, c);
  const double above = FlowShape(c.critical_ratio + 1e-12, c);
  EXPECT_NEAR(below, above, 1e-9 * below);
}

TEST(OrificeTest, LinearRegionIsContinuousAndEndsAtZero) {
  const auto c = Paper();
  EXPECT_NEAR(FlowShape(c.linear_ratio - 1e-13, c), FlowShape(c.linear_ratio + 1e-13, c), 1e-10);
  EXPECT_DOUBLE_EQ(FlowShape(1.0, c), 0.0);
}

TEST(OrificeTest, ChokedFlowAtSupplyIsKvpTimesN) {
  // K_vp is the choked mass flow at supply pressure (N = C1 p_s / sqrt(T)).
  const auto c = Paper();
  const double kvp = 9.25e-5;
  const double q = OrificeMassFlow(kvp, 5e5, 1e5, c);
  const double n_exact = ComputeOrificeConstants(1.4, 287.0).C1 * 5e5 / std::sqrt(293.0);
  EXPECT_NEAR(q, kvp * n_exact / 1181.0, 1e-15);
}

TEST(OrificeTest, FlowReversesWithThePressureDifference) {
  const auto c = Paper();
  for (double p_b : {1.0e5, 3.0e5, 4.99e5, 4.999e5}) {
    const double forward = OrificeMassFlow(1e-4, 5e5, p_b, c);
    const double reverse = OrificeMassFlow(1e-4, p_b, 5e5, c);
    EXPECT_GT(forward, 0.0);
    EXPECT_DOUBLE_EQ(reverse, -forward);
  }
  EXPECT_DOUBLE_EQ(OrificeMassFlow(1e-4, 3e5, 3e5, c), 0.0);
}

TEST(OrificeTest, FlowDecreasesMonotonicallyTowardsEqualPressures) {
  const auto c = Paper();
  double previous = OrificeMassFlow(1e-4, 5e5, 0.2e5, c);
  for (double p_b = 0.2e5; p_b <= 5e5; p_b += 0.01e5) {
    const double q = OrificeMassFlow(1e-4, 5e5, p_b, c);
    EXPECT_LE(q, previous + 1e-18) << "p_b = " << p_b;
    previous = q;
  }
}

TEST(OrificeTest, AutodiffMatchesCentralDifferences) {
  using Jet = ceres::Jet<double, 3>;
  const auto cd = Paper();
  const auto cj = MakeOrificeCoefficients<Jet>(1.4, 287.0, 293.0, 1181.0);
  // Choked, subsonic, linear and reversed points.
  const double points[][3] = {
      {9e-5, 5e5, 1e5}, {9e-5, 5e5, 3.5e5}, {9e-5, 5e5, 4.99e5}, {5e-5, 2e5, 4e5}};
  for (const auto& p : points) {
    const Jet q = OrificeMassFlow(Jet(p[0], 0), Jet(p[1], 1), Jet(p[2], 2), cj);
    for (int i = 0; i < 3; ++i) {
      double plus[3] = {p[0], p[1], p[2]}, minus[3] = {p[0], p[1], p[2]};
      const double h = 1e-6 * std::fabs(p[i]);
      plus[i] += h;
      minus[i] -= h;
      const double fd = (OrificeMassFlow(plus[0], plus[1], plus[2], cd) -
                         OrificeMassFlow(minus[0], minus[1], minus[2], cd)) /
                        (2 * h);
      EXPECT_NEAR(q.v[i], fd, 1e-6 * std::fabs(fd) + 1e-20) << "input " << i;
    }
  }
}

}  // namespace
}  // namespace pneumaid
