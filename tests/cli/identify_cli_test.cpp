// `pneumaid identify` then `validate` on the bundled unit; bad input writes nothing.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli_test_util.h"

namespace pneumaid {
namespace {

using IdentifyCliTest = testing::CliTest;

TEST_F(IdentifyCliTest, IdentifiedSetValidates) {
  const std::string out = (dir_ / "identified.yaml").string();
  ASSERT_EQ(Run("identify " + testing::Source("datasets/paper-rig") + " --only valve --out " + out),
            0)
      << Stderr();
  EXPECT_NE(Stdout().find("From the prior"), std::string::npos);
  EXPECT_NE(Read(out).find("sha256"), std::string::npos);
  EXPECT_EQ(Run("validate --params " + out + " " + testing::Source("datasets/paper-rig")), 0)
      << Stdout() << Stderr();
}

// `sensors` is optional in pneumaid-rig/1: the bundled unit with its sensors
// block cut down to the meters' lags is identified and refined (it exited 2,
// "no sigma given", before), and the report names the noise it estimated.
TEST_F(IdentifyCliTest, AUnitWithoutDeclaredNoiseIsIdentifiedAndRefined) {
  const std::filesystem::path unit = dir_ / "unit";
  std::filesystem::copy(testing::Source("datasets/paper-rig"), unit);
  std::string manifest = Read(unit / "unit.yaml");
  const std::size_t sensors = manifest.find("sensors:"),
                    experiments = manifest.find("experiments:");
  ASSERT_TRUE(sensors != std::string::npos && experiments != std::string::npos);
  manifest.replace(sensors, experiments - sensors,
                   "sensors:\n  q: {tau: 0.03}\n  q_in: {tau: 0.03}\n  q_out: {tau: 0.03}\n");
  std::ofstream(unit / "unit.yaml", std::ios::binary) << manifest;
  const std::string out = (dir_ / "refined.yaml").string();
  ASSERT_EQ(Run("identify " + unit.string() + " --refine --out " + out), 0) << Stderr();
  EXPECT_NE(Stdout().find("noise not declared, estimated from the logs: x "), std::string::npos)
      << Stdout();
  EXPECT_NE(Stdout().find("Refinement: converged"), std::string::npos) << Stdout();
  // identify --refine fits the creep speed too (RefineOptions::ForIdentify).
  EXPECT_NE(
      Stdout().find("creep fit (effects.stick_creep.v), median reduced chi-square: v held at"),
      std::string::npos)
      << Stdout();
  EXPECT_TRUE(std::filesystem::exists(out));
}

TEST_F(IdentifyCliTest, BadInputExitsTwoAndWritesNothing) {
  const std::string out = (dir_ / "identified.yaml").string();
  EXPECT_EQ(Run("identify " + testing::Source("datasets/fleet/PVQ13-0014") + " --out " + out), 2);
  EXPECT_EQ(
      Run("identify " + testing::Source("datasets/paper-rig") + " --only valves --out " + out), 2);
  // --spec and --threads belong to --refine: alone they are refused, not ignored.
  EXPECT_EQ(Run("identify " + testing::Source("datasets/paper-rig") + " --spec " +
                testing::Source("configs/fit-default.yaml") + " --out " + out),
            2);
  EXPECT_EQ(
      Run("identify " + testing::Source("datasets/paper-rig") + " --no-stick-creep --out " + out),
      2);
  EXPECT_FALSE(std::filesystem::exists(out));
}

// A prior whose rod creeps (stick_creep, an effect that acts on friction),
// asked to refine with a spec that replays friction under the paper's law
// with exact stick: refused before the component fits, the spec and the
// effect named.
TEST_F(IdentifyCliTest, ACreepingPriorIsRefusedAFrictionReplayBeforeTheComponentFits) {
  std::string prior = Read(testing::Source("configs/paper.yaml"));
  const std::size_t effects = prior.find("effects: {}");
  ASSERT_NE(effects, std::string::npos);
  prior.replace(effects, 11, "effects: {stick_creep: {v: 1.0e-4}}");
  const std::filesystem::path prior_path = dir_ / "creeping.yaml";
  std::ofstream(prior_path, std::ios::binary) << prior;
  const std::string out = (dir_ / "refined.yaml").string();
  EXPECT_EQ(
      Run("identify " + testing::Source("datasets/paper-rig") + " --prior " + prior_path.string() +
          " --refine --spec " + testing::Source("configs/fit-from-scratch.yaml") + " --out " + out),
      2);
  EXPECT_NE(Stderr().find("fit-from-scratch.yaml"), std::string::npos) << Stderr();
  EXPECT_NE(Stderr().find("stick_creep"), std::string::npos) << Stderr();
  EXPECT_EQ(Stdout().find("Valve K_vp fit"), std::string::npos) << Stdout();
  EXPECT_FALSE(std::filesystem::exists(out));
}

// A valve bench unit asked for --refine, which needs stroke runs: refused
// before the component fits (it was refused after them, their time spent), with
// the unit's manifest and the spec named, exit 2 and nothing written.
TEST_F(IdentifyCliTest, AUnitWithNothingToRefineIsRefusedBeforeTheComponentFits) {
  const std::filesystem::path unit = dir_ / "unit";
  std::filesystem::copy(testing::Source("datasets/paper-rig"), unit);
  std::string manifest = Read(unit / "unit.yaml");
  const std::size_t experiments = manifest.find("experiments:");
  ASSERT_NE(experiments, std::string::npos);
  manifest.replace(experiments, std::string::npos,
                   "experiments:\n  - {id: valve-staircase, kind: valve, file: "
                   "valve-staircase.csv}\n");
  std::ofstream(unit / "unit.yaml", std::ios::binary) << manifest;
  const std::string out = (dir_ / "refined.yaml").string();
  EXPECT_EQ(Run("identify " + unit.string() + " --refine --out " + out), 2);
  EXPECT_NE(Stderr().find((unit / "unit.yaml").string() + ": the unit has no stroke experiment"),
            std::string::npos)
      << Stderr();
  EXPECT_NE(Stderr().find("fit-default.yaml"), std::string::npos) << Stderr();
  EXPECT_EQ(Stdout().find("Valve K_vp fit"), std::string::npos) << Stdout();
  EXPECT_FALSE(std::filesystem::exists(out));
  // Without --refine the same unit is identified.
  EXPECT_EQ(Run("identify " + unit.string() + " --out " + out), 0) << Stderr();
}

// The format's promise: the tool says which rig defaults it used and which
// columns it ignores (check was the only command that did), and the
// manifest's notes (here a log listed twice); the identified set's
// provenance records the defaults.
TEST_F(IdentifyCliTest, SaysWhichRigDefaultsItUsedAndWhichColumnsItIgnores) {
  const std::filesystem::path unit = dir_ / "unit";
  std::filesystem::copy(testing::Source("datasets/paper-rig"), unit);
  std::string manifest = Read(unit / "unit.yaml");
  const std::string density = "  air_density: 1.178\n";
  ASSERT_NE(manifest.find(density), std::string::npos);
  manifest.erase(manifest.find(density), density.size());
  // The 9 cm tube's log listed once more, as if its test had been run again.
  const std::string tube =
      "  - {id: pipe-009, kind: pipeline, file: pipe-009.csv, tube_length: \"9 cm\"}\n";
  ASSERT_NE(manifest.find(tube), std::string::npos);
  manifest.insert(
      manifest.find(tube) + tube.size(),
      "  - {id: pipe-009-again, kind: pipeline, file: pipe-009.csv, tube_length: \"9 cm\"}\n");
  std::ofstream(unit / "unit.yaml", std::ios::binary) << manifest;
  std::string log = Read(unit / "pipe-009.csv");
  std::string with_column;
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    with_column += line;
    if (!line.empty() && line[0] != '#') with_column += line[0] == 't' ? ",temp [degC]" : ",21.5";
    with_column += "\n";
  }
  std::ofstream(unit / "pipe-009.csv", std::ios::binary) << with_column;
  const std::string out = (dir_ / "set.yaml").string();
  ASSERT_EQ(Run("identify " + unit.string() + " --only pipeline --out " + out), 0) << Stderr();
  EXPECT_NE(Stderr().find((unit / "unit.yaml").string() + ": rig defaults used: rig.air_density"),
            std::string::npos)
      << Stderr();
  EXPECT_NE(Stderr().find((unit / "pipe-009.csv").string() + ": ignored columns: temp"),
            std::string::npos)
      << Stderr();
  EXPECT_NE(Stderr().find("logs 'pipe-009' (pipeline) and 'pipe-009-again' (pipeline) are the "
                          "same bytes"),
            std::string::npos)
      << Stderr();
  EXPECT_NE(Read(out).find("rig_defaults_used: [rig.air_density]"), std::string::npos) << Read(out);
}

}  // namespace
}  // namespace pneumaid
