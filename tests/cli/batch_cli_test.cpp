// `pneumaid batch`, `merge` and `export` end to end: exit statuses, a kill
// mid-run then --resume, two shard processes, the exports read back.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>

#include "cli_test_util.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;
using BatchCliTest = testing::CliTest;

std::string WithoutDates(std::string text) {
  return std::regex_replace(text, std::regex("date: [^,}]*"), "date: ");
}

TEST_F(BatchCliTest, AFleetWithACorruptUnitExitsThreeAndMergeFlagsTheOutlier) {
  const std::string results = (dir_ / "results").string();
  EXPECT_EQ(Run("batch " + testing::Source("datasets/fleet") + " --out " + results + " -j 2"), 3)
      << Stderr();
  EXPECT_NE(Stdout().find("PVQ13-0014: failed"), std::string::npos) << Stdout();
  // A new directory for the summary is made (it had to exist: exit 2).
  EXPECT_EQ(Run("merge " + results + " --out " + (dir_ / "merged").string()), 0) << Stderr();
  const std::string summary = Read(dir_ / "merged" / "fleet-summary.md");
  EXPECT_NE(summary.find("**PVQ13-0013**"), std::string::npos) << summary;
  EXPECT_NE(summary.find("PVQ13-0014: "), std::string::npos);
  EXPECT_TRUE(fs::exists(dir_ / "merged" / "fleet-summary.csv"));
  // Bad input: exit 2, nothing written.
  EXPECT_EQ(Run("batch " + (dir_ / "nothing").string() + " --out " + results), 2);
  EXPECT_EQ(
      Run("batch " + testing::Source("datasets/fleet") + " --out " + results + " --shard 3/2"), 2);
  EXPECT_NE(Stderr().find("--shard"), std::string::npos);
  EXPECT_EQ(
      Run("batch " + testing::Source("datasets/fleet") + " --out " + results + " --shard auto"), 2);
  EXPECT_NE(Stderr().find("SLURM_ARRAY_TASK_ID"), std::string::npos) << Stderr();
  // diagnose's candidates: with --diagnose only, and each one known; the
  // message names the flag.
  const std::string fresh = (dir_ / "fresh").string();
  EXPECT_EQ(Run("batch " + testing::Source("datasets/fleet") + " --out " + fresh +
                " --effects valve_lag"),
            2);
  EXPECT_NE(Stderr().find("--effects"), std::string::npos) << Stderr();
  EXPECT_EQ(Run("batch " + testing::Source("datasets/fleet") + " --out " + fresh +
                " --diagnose --effects valve_lag,warp_drive"),
            2);
  EXPECT_NE(Stderr().find("--effects"), std::string::npos) << Stderr();
  EXPECT_NE(Stderr().find("unknown effect 'warp_drive'"), std::string::npos) << Stderr();
  // A spec is for --refine (it was ignored without it), as identify says.
  EXPECT_EQ(Run("batch " + testing::Source("datasets/fleet") + " --out " + fresh + " --spec " +
                testing::Source("configs/fit-default.yaml")),
            2);
  EXPECT_NE(Stderr().find("--spec requires --refine"), std::string::npos) << Stderr();
  EXPECT_FALSE(fs::exists(fresh));
}

// SIGKILL mid-run, then --resume: units finished before the kill are not
// redone, every result directory is whole, and the results equal an
// uninterrupted run's but for the provenance date.
TEST_F(BatchCliTest, AKilledRunResumesToTheSameResults) {
  const fs::path fleet = dir_ / "fleet";
  fs::create_directories(fleet);
  for (const char* unit : {"PVQ13-0001", "PVQ13-0002", "PVQ13-0003"})
    fs::copy(testing::Source(std::string("datasets/fleet/") + unit), fleet / unit,
             fs::copy_options::recursive);
  const std::string killed = (dir_ / "killed").string(), whole = (dir_ / "whole").string();
  const std::string batch = "batch " + fleet.string() + " --refine -j 1 --out ";
  // Each unit refines for about a second (more under a sanitizer), in name
  // order: the kill lands as soon as the first unit's result is in place
  // (polled every 20 ms for up to two minutes).
  const std::string command = std::string(PNEUMAID_CLI) + " " + batch + killed +
                              " > /dev/null 2>&1 & pid=$!; for i in $(seq 6000); do "
                              "[ -d " +
                              killed +
                              "/PVQ13-0001 ] && break; sleep 0.02; done; "
                              "kill -9 $pid; wait $pid";
  std::system(("bash -c '" + command + "'").c_str());
  int complete = 0;
  for (const char* unit : {"PVQ13-0001", "PVQ13-0002", "PVQ13-0003"}) {
    const fs::path result = fs::path(killed) / unit;
    if (!fs::exists(result)) continue;
    for (const char* file : {"params.yaml", "report.txt", "report.json", "stamp.txt"})
      EXPECT_TRUE(fs::exists(result / file)) << unit << " is half-written: " << file;
    ++complete;
  }
  ASSERT_GE(complete, 1) << "the kill came before any unit was done; lengthen the sleep";
  ASSERT_LT(complete, 3) << "the kill came after the end; shorten the sleep";
  EXPECT_EQ(Run(batch + killed + " --resume"), 0) << Stderr();
  const std::string resumed_report = Stdout();
  int up_to_date = 0;
  for (std::size_t at = resumed_report.find("up to date ("); at != std::string::npos;
       at = resumed_report.find("up to date (", at + 1))
    ++up_to_date;
  EXPECT_EQ(up_to_date, complete) << resumed_report;
  EXPECT_EQ(Run(batch + whole), 0) << Stderr();
  for (const char* unit : {"PVQ13-0001", "PVQ13-0002", "PVQ13-0003"}) {
    EXPECT_EQ(WithoutDates(Read(fs::path(killed) / unit / "params.yaml")),
              WithoutDates(Read(fs::path(whole) / unit / "params.yaml")))
        << unit;
  }
}

// Two processes, one shard each, one results directory: disjoint, and
// together the fleet (what `--shard {}/2 ::: 0 1` under GNU parallel runs).
TEST_F(BatchCliTest, TwoShardProcessesCoverTheFleet) {
  const std::string results = (dir_ / "results").string();
  const std::string fleet = testing::Source("datasets/fleet");
  const std::string command = std::string(PNEUMAID_CLI) + " batch " + fleet + " --out " + results +
                              " --shard 0/2 > /dev/null 2>&1 & " + PNEUMAID_CLI + " batch " +
                              fleet + " --out " + results + " --shard 1/2 > /dev/null 2>&1; wait";
  std::system(("bash -c '" + command + "'").c_str());
  EXPECT_TRUE(fs::exists(fs::path(results) / "failures.0-of-2.csv"));
  EXPECT_TRUE(fs::exists(fs::path(results) / "failures.1-of-2.csv"));
  EXPECT_EQ(Run("merge " + results), 0) << Stderr();
  EXPECT_NE(Stdout().find("13 units with a parameter set, 1 failed"), std::string::npos)
      << Stdout();
  // Slurm's variables, as `sbatch --array=0-1` sets them.
  EXPECT_EQ(Run("batch " + fleet + " --out " + (dir_ / "slurm").string() + " --shard auto"), 2);
  const std::string slurm =
      "SLURM_ARRAY_TASK_ID=1 SLURM_ARRAY_TASK_MIN=0 "
      "SLURM_ARRAY_TASK_STEP=1 SLURM_ARRAY_TASK_COUNT=2 ";
  std::system(("bash -c '" + slurm + PNEUMAID_CLI + " batch " + fleet + " --out " +
               (dir_ / "slurm").string() + " --shard auto > /dev/null 2>&1'")
                  .c_str());
  EXPECT_TRUE(fs::exists(dir_ / "slurm" / "failures.1-of-2.csv"));
}

// `mpirun -n 2 pneumaid batch --shard auto`: two ranks, two disjoint shards
// from Open MPI's variables, no MPI linked (as root Open MPI wants its two
// ALLOW variables; no ssh here, so the local launcher only).
TEST_F(BatchCliTest, MpirunLaunchesOneShardPerRank) {
  if (std::system("command -v mpirun > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "mpirun not installed (scripts/test.sh installs openmpi-bin)";
  const std::string results = (dir_ / "results").string();
  const std::string command =
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_plm_rsh_agent=false "
      "mpirun -n 2 --oversubscribe " +
      std::string(PNEUMAID_CLI) + " batch " + testing::Source("datasets/fleet") + " --out " +
      results + " --shard auto > " + (dir_ / "mpirun.log").string() + " 2>&1";
  std::system(command.c_str());
  EXPECT_TRUE(fs::exists(fs::path(results) / "summary.0-of-2.csv")) << Read(dir_ / "mpirun.log");
  EXPECT_TRUE(fs::exists(fs::path(results) / "summary.1-of-2.csv"));
  EXPECT_EQ(Run("merge " + results), 0) << Stderr();
  EXPECT_NE(Stdout().find("13 units with a parameter set, 1 failed"), std::string::npos)
      << Stdout();
}

TEST_F(BatchCliTest, ExportsEveryFormatAndRefusesAnUnknownOne) {
  const std::string params = testing::Source("datasets/paper-rig/truth.yaml");
  for (const char* format : {"ros2", "c-header", "matlab", "json"}) {
    const std::string out = (dir_ / (std::string("params.") + format)).string();
    EXPECT_EQ(Run("export --params " + params + " --format " + format + " --out " + out), 0)
        << Stderr();
    EXPECT_NE(Read(out).find("paper-rig"), std::string::npos) << format;  // the unit id
  }
  const auto before = Listing(dir_);
  EXPECT_EQ(
      Run("export --params " + params + " --format fortran --out " + (dir_ / "x.f90").string()), 2);
  EXPECT_NE(Stderr().find("expected ros2, c-header, matlab or json"), std::string::npos);
  // A node name that would not parse as the ROS 2 file's key.
  EXPECT_EQ(Run("export --params " + params + " --format ros2 --node 'bad node: x' --out " +
                (dir_ / "x.yaml").string()),
            2);
  EXPECT_NE(Stderr().find("--node: expected a ROS 2 node name"), std::string::npos) << Stderr();
  // A namespaced node and the wildcard are params files' keys too.
  EXPECT_EQ(Run("export --params " + params + " --format ros2 --node '/**'"), 0) << Stderr();
  EXPECT_EQ(Run("export --params " + params + " --format ros2 --node /arm/actuator"), 0);
  // A node for a format that has none is a mistake, not ignored.
  EXPECT_EQ(Run("export --params " + params + " --format json --node arm --out " +
                (dir_ / "x.json").string()),
            2);
  EXPECT_NE(Stderr().find("--node: names the ROS 2 node, and --format json has none"),
            std::string::npos)
      << Stderr();
  EXPECT_EQ(Listing(dir_), before);
  // The set exported over itself.
  const std::string set = Write("set.yaml", Read(params));
  EXPECT_EQ(Run("export --params " + set + " --format json --out " + set), 2);
  EXPECT_EQ(Read(set), Read(params));
}

}  // namespace
}  // namespace pneumaid
