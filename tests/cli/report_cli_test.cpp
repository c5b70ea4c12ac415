// `pneumaid report` and `--html` end to end: a unit's page from identify and
// validate, a diagnose output directory's page, the fleet's page from batch,
// merge and report --results; bad input exits 2 and writes nothing.
#include <gtest/gtest.h>

#include <filesystem>

#include "cli_test_util.h"

namespace pneumaid {
namespace {

using ReportCliTest = testing::CliTest;

bool IsPage(const std::string& html) {
  return html.rfind("<!DOCTYPE html>", 0) == 0 &&
         html.find("id=\"pneumaid-status\"") != std::string::npos &&
         html.find("</html>") != std::string::npos;
}

TEST_F(ReportCliTest, IdentifyAndValidateWriteTheUnitsPage) {
  const std::string unit = testing::Source("datasets/paper-rig");
  const std::string params = (dir_ / "p.yaml").string();
  ASSERT_EQ(Run("identify " + unit + " --out " + params + " --html " + (dir_ / "i.html").string()),
            0)
      << Stderr();
  const std::string identified = Read(dir_ / "i.html");
  EXPECT_TRUE(IsPage(identified));
  EXPECT_NE(identified.find("Friction fit: converged"), std::string::npos);  // identify's report
  EXPECT_NE(Stdout().find("wrote " + (dir_ / "i.html").string()), std::string::npos);
  // validate's page shows the runs it validated.
  const int status = Run("validate --params " + params + " " + unit + " --experiment step-1" +
                         " --html " + (dir_ / "v.html").string());
  EXPECT_TRUE(status == 0 || status == 4) << Stderr();
  const std::string validated = Read(dir_ / "v.html");
  EXPECT_TRUE(IsPage(validated));
  EXPECT_NE(validated.find("\"title\":\"step-1: x\""), std::string::npos);
  EXPECT_EQ(validated.find("\"title\":\"profile-1: x\""), std::string::npos);
  ASSERT_EQ(Run("report --params " + params + " " + unit + " --out " + (dir_ / "r.html").string()),
            0);
  EXPECT_TRUE(IsPage(Read(dir_ / "r.html")));
}

// A diagnose output directory read back: its Markdown, its augmented set and
// the effects its JSON names.
TEST_F(ReportCliTest, ReportsADiagnoseOutputDirectory) {
  const std::filesystem::path out = dir_ / "diagnosed";
  std::filesystem::create_directories(out);
  Write("diagnosed/report.md",
        "# Diagnose: hidden-valve-lag\n\n| effect | named |\n|---|---|\n"
        "| valve_lag | **yes** |\n");
  std::filesystem::copy_file(testing::Source("datasets/hidden/valve-lag/truth.yaml"),
                             out / "params.yaml");
  Write("diagnosed/report.json",
        "{\"format\": \"pneumaid-report/1\", \"unit\": \"hidden-valve-lag\", \"experiments\": [],\n"
        " \"named_effects\": [\"valve_lag\"]}\n");
  const std::string page = (dir_ / "d.html").string();
  ASSERT_EQ(Run("report --params " + testing::Source("configs/paper.yaml") + " " +
                testing::Source("datasets/hidden/valve-lag") + " --diagnose " + out.string() +
                " --out " + page),
            0)
      << Stderr();
  const std::string html = Read(page);
  EXPECT_TRUE(IsPage(html));
  EXPECT_NE(html.find("Named effect: <b>valve_lag</b>"), std::string::npos);
  EXPECT_NE(html.find("<td class=l>valve_lag</td>"), std::string::npos);
  EXPECT_NE(html.find("\"label\":\"after\""), std::string::npos);
}

TEST_F(ReportCliTest, BatchMergeAndReportWriteTheFleetsPage) {
  const std::string results = (dir_ / "results").string();
  EXPECT_EQ(Run("batch " + testing::Source("datasets/fleet") + " --out " + results + " -j 2" +
                " --html " + (dir_ / "b.html").string()),
            3);  // the corrupt unit failed
  const std::string batch = Read(dir_ / "b.html");
  EXPECT_TRUE(IsPage(batch));
  EXPECT_NE(batch.find("<tr class=failed><td class=l>PVQ13-0014</td>"), std::string::npos);
  EXPECT_NE(batch.find("<a href=\"#unit-PVQ13_0013-2d\">"), std::string::npos);
  ASSERT_EQ(Run("merge " + results + " --html " + (dir_ / "m.html").string()), 0) << Stderr();
  ASSERT_EQ(Run("report --results " + results + " --out " + (dir_ / "r.html").string()), 0);
  EXPECT_EQ(Read(dir_ / "m.html"), Read(dir_ / "r.html"));
  // The page written into the results directory, and again: an earlier page
  // there is no input of the report.
  for (int run = 0; run < 2; ++run)
    EXPECT_EQ(Run("report --results " + results + " --out " + results + "/fleet.html"), 0)
        << Stderr();
}

TEST_F(ReportCliTest, BadInputExitsTwoAndWritesNothing) {
  const std::string unit = testing::Source("datasets/hidden/valve-lag");
  const std::string params = testing::Source("configs/paper.yaml");
  const std::string out = (dir_ / "page.html").string();
  // Not a diagnose output directory.
  std::filesystem::create_directories(dir_ / "empty");
  EXPECT_EQ(Run("report --params " + params + " " + unit + " --diagnose " +
                (dir_ / "empty").string() + " --out " + out),
            2);
  EXPECT_NE(Stderr().find("not a diagnose output directory: no report.md"), std::string::npos)
      << Stderr();
  // A report.json that is not a diagnose report: its file named.
  Write("empty/report.md", "# x\n");
  std::filesystem::copy_file(params, dir_ / "empty" / "params.yaml");
  Write("empty/report.json", "{\"format\": \"pneumaid-report/1\", \"experiments\": []}\n");
  const auto listing = Listing(dir_);
  EXPECT_EQ(Run("report --params " + params + " " + unit + " --diagnose " +
                (dir_ / "empty").string() + " --out " + out),
            2);
  EXPECT_NE(Stderr().find("report.json"), std::string::npos) << Stderr();
  EXPECT_NE(Stderr().find("named_effects: expected a list"), std::string::npos) << Stderr();
  // A diagnose output of another unit: named, not shown as this unit's.
  Write("empty/report.json",
        "{\"format\": \"pneumaid-report/1\", \"unit\": \"paper-rig\", \"experiments\": [],\n"
        " \"named_effects\": [\"valve_lag\"]}\n");
  EXPECT_EQ(Run("report --params " + params + " " + unit + " --diagnose " +
                (dir_ / "empty").string() + " --out " + out),
            2);
  EXPECT_NE(Stderr().find("report.json:1:"), std::string::npos) << Stderr();
  EXPECT_NE(Stderr().find("unit: a diagnose report of unit 'paper-rig', expected one of unit "
                          "'hidden-valve-lag'"),
            std::string::npos)
      << Stderr();
  // A fleet report takes no unit; a unit report needs --params.
  EXPECT_EQ(Run("report --results " + (dir_ / "empty").string() + " " + unit + " --out " + out), 2);
  EXPECT_EQ(Run("report " + unit + " --out " + out), 2);
  EXPECT_NE(Stderr().find("--params"), std::string::npos) << Stderr();
  // A page that cannot be written stops the command before it writes anything.
  const std::string set = (dir_ / "set.yaml").string();
  EXPECT_EQ(Run("identify " + testing::Source("datasets/paper-rig") + " --only valve --out " + set +
                " --html " + (dir_ / "no-such-dir" / "page.html").string()),
            2);
  EXPECT_NE(Stderr().find("does not exist"), std::string::npos) << Stderr();
  // So does a parameter set that cannot be written (checked by the same
  // rule: before, identify fitted every component, then failed to write).
  EXPECT_EQ(Run("identify " + testing::Source("datasets/paper-rig") + " --out " +
                (dir_ / "no-such-dir" / "set.yaml").string()),
            2);
  EXPECT_NE(Stderr().find("--out: the directory"), std::string::npos) << Stderr();
  EXPECT_EQ(Stdout().find("Valve K_vp fit"), std::string::npos) << Stdout();  // no fit ran
  EXPECT_FALSE(std::filesystem::exists(set));
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_EQ(Listing(dir_), listing);
}

}  // namespace
}  // namespace pneumaid
