// `pneumaid check` end to end on the bundled datasets.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_test_util.h"

namespace pneumaid {
namespace {

class CheckCliTest : public testing::CliTest {
 protected:
  // The bundled paper unit copied into the test's directory, its manifest
  // with `from` replaced by `to`.
  std::filesystem::path PaperRigWith(const std::string& from, const std::string& to) {
    const std::filesystem::path unit = dir_ / "paper-rig";
    std::filesystem::copy(testing::Source("datasets/paper-rig"), unit);
    std::string manifest = Read(unit / "unit.yaml");
    const std::size_t at = manifest.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) manifest.replace(at, from.size(), to);
    std::ofstream(unit / "unit.yaml", std::ios::binary) << manifest;
    return unit;
  }
};

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
  const std::filesystem::path unit = PaperRigWith("p1: {sigma: 300}", "p1: {sigma: 100}");
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

// What the format allows but a rig engineer should hear of before a fit: a
// supply written as gauge on a rig whose valve log shows it absolute, a log
// cut mid-row with no line end, and rows lost for a while. The paper unit
// itself says none of it.
TEST_F(CheckCliTest, NamesASupplyTheLogsContradictACutLogAndSamplingGaps) {
  ASSERT_EQ(Run("check " + testing::Source("datasets/paper-rig")), 0) << Stderr();
  EXPECT_EQ(Stdout().find("note:"), std::string::npos) << Stdout();
  const std::filesystem::path unit =
      PaperRigWith("supply_pressure: \"5 bar\"", "supply_pressure: \"5 bar_g\"");
  // stroke-030: its last row's last number cut short with no line end, and 30
  // rows lost after its 1000th.
  std::string log = Read(unit / "stroke-030.csv");
  log.erase(log.size() - 3);
  std::size_t row = 0;
  for (int i = 0; i < 1000; ++i) row = log.find('\n', row) + 1;
  std::size_t end = row;
  for (int i = 0; i < 30; ++i) end = log.find('\n', end) + 1;
  log.erase(row, end - row);
  std::ofstream(unit / "stroke-030.csv", std::ios::binary) << log;

  ASSERT_EQ(Run("check " + unit.string()), 0) << Stderr();
  const std::string out = Stdout();
  EXPECT_NE(out.find("note: valve log 'valve-staircase': p_up's median"), std::string::npos) << out;
  EXPECT_NE(out.find("below the rig's supply_pressure 6 bar abs"), std::string::npos) << out;
  const std::size_t stroke = out.find("stroke-030: stroke");
  ASSERT_NE(stroke, std::string::npos) << out;
  const std::string after = out.substr(stroke, out.find("stroke-045") - stroke);
  EXPECT_NE(after.find("note: 1 gap in the sampling"), std::string::npos) << after;
  EXPECT_NE(after.find("about 30 samples missing"), std::string::npos) << after;
  EXPECT_NE(after.find("note: the last row has no line end"), std::string::npos) << after;
}

// The profile's rows before 1.0 s dropped (a logger that started late, the
// rod sliding under a held command): check notes that it starts unsettled;
// the bundled logs, which start at rest, get no such note.
TEST_F(CheckCliTest, NotesALogThatStartsUnsettled) {
  const std::filesystem::path unit = PaperRigWith("unit: ", "unit: ");
  std::string log = Read(unit / "profile-1.csv");
  std::size_t header = 0;  // the comment and the header row stay
  for (int i = 0; i < 2; ++i) header = log.find('\n', header) + 1;
  std::size_t row = header;
  for (int i = 0; i < 1000; ++i) row = log.find('\n', row) + 1;  // 1 kHz: 1.0 s
  log.erase(header, row - header);
  std::ofstream(unit / "profile-1.csv", std::ios::binary) << log;
  ASSERT_EQ(Run("check " + unit.string()), 0) << Stderr();
  const std::string out = Stdout();
  const std::size_t profile = out.find("profile-1: validation");
  ASSERT_NE(profile, std::string::npos) << out;
  EXPECT_NE(out.find("note: the log starts unsettled", profile), std::string::npos) << out;
  EXPECT_EQ(out.substr(0, profile).find("starts unsettled"), std::string::npos) << out;
}

TEST_F(CheckCliTest, MissingDirectoryIsBadInput) {
  EXPECT_EQ(Run("check " + (dir_ / "nowhere").string()), 2);
  EXPECT_NE(Stderr().find("not a unit directory"), std::string::npos) << Stderr();
}

}  // namespace
}  // namespace pneumaid
