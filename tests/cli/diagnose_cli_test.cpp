// `pneumaid diagnose` end to end on the bundled hidden-effect units: exit 0
// whether or not an effect is named, the augmented set and the reports
// written; a valve lag and a flow-meter lag told apart with the evidence in
// the report; bad input exits 2 and writes nothing.
#include <gtest/gtest.h>

#include <filesystem>

#include "cli_test_util.h"
#include "pneumaid/model/effects.h"

namespace pneumaid {
namespace {

using DiagnoseCliTest = testing::CliTest;

// Sensor or actuator: with the two lags as the only candidates, each unit
// gets its own, and the report shows where the gain is.
TEST_F(DiagnoseCliTest, TellsAValveLagFromAFlowMeterLag) {
  for (const auto& [unit, expected] : {std::make_pair("valve-lag", "valve_lag"),
                                       std::make_pair("flow-sensor-lag", "flow_sensor_lag")}) {
    const std::filesystem::path out = dir_ / unit;
    ASSERT_EQ(Run("diagnose --params " + testing::Source("configs/paper.yaml") + " " +
                  testing::Source(std::string("datasets/hidden/") + unit) + " --out " +
                  out.string() + " --effects valve_lag,flow_sensor_lag --max-effects 1" +
                  " --html " + out.string() + ".html"),
              0)
        << Stderr() << Stdout();
    // The page names the effect too, with the residuals before and after.
    const std::string page = Read(out.string() + ".html");
    EXPECT_NE(page.find(std::string("Named effect: <b>") + expected + "</b>"), std::string::npos);
    EXPECT_NE(page.find("\"label\":\"after\""), std::string::npos);
    const std::string report = Read(out / "report.md");
    EXPECT_NE(report.find(std::string("### Named: ") + expected), std::string::npos) << report;
    EXPECT_NE(report.find("Held-back gain per channel:"), std::string::npos);
    EXPECT_NE(
        Read(out / "report.json").find(std::string("\"named_effects\": [\"") + expected + "\"]"),
        std::string::npos);
    EXPECT_NE(Read(out / "params.yaml").find(std::string("effects: {") + expected),
              std::string::npos);
    EXPECT_TRUE(std::filesystem::exists(out / "before" / "step-1.csv"));
    EXPECT_TRUE(std::filesystem::exists(out / "after" / "profile-1.csv"));
  }
}

TEST_F(DiagnoseCliTest, BadInputExitsTwoAndWritesNothing) {
  const auto before = Listing(dir_);
  const std::string out = (dir_ / "out").string();
  EXPECT_EQ(
      Run("diagnose --params " + testing::Source("configs/paper.yaml") + " " +
          testing::Source("datasets/hidden/valve-lag") + " --out " + out + " --effects warp_drive"),
      2);
  EXPECT_NE(Stderr().find("unknown effect 'warp_drive'"), std::string::npos) << Stderr();
  EXPECT_EQ(Run("diagnose --params " + testing::Source("configs/paper.yaml") + " " +
                testing::Source("datasets/fleet/PVQ13-0014") + " --out " + out),
            2);
  EXPECT_EQ(Run("diagnose --params " + testing::Source("configs/paper.yaml") + " " +
                testing::Source("datasets/hidden/valve-lag") + " --out " + out + " --max-effects " +
                std::to_string(EffectCatalog().size() + 1)),
            2);
  EXPECT_EQ(Listing(dir_), before);
  // An --out that holds other files is never replaced.
  const std::string notes = Write("notes.txt", "mine");
  EXPECT_EQ(Run("diagnose --params " + testing::Source("configs/paper.yaml") + " " +
                testing::Source("datasets/hidden/valve-lag") + " --out " + dir_.string()),
            2);
  EXPECT_NE(Stderr().find("not an earlier diagnose output"), std::string::npos) << Stderr();
  EXPECT_EQ(Read(notes), "mine");
}

}  // namespace
}  // namespace pneumaid
