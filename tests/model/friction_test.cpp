#include "pneumaid/model/friction.h"

#include <gtest/gtest.h>

namespace pneumaid {
namespace {

const StribeckCoefficients<double> kPositive{10.0, 0.5, 5.0, 0.01};
const StribeckCoefficients<double> kNegative{8.0, 5.0, 3.0, 0.02};

TEST(FrictionTest, MagnitudeTendsToStaticForceAtRest) {
  EXPECT_NEAR(StribeckMagnitude(1e-9, kPositive), 10.0, 1e-8);
  EXPECT_NEAR(StribeckMagnitude(1e-9, kNegative), 8.0, 1e-8);
}

TEST(FrictionTest, FastSlidingFollowsCoulombPlusViscous) {
  for (double speed : {0.1, 0.5, 1.0}) {
    EXPECT_NEAR(StribeckMagnitude(speed, kPositive), 0.5 + 5.0 * speed, 1e-12);
    EXPECT_NEAR(StribeckMagnitude(speed, kNegative), 5.0 + 3.0 * speed, 1e-9);
  }
}

TEST(FrictionTest, OpposesMotionWithPerDirectionCoefficients) {
  const double stick = 1e-5;
  EXPECT_NEAR(FrictionForce(0.2, kPositive, kNegative, stick), 0.5 + 1.0, 1e-9);
  EXPECT_NEAR(FrictionForce(-0.2, kPositive, kNegative, stick), -(5.0 + 0.6), 1e-9);
  EXPECT_EQ(FrictionForce(0.0, kPositive, kNegative, stick), 0.0);
}

TEST(FrictionTest, StickBandReachesStaticForceAtItsEdge) {
  const double stick = 1e-5;
  EXPECT_NEAR(FrictionForce(stick, kPositive, kNegative, stick), 10.0, 1e-4);  // + b v
  EXPECT_NEAR(FrictionForce(-stick, kPositive, kNegative, stick), -8.0, 1e-4);
  // Inside the band the force is monotonic in v: a net force below Fs finds a
  // balance at a speed below the band edge.
  double previous = -1e9;
  for (double v = -stick; v <= stick; v += stick / 100) {
    const double f = FrictionForce(v, kPositive, kNegative, stick);
    EXPECT_GE(f, previous);
    previous = f;
  }
}

}  // namespace
}  // namespace pneumaid
