#include "pneumaid/model/gas.h"

#include <gtest/gtest.h>

namespace pneumaid {
namespace {

TEST(GasTest, Eq2ConstantsMatchThePaperForAir) {
  const OrificeConstants c = ComputeOrificeConstants(1.4, 287.0);
  EXPECT_NEAR(c.C1, 0.0404, 5e-5);
  EXPECT_NEAR(c.C2, 0.1562, 5e-5);
  EXPECT_NEAR(c.critical_ratio, 0.528, 5e-4);
}

TEST(GasTest, NormalizationIsChokedFlowConstantAtSupply) {
  // N = C1 p_supply / sqrt(T) = 1181 in the paper (to its rounding).
  const OrificeConstants c = ComputeOrificeConstants(1.4, 287.0);
  EXPECT_NEAR(c.C1 * 5e5 / std::sqrt(293.0), 1181.0, 1.5);
}

TEST(GasTest, ConstantsFollowTheHeatCapacityRatio) {
  // A monatomic gas (k = 5/3) chokes at (3/4)^(5/2) = 0.487.
  const OrificeConstants c = ComputeOrificeConstants(5.0 / 3.0, 2077.0);
  EXPECT_NEAR(c.critical_ratio, std::pow(0.75, 2.5), 1e-12);
}

}  // namespace
}  // namespace pneumaid
