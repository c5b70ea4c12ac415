// Refinement's robust refit (RefineOptions::robust_refit): when neither the
// fit from the given start nor the screened one explains the runs, one run
// the model cannot follow must not drag the others. Logs written with model
// mismatch (smooth stick, the rig integrated at rtol 1e-8); one stroke run's
// p2 sensor then reads 0.3 bar high, an effect the model does not have.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>

#include "pneumaid/ident/refine.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/synth/synthetic_rig.h"
#include "refine_mismatch_util.h"

namespace pneumaid {
namespace {

const std::string& kDefaultSpec = testing::kDefaultFitSpec;

struct FaultCase {
  Parameters truth;
  Unit unit;
  std::string faulty_run;
};

const FaultCase& OneFaultyRun() {
  static const FaultCase c = [] {
    FaultCase f;
    f.truth = testing::HeavyHorizontalTruth();
    f.unit = testing::MismatchedStrokes(f.truth, 21, "F", "refine_robust_fault");
    for (Experiment& e : f.unit.experiments) {
      if (e.entry.kind != ExperimentKind::kStroke) continue;
      for (double& p : e.columns.at("p2")) p += 0.3e5;
      f.faulty_run = e.entry.id;
      break;
    }
    return f;
  }();
  return c;
}

void ExpectWithinTolerance(const Parameters& fit, const Parameters& truth) {
  testing::ExpectFrictionWithinTolerance(fit, truth);
  EXPECT_NEAR(fit.pipeline.delta_per_s, truth.pipeline.delta_per_s,
              0.05 * truth.pipeline.delta_per_s);
}

// From the true parameters the plain fit is dragged by the faulty run: the
// runs' median ends at 120 (the other two runs' p2 at 223) and the positive
// Fd at its bound (0 for 0.5 N).
// The robust refit follows the two runs the model can follow: explained
// (median 1.6), every coefficient within the tolerance, the faulty
// run named as the worst.
TEST(RefineRobustRefitTest, OneRunTheModelCannotFollowDoesNotDragTheOthers) {
  const FaultCase& c = OneFaultyRun();
  const FitSpec spec = LoadFitSpec(kDefaultSpec);
  RefineOptions options;
  // The attempts before it off: the robust refit on its own.
  options.coordinate_rounds = 0;
  options.stribeck_velocity_divisor = 0;
  const RefineResult result = Refine(c.truth, c.unit, spec, options);
  std::cout << result.BriefReport();
  ASSERT_EQ(result.status, FitStatus::kConverged) << result.reason;
  EXPECT_NE(result.robust_report.find(", kept"), std::string::npos) << result.robust_report;
  EXPECT_EQ(result.robust_report.find("rescue"), std::string::npos) << result.robust_report;
  EXPECT_EQ(result.rescue_starts_tried, 0);
  ExpectWithinTolerance(result.params, c.truth);
  ASSERT_FALSE(result.misfits.empty());
  EXPECT_EQ(result.misfits.front().run, c.faulty_run);
  EXPECT_EQ(result.misfits.front().channel, "p2");

  RefineOptions plain_options = options;
  plain_options.robust_refit = false;
  plain_options.windowed_refit = false;  // the robust refit alone against the plain fit
  plain_options.windowed_polish = false;
  plain_options.rounds = 1;
  const RefineResult plain = Refine(c.truth, c.unit, spec, plain_options);
  std::cout << plain.BriefReport();
  EXPECT_EQ(plain.status, FitStatus::kNotExplained);
  EXPECT_TRUE(plain.robust_report.empty());
  EXPECT_GT(std::fabs(plain.params.friction.positive.dynamic_force_N -
                      c.truth.friction.positive.dynamic_force_N),
            0.1);
}

}  // namespace
}  // namespace pneumaid
