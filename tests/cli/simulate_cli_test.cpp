// End to end: the `pneumaid simulate` binary, its output and its exit codes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "cli_test_util.h"
#include "pneumaid/io/csv_table.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;

const std::string kPaper = std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper.yaml";

using SimulateCliTest = testing::CliTest;

TEST_F(SimulateCliTest, StepWritesAValidationLogInSI) {
  const std::string out = (dir_ / "sim.csv").string();
  ASSERT_EQ(Run("simulate --params " + kPaper +
                " --step 1@0 --step -1@0.8 --until 1.5 --rate 200 --out " + out),
            0)
      << Stderr();
  const CsvTable table = ReadCsv(out);
  EXPECT_EQ(table.rows(), 301u);
  for (const char* name : {"t", "u", "x", "v", "p1", "p2", "q1", "q2"}) {
    EXPECT_NE(table.Find(name), nullptr) << name;
  }
  EXPECT_EQ(table.Find("q1")->unit, "kg/s");
  EXPECT_EQ(table.Find("u")->values[160], -1.0);
  // The file drives a new run through --input, closing the loop.
  const std::string again = (dir_ / "again.csv").string();
  ASSERT_EQ(Run("simulate --params " + kPaper + " --input " + out + " --rate 200 --out " + again),
            0)
      << Stderr();
  EXPECT_NEAR(ReadCsv(again).Find("x")->values.back(), table.Find("x")->values.back(), 2e-4);
}

// A command alone (t and u, no state) from a first command of 1 V: the run
// starts from the retracted rest at the atmosphere, so the command is a
// step at its start, as `--step 1@0` and as validation reads such a log.
// Before, the valves started settled, fully open, from chambers at the
// atmosphere: a log that validation, reading the same rows, took otherwise.
TEST_F(SimulateCliTest, ACommandAloneStartsAtItsStepAsValidationReadsIt) {
  const std::string step = (dir_ / "step.csv").string();
  ASSERT_EQ(Run("simulate --params " + kPaper +
                " --step 1@0 --step -1@0.8 --until 1.5 --rate 200 --out " + step),
            0)
      << Stderr();
  const std::string command = (dir_ / "command.csv").string();
  {
    std::ofstream file(command);
    file << "t [s],u [V]\n";
    for (int i = 0; i <= 300; ++i) file << i * 0.005 << "," << (i * 0.005 < 0.8 ? 1 : -1) << "\n";
  }
  const std::string out = (dir_ / "sim.csv").string();
  ASSERT_EQ(Run("simulate --params " + kPaper + " --input " + command + " --rate 200 --out " + out),
            0)
      << Stderr();
  const CsvTable a = ReadCsv(step), b = ReadCsv(out);
  ASSERT_EQ(a.rows(), b.rows());
  double worst_x = 0, worst_p1 = 0;
  for (std::size_t i = 0; i < a.rows(); ++i) {
    worst_x = std::max(worst_x, std::fabs(a.Find("x")->values[i] - b.Find("x")->values[i]));
    worst_p1 = std::max(worst_p1, std::fabs(a.Find("p1")->values[i] - b.Find("p1")->values[i]));
  }
  EXPECT_LT(worst_x, 2e-4);  // m
  EXPECT_LT(worst_p1, 2e3);  // Pa
}

// A unit's log whose rod rests on its stop reads a little beyond it (the
// fleet's step-1 starts at -0.01 mm from the retracted end): the run starts
// as validation starts it, clamped to the stroke, not refused.
TEST_F(SimulateCliTest, ALogWhoseRodRestsJustBeyondItsStopIsSimulated) {
  const std::string log =
      std::string(PNEUMAID_SOURCE_DIR) + "/datasets/fleet/PVQ13-0002/step-1.csv";
  ASSERT_LT(ReadCsv(log).Find("x")->values.front(), 0.0);  // as logged, in mm from retracted
  const std::string out = (dir_ / "sim.csv").string();
  ASSERT_EQ(Run("simulate --params " + kPaper + " --input " + log + " --out " + out), 0)
      << Stderr();
  EXPECT_GE(ReadCsv(out).Find("x")->values.front(), -0.025);
}

// A log of a unit directory is simulated as validate simulates it: the
// unit's rig conditions and position zero, the logger's pauses, a start read
// where the log begins unsettled, and the flows as its declared meters (tau
// 30 ms here) read them. Before, simulate read the log's command and first
// sample only, and its flows were the model's, unlagged.
TEST_F(SimulateCliTest, ALogOfAUnitIsSimulatedAsValidateSimulatesIt) {
  // A copy: the test tries to write over one of its logs.
  const std::string unit = (dir_ / "PVQ13-0002").string();
  fs::copy(std::string(PNEUMAID_SOURCE_DIR) + "/datasets/fleet/PVQ13-0002", unit,
           fs::copy_options::recursive);
  const std::string truth = unit + "/truth.yaml";
  ASSERT_EQ(Run("validate " + unit + " --params " + truth + " --csv-out " + dir_.string()), 0)
      << Stderr();
  const std::string stroke_log = Read(unit + "/stroke-040.csv");
  const std::string out = (dir_ / "sim.csv").string();
  ASSERT_EQ(Run("simulate --params " + truth + " --input " + unit + "/step-1.csv --out " + out), 0)
      << Stderr();
  const CsvTable validated = ReadCsv((dir_ / "step-1-validation.csv").string());
  const CsvTable simulated = ReadCsv(out);
  ASSERT_EQ(simulated.rows(), validated.rows());
  for (const auto& [mine, theirs] : std::vector<std::pair<std::string, std::string>>{
           {"t", "t"}, {"x", "x_sim"}, {"p1", "p1_sim"}, {"q1", "q1_sim"}, {"q2", "q2_sim"}}) {
    const std::vector<double>& a = simulated.Find(mine)->values;
    const std::vector<double>& b = validated.Find(theirs)->values;
    double scale = 0;
    for (double value : b) scale = std::max(scale, std::fabs(value));
    for (std::size_t i = 0; i < a.size(); ++i)
      ASSERT_NEAR(a[i], b[i], 1e-6 * scale) << mine << " row " << i;
  }
  // --rate does not apply: the run is on the log's own clock.
  const std::string other = (dir_ / "other.csv").string();
  EXPECT_EQ(Run("simulate --params " + truth + " --input " + unit +
                "/step-1.csv --rate 100 --out " + other),
            2);
  EXPECT_NE(Stderr().find("--rate: not for a log of a unit directory"), std::string::npos)
      << Stderr();
  EXPECT_FALSE(fs::exists(other));
  // Nor may the output be one of the unit's files, which are all read.
  EXPECT_EQ(Run("simulate --params " + truth + " --input " + unit + "/step-1.csv --out " + unit +
                "/stroke-040.csv"),
            2);
  EXPECT_NE(Stderr().find("stroke-040.csv"), std::string::npos) << Stderr();
  EXPECT_EQ(Read(unit + "/stroke-040.csv"), stroke_log);
  // --until, from the log's first sample, cuts the run's rows.
  ASSERT_EQ(Run("simulate --params " + truth + " --input " + unit +
                "/step-1.csv --until 0.5 --out " + other),
            0)
      << Stderr();
  const CsvTable cut = ReadCsv(other);
  const std::vector<double>& t = cut.Find("t")->values;
  EXPECT_LE(t.back(), 0.5);
  EXPECT_GT(t.back(), 0.49);
}

TEST_F(SimulateCliTest, BadInputExitsTwoAndWritesNothing) {
  const std::string out = (dir_ / "sim.csv").string();
  std::ifstream paper(kPaper);
  std::string text((std::istreambuf_iterator<char>(paper)), {});
  const std::string typo = Write("typo.yaml", text + "colour: blue\n");
  text.replace(text.find("effects: {}"), 11, "effects: {heat_transfer: {h: -0.1}}");
  const std::string negative = Write("heat.yaml", text);
  const std::string ragged = Write("ragged.csv", "t [s],u [V]\n0,0\n0.1\n");
  // x from the retracted stop in a log outside a unit directory (read from
  // mid-stroke): the format's check of a wrong origin.
  const std::string retracted = Write(
      "retracted.csv", "t [s],u [V],x [mm],p1 [Pa],p2 [Pa]\n0,0,0,1e5,5e5\n0.1,1,51,5e5,1e5\n");
  struct Case {
    std::string arguments;
    std::string message;
  } cases[] = {
      {"--params " + typo + " --step 1@0 --until 1", "typo.yaml:34:1: unknown key 'colour'"},
      {"--params " + negative + " --step 1@0 --until 1", "heat_transfer"},
      {"--params " + kPaper + " --step 1at0 --until 1", "expected U@T0"},
      {"--params " + kPaper + " --step 2@0 --until 1", "expected U@T0"},
      {"--params " + kPaper + " --step 1@0", "--until"},
      {"--params " + kPaper + " --input " + ragged, "ragged.csv:3: ragged row"},
      {"--params " + kPaper + " --input " + retracted,
       "retracted.csv:3:3: column 'x': position 51 mm is more than 1 mm outside the stroke"},
      {"--params " + kPaper + " --input " + (dir_ / "missing.csv").string(), "cannot open"},
      {"--params " + (dir_ / "none.yaml").string() + " --step 1@0 --until 1", "cannot open"},
      {"--params " + kPaper + " --step 1@0.1 --until 1e6 --rate 1e6",
       "1e+12 samples asked for, expected at most 1e+07"},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(Run("simulate " + c.arguments + " --out " + out), 2) << c.arguments;
    EXPECT_NE(Stderr().find(c.message), std::string::npos) << Stderr();
    EXPECT_FALSE(fs::exists(out)) << c.arguments;
  }
  EXPECT_EQ(Run("simulate --params " + kPaper), 2);  // missing required options
}

}  // namespace
}  // namespace pneumaid
