// `pneumaid refine` on the bundled unit: a small spec refines and writes a
// parameter set with uncertainty and provenance; bad input exits 2 and writes
// nothing.
#include <gtest/gtest.h>

#include <filesystem>

#include "cli_test_util.h"

namespace pneumaid {
namespace {

using RefineCliTest = testing::CliTest;

// One short validation run fitted, the other held out: seconds, not minutes.
const char* kSmallSpec = R"(format: pneumaid-fit/1
parameters:
  friction.positive.Fd: {min: 0.01, max: 20}
  friction.negative.Fd: {min: 0.01, max: 20}
experiments: {fit: [step-1], hold_out: [profile-1]}
max_iterations: 10
)";

TEST_F(RefineCliTest, RefinesAndWritesUncertaintyAndProvenance) {
  const std::string spec = Write("small.yaml", kSmallSpec);
  const std::string out = (dir_ / "refined.yaml").string();
  ASSERT_EQ(Run("refine " + testing::Source("datasets/paper-rig") + " --params " +
                testing::Source("configs/paper.yaml") + " --spec " + spec + " --out " + out),
            0)
      << Stdout() << Stderr();
  EXPECT_NE(Stdout().find("held out profile-1"), std::string::npos) << Stdout();
  // Every chamber's RMSE, p2's too (a miss in p2 alone showed nowhere here).
  EXPECT_NE(Stdout().find("p2 RMSE"), std::string::npos) << Stdout();
  const std::string written = Read(out);
  EXPECT_NE(written.find("friction.negative.Fd"), std::string::npos) << written;  // uncertainty
  EXPECT_NE(written.find("refine:"), std::string::npos) << written;               // provenance
  EXPECT_EQ(Run("validate --params " + out + " " + testing::Source("datasets/paper-rig")), 0)
      << Stdout() << Stderr();
}

// --verbose: the solver's progress reaches stdout through the library's log
// sink (the library itself prints nothing); without it, none. The creep fit
// runs by default and not with --no-stick-creep.
TEST_F(RefineCliTest, VerboseShowsTheSolversProgressThroughTheLogSink) {
  const std::string spec = Write("small.yaml", kSmallSpec);
  const std::string out = (dir_ / "refined.yaml").string();
  const std::string command = "refine " + testing::Source("datasets/paper-rig") + " --params " +
                              testing::Source("configs/paper.yaml") + " --spec " + spec +
                              " --out " + out;
  ASSERT_EQ(Run(command + " --verbose"), 0) << Stdout() << Stderr();
  EXPECT_NE(Stdout().find("iteration   1: cost"), std::string::npos) << Stdout();
  EXPECT_NE(Stdout().find("Solver Summary"), std::string::npos) << Stdout();
  EXPECT_NE(Stdout().find("creep fit (effects.stick_creep.v)"), std::string::npos) << Stdout();
  std::filesystem::remove(out);
  // --no-stick-creep: the spec's model only.
  ASSERT_EQ(Run(command + " --no-stick-creep"), 0) << Stdout() << Stderr();
  EXPECT_EQ(Stdout().find("iteration   1: cost"), std::string::npos) << Stdout();
  EXPECT_EQ(Stdout().find("creep fit"), std::string::npos) << Stdout();
}

TEST_F(RefineCliTest, IdentifyRefineRunsTheComponentFitsThenTheRefinement) {
  const std::string spec = Write("small.yaml", kSmallSpec);
  const std::string out = (dir_ / "identified.yaml").string();
  const std::string html = (dir_ / "identified.html").string();
  ASSERT_EQ(Run("identify " + testing::Source("datasets/paper-rig") + " --refine --spec " + spec +
                " --out " + out + " --html " + html),
            0)
      << Stdout() << Stderr();
  EXPECT_NE(Stdout().find("From the prior"), std::string::npos) << Stdout();  // identify's report
  EXPECT_NE(Stdout().find("Refinement: converged"), std::string::npos) << Stdout();
  // The page of the refined set carries both reports.
  const std::string page = Read(html);
  EXPECT_NE(page.find("From the prior"), std::string::npos);
  EXPECT_NE(page.find("Refinement: converged"), std::string::npos);
  const std::string written = Read(out);
  EXPECT_NE(written.find("friction:"), std::string::npos) << written;  // identify's provenance
  EXPECT_NE(written.find("refine:"), std::string::npos) << written;
}

// A refinement the model cannot win (the tube's delta held to a tenth of
// the rig's by its bounds): exit 3, "the model does not explain these logs",
// and the start's set written with the refined value in its provenance, and
// the next step named (diagnose, from the set written).
TEST_F(RefineCliTest, WhereTheModelDoesNotExplainTheLogsTheStartIsWrittenAndDiagnoseNamed) {
  std::string paper = Read(testing::Source("configs/paper.yaml"));
  paper.replace(paper.find("delta: 8.0"), 10, "delta: 0.8");
  const std::string start = Write("slow-tube.yaml", paper);
  const std::string spec = Write("tube.yaml", R"(format: pneumaid-fit/1
parameters:
  pipeline.delta: {min: 0.5, max: 1}
experiments: {fit: [step-1], hold_out: [profile-1]}
max_iterations: 10
)");
  const std::string out = (dir_ / "refined.yaml").string();
  const std::string unit = testing::Source("datasets/paper-rig");
  ASSERT_EQ(Run("refine " + unit + " --params " + start + " --spec " + spec + " --out " + out +
                " --no-stick-creep"),
            3)
      << Stdout() << Stderr();
  EXPECT_NE(Stderr().find("the model does not explain these logs"), std::string::npos);
  // So far above the threshold that no second round is run (out_of_reach_ratio).
  EXPECT_NE((Stdout() + Stderr()).find("round 2: not run, the first round ends"), std::string::npos)
      << Stdout() << Stderr();
  EXPECT_NE(Stderr().find("the start's coefficients are written"), std::string::npos) << Stderr();
  EXPECT_NE(Stderr().find("next: pneumaid diagnose " + unit + " --params " + out),
            std::string::npos)
      << Stderr();
  const std::string written = Read(out);
  EXPECT_NE(written.find("delta: 0.8\n"), std::string::npos) << written;
  EXPECT_NE(written.find("refine_not_written: {"), std::string::npos) << written;
  EXPECT_NE(written.find("refined: {pipeline.delta: "), std::string::npos) << written;
}

TEST_F(RefineCliTest, BadInputExitsTwoAndWritesNothing) {
  const std::string out = (dir_ / "refined.yaml").string();
  const std::string unit = testing::Source("datasets/paper-rig");
  const std::string params = " --params " + testing::Source("configs/paper.yaml");
  const std::string typo = Write("typo.yaml", std::string(kSmallSpec) + "multistrat: 2\n");
  EXPECT_EQ(Run("refine " + unit + params + " --spec " + typo + " --out " + out), 2);
  EXPECT_NE(Stderr().find("typo.yaml:7"), std::string::npos) << Stderr();
  EXPECT_NE(Stderr().find("multistrat"), std::string::npos) << Stderr();
  std::string missing = kSmallSpec;
  missing.replace(missing.find("step-1"), 6, "step-9");
  const std::string unknown = Write("unknown.yaml", missing);
  EXPECT_EQ(Run("refine " + unit + params + " --spec " + unknown + " --out " + out), 2);
  EXPECT_NE(Stderr().find("step-9"), std::string::npos) << Stderr();
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace pneumaid
