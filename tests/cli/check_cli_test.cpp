// `pneumaid check` end to end on the bundled datasets.
#include <gtest/gtest.h>

#include "cli_test_util.h"

namespace pneumaid {
namespace {

using CheckCliTest = testing::CliTest;

TEST_F(CheckCliTest, SummarisesEveryExperimentInDisplayUnits) {
  ASSERT_EQ(Run("check " + testing::Source("datasets/paper-rig")), 0) << Stderr();
  const std::string out = Stdout();
  EXPECT_NE(out.find("unit paper-rig"), std::string::npos) << out;
  EXPECT_NE(out.find("valve-staircase: valve, 12301 samples"), std::string::npos) << out;
  EXPECT_NE(out.find("pipe-120: pipeline"), std::string::npos) << out;
  EXPECT_NE(out.find("x [mm]"), std::string::npos) << out;
  EXPECT_NE(out.find("p1 [bar_g]"), std::string::npos) << out;
  EXPECT_NE(out.find("at 1000 Hz"), std::string::npos) << out;
}

TEST_F(CheckCliTest, CorruptUnitExitsTwoNamingFileAndLineAndTheOthersAreStillChecked) {
  const auto before = Listing(testing::Source("datasets/fleet"));
  EXPECT_EQ(Run("check " + testing::Source("datasets/fleet/PVQ13-0014") + " " +
                testing::Source("datasets/fleet/PVQ13-0001")),
            2);
  EXPECT_NE(Stderr().find("PVQ13-0014/step-1.csv:1623: ragged row"), std::string::npos) << Stderr();
  EXPECT_NE(Stdout().find("unit PVQ13-0001"), std::string::npos);
  EXPECT_EQ(Listing(testing::Source("datasets/fleet")), before);
}

TEST_F(CheckCliTest, MissingDirectoryIsBadInput) {
  EXPECT_EQ(Run("check " + (dir_ / "nowhere").string()), 2);
  EXPECT_NE(Stderr().find("not a unit directory"), std::string::npos) << Stderr();
}

}  // namespace
}  // namespace pneumaid
