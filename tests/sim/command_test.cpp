#include "pneumaid/sim/command.h"

#include <gtest/gtest.h>

namespace pneumaid {
namespace {

TEST(CommandTest, StepsHoldFromTheirTimeOn) {
  const CommandSignal c = StepCommand({{0.5, -1.0}, {0.0, 1.0}});
  EXPECT_EQ(c.ValueAt(-1.0), 0.0);
  EXPECT_EQ(c.ValueAt(0.0), 1.0);
  EXPECT_EQ(c.ValueAt(0.49), 1.0);
  EXPECT_EQ(c.ValueAt(0.5), -1.0);
  EXPECT_TRUE(c.IsValid(nullptr));
}

TEST(CommandTest, SampledCommandHoldsItsFirstValueBefore) {
  const CommandSignal c = SampledCommand({1.0, 2.0}, {0.3, 0.4});
  EXPECT_EQ(c.ValueAt(0.0), 0.3);
  EXPECT_EQ(c.ValueAt(1.5), 0.3);
  EXPECT_EQ(c.ValueAt(2.5), 0.4);
}

TEST(CommandTest, SampledCommandKeepsOnlyChanges) {
  const CommandSignal c = SampledCommand({0.0, 0.1, 0.2, 0.3}, {0.5, 0.5, 1.0, 1.0});
  EXPECT_EQ(c.time_s, std::vector<double>{0.2});
  EXPECT_EQ(c.ValueAt(0.15), 0.5);
  EXPECT_EQ(c.ValueAt(0.25), 1.0);
}

TEST(CommandTest, RejectsNonIncreasingKnots) {
  std::string error;
  EXPECT_FALSE((CommandSignal{0.0, {1.0, 1.0}, {0.3, 0.4}}.IsValid(&error)));
  EXPECT_NE(error.find("strictly increasing"), std::string::npos);
}

}  // namespace
}  // namespace pneumaid
