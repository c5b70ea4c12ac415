// `pneumaid check` end to end on the bundled datasets.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

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

// A sensor whose declared noise its logs contradict (p1 declared at 100 Pa
// for the 300 it carries) is named before any fit weighs by it; a unit whose
// declarations hold says nothing of its noise.
TEST_F(CheckCliTest, NamesADeclaredNoiseTheLogsContradict) {
  ASSERT_EQ(Run("check " + testing::Source("datasets/paper-rig")), 0) << Stderr();
  EXPECT_EQ(Stdout().find("noise"), std::string::npos) << Stdout();
  const std::filesystem::path unit = dir_ / "paper-rig";
  std::filesystem::copy(testing::Source("datasets/paper-rig"), unit);
  std::string manifest = Read(unit / "unit.yaml");
  const std::size_t at = manifest.find("p1: {sigma: 300}");
  ASSERT_NE(at, std::string::npos);
  manifest.replace(at, 16, "p1: {sigma: 100}");
  std::ofstream(unit / "unit.yaml", std::ios::binary) << manifest;
  ASSERT_EQ(Run("check " + unit.string()), 0) << Stderr();
  EXPECT_NE(Stdout().find("declared noise below what the logs show: p1 100 Pa declared, "
                          "the logs' quietest stretches 2"),
            std::string::npos)
      << Stdout();
  EXPECT_EQ(Stdout().find("p2 300 Pa declared"), std::string::npos) << Stdout();
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
