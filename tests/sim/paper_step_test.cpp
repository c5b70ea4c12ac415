// The seed paper's Section 3 step: u = +1 from the retracted end, at rest,
// both chambers at atmosphere. docs/paper-reproduction.md quotes this run.
#include <gtest/gtest.h>

#include "pneumaid/eval/stroke_summary.h"
#include "pneumaid/io/params_yaml.h"
#include "sim_test_util.h"

namespace pneumaid {
namespace {

TEST(PaperStepTest, FullCommandReachesTheFarEndOfTheStroke) {
  for (const char* config : {"paper.yaml", "paper-horizontal.yaml"}) {
    const Parameters p = LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/" + config);
    const Trajectory run = testing::MustSimulate(p, StepCommand({{0.0, 1.0}}), RetractedAtRest(p),
                                                 UniformTimes(0, 1.5, 1000));
    const StrokeSummary summary = SummarizeStroke(run, 0.025);
    std::cout << config << ": " << summary.Describe() << "\n";
    ASSERT_TRUE(summary.mid_stroke_time_s.has_value()) << config;
    ASSERT_TRUE(summary.end_reached_time_s.has_value()) << config;
    EXPECT_LT(*summary.mid_stroke_time_s, *summary.end_reached_time_s);
    EXPECT_LT(*summary.end_reached_time_s, 1.5);
    EXPECT_GT(run.x_m.back(), 0.025 - 1e-4);
    EXPECT_LE(summary.peak_p1_Pa, p.supply.supply_pressure_Pa * 1.001);
  }
}

}  // namespace
}  // namespace pneumaid
