#include "pneumaid/model/kvp.h"

#include <gtest/gtest.h>

namespace pneumaid {
namespace {

TEST(KvpTest, Table2JumpAtSaturationIsAsPublished) {
  const ValveParams valve;
  for (const auto* branch : {&valve.increasing, &valve.decreasing}) {
    const auto c = MakeKvpCoefficients<double>(*branch);
    const double u = branch->u_sat_V;
    const double polynomial_end = KvpPolynomial(u, c) / branch->q_max_kg_per_s;
    const double expected = ((branch->a * u + branch->b) * u + branch->c) * u * u + branch->d * u;
    EXPECT_NEAR(polynomial_end, expected, 1e-12);
    EXPECT_DOUBLE_EQ(Kvp(u, c), branch->q_max_kg_per_s);
    EXPECT_NEAR(Kvp(u - 1e-12, c) / branch->q_max_kg_per_s, expected, 1e-9);
  }
  // The values quoted in the issue: 1.0063 q_max (increasing), 0.9795 (decreasing).
  EXPECT_NEAR(KvpPolynomial(0.75, MakeKvpCoefficients<double>(valve.increasing)) / 9.25e-5, 1.0063,
              1e-4);
  EXPECT_NEAR(KvpPolynomial(0.75, MakeKvpCoefficients<double>(valve.decreasing)) / 9.15e-5, 0.9795,
              1e-4);
}

TEST(KvpTest, NeverNegativeAndZeroWhenClosed) {
  const ValveParams valve;
  const auto decreasing = MakeKvpCoefficients<double>(valve.decreasing);
  EXPECT_LT(KvpPolynomial(0.01, decreasing), 0.0);  // Table 2 dips below zero here
  for (double u = -0.1; u <= 1.0; u += 1e-4) {
    EXPECT_GE(Kvp(u, decreasing), 0.0) << u;
    EXPECT_GE(Kvp(u, MakeKvpCoefficients<double>(valve.increasing)), 0.0) << u;
  }
  EXPECT_EQ(Kvp(0.0, decreasing), 0.0);
}

TEST(KvpTest, SaturatesAboveUsat) {
  const auto c = MakeKvpCoefficients<double>(ValveParams{}.increasing);
  EXPECT_DOUBLE_EQ(Kvp(0.8, c), 9.25e-5);
  EXPECT_DOUBLE_EQ(Kvp(1.0, c), 9.25e-5);
}

}  // namespace
}  // namespace pneumaid
