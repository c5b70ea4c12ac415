// `pneumaid validate` end to end: exit codes 0, 4 and 2, files written or not.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "cli_test_util.h"
#include "pneumaid/io/files.h"

namespace pneumaid {
namespace {

using ValidateCliTest = testing::CliTest;

TEST_F(ValidateCliTest, PassesOnTheTruthAndWritesReports) {
  const std::string json = (dir_ / "report.json").string();
  const std::string csv_dir = (dir_ / "csv").string() + "/";  // a new directory, named with '/'
  ASSERT_EQ(
      Run("validate --params " + testing::Source("datasets/paper-rig/truth.yaml") + " " +
          testing::Source("datasets/paper-rig") + " --json " + json + " --csv-out " + csv_dir),
      0)
      << Stderr() << Stdout();
  EXPECT_NE(Stdout().find("all thresholds met"), std::string::npos);
  EXPECT_NE(Read(json).find("\"thresholds_met\": true"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir_ / "csv" / "step-1-validation.csv"));
}

// A run's id names its CSV: an id that is a path ("../x", "a/b") names a
// file inside --csv-out all the same (the id "../../pwned" wrote above it).
TEST_F(ValidateCliTest, ARunsIdNamesAFileInsideTheCsvDirectory) {
  const std::filesystem::path unit = dir_ / "unit";
  std::filesystem::copy(testing::Source("datasets/paper-rig"), unit);
  std::string manifest = Read(unit / "unit.yaml");
  const std::string id = "id: step-1,";
  ASSERT_NE(manifest.find(id), std::string::npos) << manifest;
  manifest.replace(manifest.find(id), id.size(), "id: \"../../a/b c\",");
  std::ofstream(unit / "unit.yaml", std::ios::binary) << manifest;
  const std::filesystem::path csv_dir = dir_ / "out" / "csv";
  std::filesystem::create_directories(csv_dir);
  ASSERT_EQ(Run("validate --params " + testing::Source("datasets/paper-rig/truth.yaml") + " " +
                unit.string() + " --experiment ../../a/b\\ c --csv-out " + csv_dir.string()),
            0)
      << Stderr() << Stdout();
  EXPECT_EQ(Listing(dir_ / "out"),
            (std::set<std::string>{csv_dir.string(),
                                   (csv_dir / "%2E.%2F..%2Fa%2Fb%20c-validation.csv").string()}));
  EXPECT_EQ(FileNameOfId("step-1.b_2"), "step-1.b_2");
}

TEST_F(ValidateCliTest, MissedThresholdExitsFourAndStillReports) {
  const std::string json = (dir_ / "report.json").string();
  EXPECT_EQ(Run("validate --params " + testing::Source("configs/paper.yaml") + " " +
                testing::Source("datasets/paper-rig") + " --min-fit x=99.99 --json " + json),
            4);
  EXPECT_NE(Stdout().find("MISSED: x fit"), std::string::npos) << Stdout();
  EXPECT_NE(Read(json).find("\"thresholds_met\": false"), std::string::npos);
}

TEST_F(ValidateCliTest, BadInputExitsTwoAndWritesNothing) {
  const std::string json = (dir_ / "report.json").string();
  std::string params = Read(testing::Source("configs/paper.yaml"));
  params.replace(params.find("stroke: 0.05"), 12, "stroke: 0.08");
  const std::string other_geometry = Write("long.yaml", params);
  const auto before = Listing(dir_);
  EXPECT_EQ(Run("validate --params " + other_geometry + " " +
                testing::Source("datasets/paper-rig") + " --json " + json),
            2);
  // At the manifest's line of the stroke.
  EXPECT_NE(Stderr().find("datasets/paper-rig/unit.yaml:12: geometry disagrees"), std::string::npos)
      << Stderr();
  EXPECT_EQ(Run("validate --params " + testing::Source("configs/paper.yaml") + " " +
                testing::Source("datasets/fleet/PVQ13-0014") + " --json " + json),
            2);
  EXPECT_EQ(Run("validate --params " + testing::Source("configs/paper.yaml") + " " +
                testing::Source("datasets/paper-rig") + " --min-fit z=3 --json " + json),
            2);
  // A threshold that is no number the comparison can use, named by its flag.
  for (const auto& [threshold, message] :
       {std::pair<std::string, std::string>{"--min-fit x=nan",
                                            "--min-fit: x: expected a number at most 100, got nan"},
        {"--max-rmse p1=inf", "--max-rmse: p1: expected a finite number > 0, got inf"}}) {
    EXPECT_EQ(Run("validate --params " + testing::Source("configs/paper.yaml") + " " +
                  testing::Source("datasets/paper-rig") + " " + threshold + " --json " + json),
              2);
    EXPECT_NE(Stderr().find(message), std::string::npos) << Stderr();
  }
  EXPECT_EQ(Listing(dir_), before);
  // A CSV directory that is a file, a JSON path that is a directory: refused
  // before the validation runs, nothing written (the JSON was written first
  // and the command ended in an internal error).
  const std::string file = Write("taken", "x\n");
  const auto with_file = Listing(dir_);
  EXPECT_EQ(Run("validate --params " + testing::Source("configs/paper.yaml") + " " +
                testing::Source("datasets/paper-rig") + " --json " + json + " --csv-out " + file),
            2);
  EXPECT_NE(Stderr().find("exists and is not a directory"), std::string::npos) << Stderr();
  EXPECT_EQ(Run("validate --params " + testing::Source("configs/paper.yaml") + " " +
                testing::Source("datasets/paper-rig") + " --json " + dir_.string()),
            2);
  EXPECT_NE(Stderr().find("is a directory, not a file"), std::string::npos) << Stderr();
  EXPECT_EQ(Listing(dir_), with_file);
  // An output that is one of the inputs (the unit's manifest): refused, the
  // manifest intact (it was replaced by the report, and the unit unreadable).
  std::filesystem::copy(testing::Source("datasets/paper-rig"), dir_ / "unit");
  const std::string manifest = Read(dir_ / "unit" / "unit.yaml");
  EXPECT_EQ(Run("validate --params " + testing::Source("configs/paper.yaml") + " " +
                (dir_ / "unit").string() + " --json " + (dir_ / "unit" / "unit.yaml").string()),
            2);
  EXPECT_NE(Stderr().find("would replace an input of this command"), std::string::npos) << Stderr();
  EXPECT_EQ(Read(dir_ / "unit" / "unit.yaml"), manifest);
}

// A threshold given replaces that channel's default only: the paper's set
// on a fleet unit misses the position's fit and p2's RMSE (0.33 bar), and a
// looser p1 leaves both checked (before, one --max-rmse dropped p2's).
TEST_F(ValidateCliTest, AThresholdGivenKeepsTheOtherChannelsDefaults) {
  const std::string unit = testing::Source("datasets/fleet/PVQ13-0001");
  EXPECT_EQ(Run("validate " + unit + " --params " + testing::Source("configs/paper.yaml") +
                " --max-rmse p1=1e9"),
            4);
  EXPECT_NE(Stdout().find("MISSED: p2 RMSE"), std::string::npos) << Stdout();
  EXPECT_NE(Stdout().find("MISSED: x fit"), std::string::npos) << Stdout();
  EXPECT_EQ(Stdout().find("MISSED: p1 RMSE"), std::string::npos) << Stdout();
  // CHANNEL=off drops a default's check: with the three missed ones off,
  // nothing is missed.
  EXPECT_EQ(Run("validate " + unit + " --params " + testing::Source("configs/paper.yaml") +
                " --max-rmse p1=off --max-rmse p2=off --min-fit x=off"),
            0)
      << Stdout();
  EXPECT_EQ(Stdout().find("MISSED"), std::string::npos) << Stdout();
  EXPECT_EQ(Run("validate " + unit + " --params " + testing::Source("configs/paper.yaml") +
                " --max-rmse z=off"),
            2);
  EXPECT_NE(Stderr().find("'z=off': expected CHANNEL=NUMBER or CHANNEL=off"), std::string::npos)
      << Stderr();
}

// A set that names another unit than the logs' is validated, with a note:
// a fleet's sets are easily mixed up (the helper's PVQ13-0099 ran silently).
TEST_F(ValidateCliTest, ASetOfAnotherUnitIsNoted) {
  const std::string fleet = testing::Source("datasets/fleet");
  Run("validate " + fleet + "/PVQ13-0001 --params " + fleet + "/PVQ13-0002/truth.yaml");
  EXPECT_NE(Stderr().find("truth.yaml names unit PVQ13-0002; the logs are unit PVQ13-0001"),
            std::string::npos)
      << Stderr();
  Run("validate " + fleet + "/PVQ13-0001 --params " + fleet + "/PVQ13-0001/truth.yaml");
  EXPECT_EQ(Stderr().find("names unit"), std::string::npos) << Stderr();
}

}  // namespace
}  // namespace pneumaid
