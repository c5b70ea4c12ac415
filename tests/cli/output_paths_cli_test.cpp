// Where the commands may write (src/cli/output_paths.cpp), end to end: no
// output replaces one of the command's inputs (a unit's logs, a fleet's
// units, the results a report or merge reads) or another of its outputs, and
// no results directory is made inside a unit. Each refusal exits 2 and
// leaves every file as it was.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "cli_test_util.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;
using OutputPathsCliTest = testing::CliTest;

TEST_F(OutputPathsCliTest, NoOutputReplacesAnInputOrAnotherOutput) {
  const fs::path unit = dir_ / "fleet" / "PVQ13-0001";
  fs::create_directories(unit.parent_path());
  fs::copy(testing::Source("datasets/fleet/PVQ13-0001"), unit);
  const std::string fleet = (dir_ / "fleet").string(), results = (dir_ / "results").string();
  ASSERT_EQ(Run("batch " + fleet + " --out " + results), 0) << Stderr();
  const std::string log = (unit / "step-1.csv").string(), summary = results + "/summary.csv";
  const std::string logged = Read(log), summarised = Read(summary);
  const auto before = Listing(dir_);
  const auto refused = [this](const std::string& arguments, const std::string& why) {
    EXPECT_EQ(Run(arguments), 2) << arguments << "\n" << Stderr();
    EXPECT_NE(Stderr().find(why), std::string::npos) << arguments << "\n" << Stderr();
  };
  // batch's page onto a unit's log (it wrote 70 KiB of HTML there).
  refused("batch " + fleet + " --out " + (dir_ / "again").string() + " --html " + log,
          "would replace an input of this command");
  // Results inside a unit directory.
  refused("batch " + fleet + " --out " + (unit / "results").string(), "inside the unit directory");
  // merge's and report's outputs onto the results they read.
  refused("merge " + results + " --out " + (dir_ / "merged").string() + " --html " + summary,
          "would replace an input of this command");
  refused("report --results " + results + " --out " + summary,
          "would replace an input of this command");
  // Two outputs of one command at one path (the set was lost to the page).
  const std::string set = (dir_ / "set.yaml").string();
  refused("identify " + unit.string() + " --only valve --out " + set + " --html " + set,
          "named for two outputs of this command");
  EXPECT_EQ(Read(log), logged);
  EXPECT_EQ(Read(summary), summarised);
  EXPECT_EQ(Listing(dir_), before);
  // A page written into the results directory is no input of the next run.
  const std::string page = results + "/fleet.html";
  for (int run = 0; run < 2; ++run) {
    EXPECT_EQ(Run("batch " + fleet + " --out " + results + " --html " + page), 0) << Stderr();
    EXPECT_EQ(Run("merge " + results + " --out " + results + " --html " + page), 0) << Stderr();
  }
}

// validate's comparison CSVs are named by run: one that would take the name
// of a log of the unit (a log named step-1-validation.csv) is refused too.
TEST_F(OutputPathsCliTest, AComparisonCsvDoesNotReplaceALogOfTheUnit) {
  const fs::path unit = dir_ / "unit";
  fs::copy(testing::Source("datasets/fleet/PVQ13-0001"), unit);
  fs::rename(unit / "step-1.csv", unit / "step-1-validation.csv");
  std::string manifest = Read(unit / "unit.yaml");
  const auto at = manifest.find("file: step-1.csv");
  ASSERT_NE(at, std::string::npos);
  manifest.replace(at, 16, "file: step-1-validation.csv");
  Write("unit/unit.yaml", manifest);
  const std::string logged = Read(unit / "step-1-validation.csv");
  EXPECT_EQ(Run("validate " + unit.string() + " --params " + (unit / "truth.yaml").string() +
                " --csv-out " + unit.string()),
            2)
      << Stderr();
  EXPECT_NE(Stderr().find("would replace an input of this command"), std::string::npos) << Stderr();
  EXPECT_EQ(Read(unit / "step-1-validation.csv"), logged);
}

}  // namespace
}  // namespace pneumaid
