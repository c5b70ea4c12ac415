#include "pneumaid/model/valve_bank.h"

#include <gtest/gtest.h>

#include <array>
#include <random>

namespace pneumaid {
namespace {

TEST(ValveBankTest, CommandSignSelectsTheValvePair) {
  const auto extend = OpeningsForCommand(0.4);
  EXPECT_EQ(extend[kSupplyToChamber1], 0.4);
  EXPECT_EQ(extend[kChamber2ToExhaust], 0.4);
  EXPECT_EQ(extend[kChamber1ToExhaust], 0.0);
  EXPECT_EQ(extend[kSupplyToChamber2], 0.0);
  const auto retract = OpeningsForCommand(-0.7);
  EXPECT_EQ(retract[kChamber1ToExhaust], 0.7);
  EXPECT_EQ(retract[kSupplyToChamber2], 0.7);
  EXPECT_EQ(retract[kSupplyToChamber1], 0.0);
  EXPECT_EQ(OpeningsForCommand(1.5)[kSupplyToChamber1], 1.0);
}

TEST(ValveBankTest, HysteresisFollowsAStaircaseUpAndDown) {
  BranchLatch latch(0.01);
  for (int i = 1; i <= 10; ++i) {
    latch.Update(0.1 * i);
    EXPECT_FALSE(latch.decreasing()) << "up step " << i;
  }
  for (int i = 9; i >= 0; --i) {
    latch.Update(0.1 * i);
    EXPECT_TRUE(latch.decreasing()) << "down step " << i;
  }
  latch.Update(0.05);
  EXPECT_FALSE(latch.decreasing());
}

TEST(ValveBankTest, NoisyHeldCommandDoesNotChatter) {
  std::mt19937 rng(42);
  std::normal_distribution<double> noise(0.0, 0.0015);  // 3 sigma below threshold/2
  for (bool approach_from_above : {false, true}) {
    BranchLatch latch(0.01);
    latch.Update(approach_from_above ? 0.8 : 0.2);
    latch.Update(0.5);
    const bool branch = latch.decreasing();
    EXPECT_EQ(branch, approach_from_above);
    int switches = 0;
    bool last = branch;
    for (int i = 0; i < 10000; ++i) {
      latch.Update(0.5 + noise(rng));
      switches += latch.decreasing() != last;
      last = latch.decreasing();
    }
    EXPECT_EQ(switches, 0);
  }
}

TEST(ValveBankTest, SlowRampSwitchesDespiteSubThresholdSamples) {
  BranchLatch latch(0.01);
  latch.Update(0.6);
  for (double u = 0.6; u > 0.3; u -= 0.001) latch.Update(u);  // 1 mV per sample
  EXPECT_TRUE(latch.decreasing());
}

// Why a lag needs one state per valve pair (actuator.h): the two valves a
// command opens together see the same opening and, each with its own latch,
// the same K_vp branch, whatever the command does (sign changes, noise,
// ramps, saturation).
TEST(ValveBankTest, TheTwoValvesOfAPairAlwaysAgree) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> level(-1.2, 1.2);
  std::normal_distribution<double> noise(0.0, 0.004);
  std::array<BranchLatch, kValveCount> latches{BranchLatch(0.01), BranchLatch(0.01),
                                               BranchLatch(0.01), BranchLatch(0.01)};
  double u = 0.0;
  for (int step = 0; step < 20000; ++step) {
    u = step % 500 == 0 ? level(rng) : u + noise(rng);
    const ValveOpenings opening = OpeningsForCommand(u);
    for (int i = 0; i < kValveCount; ++i) latches[i].Update(opening[i]);
    for (const ValvePair& pair : kValvePairs) {
      ASSERT_EQ(opening[pair.lead], opening[pair.partner]) << "step " << step;
      ASSERT_EQ(latches[pair.lead].decreasing(), latches[pair.partner].decreasing())
          << "step " << step;
    }
  }
  // Every valve belongs to exactly one pair.
  std::array<int, kValveCount> seen{};
  for (const ValvePair& pair : kValvePairs) {
    ++seen[pair.lead];
    ++seen[pair.partner];
  }
  for (int count : seen) EXPECT_EQ(count, 1);
}

}  // namespace
}  // namespace pneumaid
