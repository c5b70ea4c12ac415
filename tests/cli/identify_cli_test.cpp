// `pneumaid identify` then `validate` on the bundled unit; bad input writes nothing.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
  EXPECT_TRUE(std::filesystem::exists(out));
}

TEST_F(IdentifyCliTest, BadInputExitsTwoAndWritesNothing) {
  const std::string out = (dir_ / "identified.yaml").string();
  EXPECT_EQ(Run("identify " + testing::Source("datasets/fleet/PVQ13-0014") + " --out " + out), 2);
  EXPECT_EQ(
      Run("identify " + testing::Source("datasets/paper-rig") + " --only valves --out " + out), 2);
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace pneumaid
