// Recovery of the tube lag delta from synthetic step logs with a known truth.
#include "pneumaid/ident/pipeline_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "../synth/synth_test_util.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid {
namespace {

Unit SyntheticTubes(const Parameters& truth, std::uint64_t seed) {
  Protocol protocol;
  protocol.tube_lengths_m = {0.09, 0.38, 1.2};
  protocol.sensors["q_in"] = {2e-7, 0.03, 0.0, true};
  protocol.sensors["q_out"] = {2e-7, 0.03, 0.0, true};
  return testing::WriteAndReadUnit(Synthesize(truth, protocol, seed, "P"),
                                   "pipeline_fit_" + std::to_string(seed));
}

TEST(PipelineFitTest, RecoversDeltaWithinFivePercentFromAPriorThirtyPercentOff) {
  const Unit unit = ReadUnit(std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig");
  PipelineFitOptions options;
  options.initial_delta_per_s = 8.0 * 1.3;
  const PipelineFitResult fit = FitPipeline(unit, options);
  std::cout << fit.BriefReport();
  ASSERT_TRUE(fit.fitted) << fit.note;
  EXPECT_NEAR(fit.delta_at_rig_per_s, 8.0, 0.05 * 8.0);
  for (const auto& tube : fit.tubes)
    EXPECT_NEAR(tube.delta_per_s, 8.0, 0.05 * 8.0) << tube.experiment;
  EXPECT_NEAR(fit.law_slope_per_s_m, 0.0, 0.5);  // the truth's law is flat
}

TEST(PipelineFitTest, IgnoringTheDeclaredMeterLagBiasesDeltaLow) {
  Unit unit = ReadUnit(std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig");
  unit.manifest.sensors["q_in"].tau_s.reset();
  unit.manifest.sensors["q_out"].tau_s.reset();
  const PipelineFitResult fit = FitPipeline(unit, PipelineFitOptions{});
  ASSERT_TRUE(fit.fitted);
  // The warning: a 30 ms meter lag left out underestimates delta.
  EXPECT_LT(fit.delta_at_rig_per_s, 0.9 * 8.0);
}

TEST(PipelineFitTest, StandardErrorsAreHonestOverSeedsAndALengthLawIsFound) {
  Parameters truth;
  truth.pipeline.delta_by_length = {{0.09, 9.0}, {1.2, 6.0}};  // a law that is not flat
  int inside = 0, total = 0;
  double sum_sq = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const PipelineFitResult fit = FitPipeline(SyntheticTubes(truth, seed), PipelineFitOptions{});
    for (const auto& tube : fit.tubes) {
      ASSERT_TRUE(tube.fitted) << tube.note;
      const double w = (tube.tube_length_m - 0.09) / (1.2 - 0.09);
      const double expected = 9.0 + w * (6.0 - 9.0);
      const double z = (tube.delta_per_s - expected) / tube.delta_standard_error;
      inside += std::fabs(z) <= 3;
      sum_sq += z * z;
      ++total;
    }
    EXPECT_NEAR(fit.law_slope_per_s_m, -3.0 / 1.11, 0.3);
  }
  const double spread = std::sqrt(sum_sq / total);
  std::cout << "within 3 SE: " << inside << "/" << total << ", z spread " << spread << "\n";
  EXPECT_GE(inside, 0.9 * total);
  EXPECT_GE(spread, 0.5);
  EXPECT_LE(spread, 2.0);
}

}  // namespace
}  // namespace pneumaid
