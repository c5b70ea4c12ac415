// Recovery of the tube lag delta from synthetic step logs with a known truth.
#include "pneumaid/ident/pipeline_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
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
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_NEAR(fit.coefficients.at(0).value, 8.0, 0.05 * 8.0);
  for (const auto& tube : fit.tubes)
    EXPECT_NEAR(tube.delta_per_s(), 8.0, 0.05 * 8.0) << tube.experiment;
  EXPECT_NEAR(fit.law_slope_per_s_m, 0.0, 0.5);  // the truth's law is flat
}

TEST(PipelineFitTest, IgnoringTheOutletMetersDeclaredLagBiasesDeltaLow) {
  Unit unit = ReadUnit(std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig");
  unit.manifest.sensors["q_out"].tau_s.reset();
  const PipelineFitResult fit = FitPipeline(unit, PipelineFitOptions{});
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  // The warning: a 30 ms meter lag left out underestimates delta.
  EXPECT_LT(fit.coefficients.at(0).value, 0.9 * 8.0);
}

TEST(PipelineFitTest, ALagCommonToBothMetersThatIsNotDeclaredIsTakenUpByTheValveLag) {
  Unit unit = ReadUnit(std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig");
  unit.manifest.sensors["q_in"].tau_s.reset();
  unit.manifest.sensors["q_out"].tau_s.reset();
  const PipelineFitResult fit = FitPipeline(unit, PipelineFitOptions{});
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_NEAR(fit.coefficients.at(0).value, 8.0, 0.05 * 8.0);
  for (const auto& tube : fit.tubes) EXPECT_NEAR(tube.valve_lag_s, 0.03, 0.003) << tube.experiment;
}

TEST(PipelineFitTest, StandardErrorsAreHonestOverSeedsAndALengthLawIsFound) {
  Parameters truth;
  truth.pipeline.delta_by_length = {{0.09, 9.0}, {1.2, 6.0}};  // a law that is not flat
  int inside = 0, total = 0;
  double sum_sq = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const PipelineFitResult fit = FitPipeline(SyntheticTubes(truth, seed), PipelineFitOptions{});
    for (const auto& tube : fit.tubes) {
      ASSERT_EQ(tube.status, FitStatus::kConverged) << tube.reason;
      const double w = (tube.tube_length_m - 0.09) / (1.2 - 0.09);
      const double expected = 9.0 + w * (6.0 - 9.0);
      const double z = (tube.delta_per_s() - expected) / tube.delta_standard_error();
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

// Tube tests of other shapes than the synthetic rig's default step, with a
// valve that does not open instantly (a hidden valve lag the fit does not
// model), at low and high sample rates, with deltas far from the prior's.
struct TubeProtocolCase {
  const char* name;
  std::vector<std::pair<double, double>> schedule;
  double rate_Hz, delta_per_s, duration_s;
};

class TubeProtocolTest : public ::testing::TestWithParam<TubeProtocolCase> {};

TEST_P(TubeProtocolTest, DeltaWithinFivePercentWithMismatch) {
  const TubeProtocolCase& c = GetParam();
  Parameters truth;
  truth.pipeline.delta_per_s = c.delta_per_s;
  truth.effects["valve_lag"] = {{"tau", 0.004}};  // not in the fitted model
  Protocol protocol;
  protocol.sample_rate_Hz = c.rate_Hz;
  protocol.tube_lengths_m = {0.38};
  protocol.pipeline_schedule = c.schedule;
  protocol.pipeline_duration_s = c.duration_s;
  protocol.sensors["q_in"] = {2e-7, 0.02, 2e-8, true};
  protocol.sensors["q_out"] = {2e-7, 0.04, 2e-8, true};
  const Unit unit = testing::WriteAndReadUnit(Synthesize(truth, protocol, 5, "P"), c.name);
  PipelineFitOptions options;
  options.initial_delta_per_s = 8.0;  // the paper's, far from most of these
  const PipelineFitResult fit = FitPipeline(unit, options);
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_NEAR(fit.coefficients.at(0).value, c.delta_per_s, 0.05 * c.delta_per_s);
  // The error is honest: the truth lies within 3 standard errors or 1 %.
  EXPECT_LT(std::fabs(fit.coefficients.at(0).value - c.delta_per_s),
            std::max(3 * fit.coefficients.at(0).standard_error, 0.01 * c.delta_per_s));
}

INSTANTIATE_TEST_SUITE_P(
    Shapes, TubeProtocolTest,
    ::testing::Values(TubeProtocolCase{"OnHoldOff", {{0.1, 1.0}, {1.2, 0.0}}, 1000, 3.5, 2.5},
                      TubeProtocolCase{"TwoLevels", {{0.05, 0.4}, {0.7, 1.0}}, 500, 12.0, 1.4},
                      TubeProtocolCase{"StaircaseUpAndDown",
                                       {{0.1, 0.3}, {0.4, 0.7}, {0.7, 1.0}, {1.0, 0.5}, {1.3, 0.0}},
                                       5000,
                                       20.0,
                                       1.6},
                      TubeProtocolCase{"OffStepAtLowRate", {{0.2, 0.8}, {1.0, 0.0}}, 250, 5.0, 2.0},
                      // Logged from the valve's opening: the first sample at
                      // u = 1 with the tube still empty (session 45).
                      TubeProtocolCase{
                          "LoggedFromTheOpening", {{0.0, 1.0}, {0.8, 0.0}}, 1000, 5.0, 1.6}),
    [](const ::testing::TestParamInfo<TubeProtocolCase>& info) { return info.param.name; });

// A tube test logged from the valve's opening: the rows before the step are
// cut, so that the first sample is at u = 1 with the tube still empty. The
// lags start where the meters' first readings say; settled for the first
// level instead, the fit found delta "not determined" (4.36 +- 2.2 for 5)
// and kept the prior's.
TEST(PipelineFitTest, ATubeTestLoggedFromTheValvesOpening) {
  Parameters truth;
  truth.pipeline.delta_per_s = 5.0;
  Protocol protocol;
  protocol.tube_lengths_m = {0.38};
  protocol.pipeline_schedule = {{0.1, 1.0}, {0.9, 0.0}};
  protocol.pipeline_duration_s = 1.6;
  protocol.sensors["q_in"] = {2e-7, 0.02, 2e-8, true};
  protocol.sensors["q_out"] = {2e-7, 0.03, 2e-8, true};
  Unit unit =
      testing::WriteAndReadUnit(Synthesize(truth, protocol, 7, "P"), "pipeline_from_opening");
  for (Experiment& e : unit.experiments) {
    if (e.entry.kind != ExperimentKind::kPipeline) continue;
    const std::vector<double>& u = e.columns.at("u");
    const auto first =
        std::find_if(u.begin(), u.end(), [](double v) { return v > 0.5; }) - u.begin();
    ASSERT_GT(first, 0);
    for (auto& [name, column] : e.columns) column.erase(column.begin(), column.begin() + first);
    EXPECT_LT(e.columns.at("q_out").front(), 0.05 * e.columns.at("q_in").back());  // empty tube
  }
  PipelineFitOptions options;
  options.initial_delta_per_s = 8.0;
  const PipelineFitResult fit = FitPipeline(unit, options);
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_NEAR(fit.coefficients.at(0).value, 5.0, 0.05 * 5.0);
}

// A tube test whose command never holds: a ramp up over 0.7 s in 70 steps of
// 10 ms and down again at 1 kHz, with a hidden valve lag and quantised
// meters of 20 and 40 ms.
Unit RampedTube(double delta_per_s, std::uint64_t seed) {
  Parameters truth;
  truth.pipeline.delta_per_s = delta_per_s;
  truth.effects["valve_lag"] = {{"tau", 0.004}};
  Protocol protocol;
  protocol.tube_lengths_m = {0.38};
  for (int k = 0; k < 70; ++k) protocol.pipeline_schedule.push_back({0.1 + 0.01 * k, 0.014 * k});
  for (int k = 0; k < 70; ++k)
    protocol.pipeline_schedule.push_back({1.0 + 0.01 * k, 0.98 - 0.014 * k});
  protocol.pipeline_duration_s = 2.2;
  protocol.sensors["q_in"] = {2e-7, 0.02, 2e-8, true};
  protocol.sensors["q_out"] = {2e-7, 0.04, 2e-8, true};
  return testing::WriteAndReadUnit(Synthesize(truth, protocol, seed, "P"),
                                   "ramp_" + std::to_string(seed));
}

// Such a log gives no level flows to solve for: delta comes from the two
// meters' readings alone (L_in q_out = L_out L_delta q_in), within 5 % and
// 3 standard errors from 4 to 30 1/s, and over ten seeds the errors are
// honest (z spread 0.5 to 2). Before, such a log was not fitted.
TEST(PipelineFitTest, ACommandThatNeverHoldsIsFittedFromTheMetersAlone) {
  for (const double delta : {4.0, 12.0, 30.0}) {
    const PipelineFitResult fit = FitPipeline(RampedTube(delta, 5), PipelineFitOptions{});
    std::cout << fit.BriefReport();
    ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
    ASSERT_EQ(fit.tubes.size(), 1u);
    EXPECT_GT(fit.tubes[0].levels, PipelineFitOptions{}.max_levels);
    EXPECT_NE(fit.tubes[0].reason.find("not held"), std::string::npos) << fit.tubes[0].reason;
    const FittedCoefficient& c = fit.coefficients.at(0);
    EXPECT_NEAR(c.value, delta, 0.05 * delta);
    EXPECT_LT(std::fabs(c.value - delta), 3 * c.standard_error);
  }
  double sum_sq = 0;
  int inside = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const FittedCoefficient c =
        FitPipeline(RampedTube(12.0, seed), PipelineFitOptions{}).coefficients.at(0);
    const double z = (c.value - 12.0) / c.standard_error;
    sum_sq += z * z;
    inside += std::fabs(z) <= 3;
  }
  const double spread = std::sqrt(sum_sq / 10);
  std::cout << "within 3 SE: " << inside << "/10, z spread " << spread << "\n";
  EXPECT_GE(inside, 9);
  EXPECT_GE(spread, 0.5);
  EXPECT_LE(spread, 2.0);
}

// A logger that stops as the valve is switched off: the command's last level
// is the log's last sample, and no sample tells that level's flow. Its
// column made the joint covariance singular and the tube's delta (8.001 for
// 8) was dropped for the prior; delta's own variance (its Schur complement)
// keeps it, with the error the log without that sample gives.
TEST(PipelineFitTest, ACommandChangedAtTheLogsLastSampleKeepsTheTubesDelta) {
  const Unit unit = ReadUnit(std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig");
  Unit cut = unit;
  for (Experiment& e : cut.experiments) {
    if (e.entry.kind == ExperimentKind::kPipeline) e.columns.at("u").back() = 0.0;
  }
  const PipelineFitResult whole = FitPipeline(unit, PipelineFitOptions{});
  const PipelineFitResult fit = FitPipeline(cut, PipelineFitOptions{});
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.tubes.size(), whole.tubes.size());
  for (std::size_t k = 0; k < fit.tubes.size(); ++k) {
    const TubeFit& tube = fit.tubes[k];
    ASSERT_TRUE(tube.has_values()) << tube.experiment << ": " << tube.reason;
    EXPECT_NEAR(tube.delta_per_s(), 8.0, 0.05 * 8.0) << tube.experiment;
    EXPECT_NEAR(tube.delta_standard_error(), whole.tubes[k].delta_standard_error(),
                0.1 * whole.tubes[k].delta_standard_error())
        << tube.experiment;
  }
}

TEST(PipelineFitTest, ACommandThatNeverChangesSaysWhy) {
  Protocol protocol;
  protocol.tube_lengths_m = {0.38};
  protocol.pipeline_schedule = {{0.0, 1.0}};
  const Unit unit = testing::WriteAndReadUnit(Synthesize(Parameters{}, protocol, 5, "P"), "flat");
  const PipelineFitResult fit = FitPipeline(unit, PipelineFitOptions{});
  EXPECT_EQ(fit.status, FitStatus::kNotFitted);
  EXPECT_FALSE(fit.coefficients.at(0).determined());
  EXPECT_NE(fit.tubes.at(0).reason.find("never changes"), std::string::npos) << fit.tubes[0].reason;
}

// The paper rig's tube log, joined to itself 20 times end to end: at
// each seam the meters' readings jump back to the log's start, which no lag
// of a tube follows. The fit says the model does not explain them, by log
// and reduced chi-square, and still gives its best delta; the logs as
// recorded are explained. (A fleet unit's logs joined so fitted to 4.97e3.)
TEST(PipelineFitTest, ALogTheTubeModelCannotFollowIsNotExplained) {
  Unit unit = ReadUnit(std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig");
  // One tube log is enough (pipe-038).
  unit.experiments.erase(std::remove_if(unit.experiments.begin(), unit.experiments.end(),
                                        [](const Experiment& e) {
                                          return e.entry.kind == ExperimentKind::kPipeline &&
                                                 e.entry.id != "pipe-038";
                                        }),
                         unit.experiments.end());
  const PipelineFitResult recorded = FitPipeline(unit, PipelineFitOptions{});
  ASSERT_EQ(recorded.status, FitStatus::kConverged) << recorded.reason;
  ASSERT_EQ(recorded.tubes.size(), 1u);
  for (Experiment& e : unit.experiments) {
    if (e.entry.kind != ExperimentKind::kPipeline) continue;
    const double span = e.column("t").back() + (e.column("t")[1] - e.column("t")[0]);
    for (auto& [name, column] : e.columns) {
      const std::size_t n = column.size();
      for (int copy = 1; copy < 20; ++copy) {
        for (std::size_t i = 0; i < n; ++i)
          column.push_back(column[i] + (name == "t" ? copy * span : 0.0));
      }
    }
  }
  const PipelineFitResult joined = FitPipeline(unit, PipelineFitOptions{});
  std::cout << joined.BriefReport();
  EXPECT_EQ(joined.status, FitStatus::kNotExplained);
  EXPECT_TRUE(joined.has_values());
  for (const TubeFit& tube : joined.tubes) {
    EXPECT_EQ(tube.status, FitStatus::kNotExplained) << tube.experiment;
    EXPECT_GT(tube.reduced_chi_square, PipelineFitOptions{}.max_reduced_chi_square);
    EXPECT_NE(joined.reason.find(tube.experiment + ": the tube model does not explain"),
              std::string::npos)
        << joined.reason;
  }
  PipelineFitOptions bad;
  bad.max_reduced_chi_square = 0.5;
  std::string error;
  EXPECT_FALSE(bad.IsValid(&error));
  EXPECT_NE(error.find("max_reduced_chi_square"), std::string::npos) << error;
}

}  // namespace
}  // namespace pneumaid
