// `pneumaid synth` end to end: a unit that `check` accepts, and nothing
// written on bad input or over an existing directory.
#include <gtest/gtest.h>

#include <filesystem>

#include "cli_test_util.h"

namespace pneumaid {
namespace {

using SynthCliTest = testing::CliTest;

std::string Args(const std::string& out) {
  return "synth --truth " + testing::Source("configs/paper.yaml") + " --protocol " +
         testing::Source("configs/protocol-fleet.yaml") + " --seed 4 --out " + out;
}

TEST_F(SynthCliTest, WritesAUnitThatChecks) {
  const std::string unit = (dir_ / "unit").string();
  ASSERT_EQ(Run(Args(unit) + " --unit X-1 --spread 'friction.*.*=0.1'"), 0) << Stderr();
  for (const char* file : {"unit.yaml", "truth.yaml", "valve-staircase.csv", "pipe-038.csv",
                           "stroke-040.csv", "stroke-100.csv", "step-1.csv"}) {
    EXPECT_TRUE(std::filesystem::exists(dir_ / "unit" / file)) << file;
  }
  EXPECT_EQ(Run("check " + unit), 0) << Stderr();
  EXPECT_NE(Stdout().find("unit X-1"), std::string::npos);
  EXPECT_NE(Read(dir_ / "unit" / "step-1.csv").find("synthetic data"), std::string::npos);
}

TEST_F(SynthCliTest, RefusesToOverwriteAndBadInputWritesNothing) {
  const std::string unit = (dir_ / "unit").string();
  ASSERT_EQ(Run(Args(unit)), 0) << Stderr();
  const auto before = Listing(dir_);
  EXPECT_EQ(Run(Args(unit)), 2);
  EXPECT_NE(Stderr().find("not empty; not overwriting"), std::string::npos) << Stderr();
  const std::string other = (dir_ / "other").string();
  EXPECT_EQ(Run(Args(other) + " --scale friction.sideways.Fs=3"), 2);
  EXPECT_NE(Stderr().find("names no parameter"), std::string::npos) << Stderr();
  EXPECT_EQ(Run(Args(other) + " --spread nonsense"), 2);
  const std::string bad_protocol =
      Write("bad.yaml", "format: pneumaid-protocol/1\nvalve: {stp: 1}\n");
  EXPECT_EQ(Run("synth --truth " + testing::Source("configs/paper.yaml") + " --protocol " +
                bad_protocol + " --out " + other),
            2);
  EXPECT_NE(
      Stderr().find("bad.yaml:2:9: unknown key 'valve.stp' (expected hold, levels, ramp, step)"),
      std::string::npos)
      << Stderr();
  std::filesystem::remove(dir_ / "bad.yaml");
  EXPECT_EQ(Listing(dir_), before);
}

}  // namespace
}  // namespace pneumaid
