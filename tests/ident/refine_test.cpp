// Refinement on synthetic units with known truth: recovery from trajectories
// alone, repair of biased component fits, refusal of specs that do not fit the
// unit, and multistart.
#include "pneumaid/ident/refine.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <atomic>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "../../src/ident/refine_residual.h"
#include "../synth/synth_test_util.h"
#include "pneumaid/ident/identify.h"
#include "pneumaid/io/channel_noise.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/provenance.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/validate/logged_run.h"
#include "pneumaid/validate/validate.h"
#include "refine_mismatch_util.h"

namespace pneumaid {
namespace {

const std::string& kDefaultSpec = testing::kDefaultFitSpec;
const std::string kFromScratchSpec =
    std::string(PNEUMAID_SOURCE_DIR) + "/configs/fit-from-scratch.yaml";

// The issue's tolerances: Fs, Fd 5 % or 0.1 N; b 15 % or 0.5 N s/m; vs 25 %
// or 1 mm/s; delta and q_max 5 %.
double Tolerance(const std::string& path, double truth) {
  const auto ends = [&path](const char* suffix) {
    return path.size() >= std::strlen(suffix) &&
           path.compare(path.size() - std::strlen(suffix), std::string::npos, suffix) == 0;
  };
  if (ends(".Fs") || ends(".Fd")) return std::max(0.05 * truth, 0.1);
  if (ends(".b")) return std::max(0.15 * truth, 0.5);
  if (ends(".vs")) return std::max(0.25 * truth, 1e-3);
  return 0.05 * truth;
}

// Converged, every free parameter within the issue's tolerance of the truth,
// each with a standard error.
void ExpectRecovered(const RefineResult& result, const Parameters& truth, const FitSpec& spec) {
  std::cout << result.BriefReport();
  ASSERT_EQ(result.status, FitStatus::kConverged) << result.reason;
  for (const FreeParameter& free : spec.parameters) {
    const double exact = testing::ParameterValue(truth, free.path);
    EXPECT_NEAR(testing::ParameterValue(result.params, free.path), exact,
                Tolerance(free.path, exact))
        << free.path;
    EXPECT_GT(result.params.uncertainty.count(free.path), 0u) << free.path;
  }
}

// (refined - truth) / reported standard error of every free parameter.
std::vector<double> ZScores(const RefineResult& result, const Parameters& truth,
                            const FitSpec& spec) {
  std::vector<double> z;
  for (const FreeParameter& free : spec.parameters) {
    const double error = result.params.uncertainty.at(free.path);
    z.push_back((testing::ParameterValue(result.params, free.path) -
                 testing::ParameterValue(truth, free.path)) /
                error);
    std::cout << "  z " << free.path << " " << z.back() << "\n";
  }
  return z;
}

// Honest standard errors: at least 9 of 10 parameters within 3 of them of the
// truth (too small errors fail), and not all within a tenth of one (errors
// inflated out of use fail).
void ExpectHonestErrors(const RefineResult& result, const Parameters& truth, const FitSpec& spec) {
  const std::vector<double> z = ZScores(result, truth, spec);
  const auto within = [&z](double bound) {
    return std::count_if(z.begin(), z.end(), [bound](double v) { return std::fabs(v) <= bound; });
  };
  EXPECT_GE(within(3.0), static_cast<long>(z.size()) - 1);
  EXPECT_LT(within(0.1), static_cast<long>(z.size()));
}

// From the stroke trajectories alone (the unit has no bench logs), starting
// 30 % off the truth on all ten parameters of fit-from-scratch.yaml.
TEST(RefineTest, RecoversTenParametersFromTrajectoriesAloneStartingThirtyPercentOff) {
  const Parameters truth;
  const Unit unit = testing::WriteAndReadUnit(
      Synthesize(truth, testing::RefinementProtocol({0.6, 0.8, 1.0}, false), 31, "R"),
      "refine_from_scratch");
  const FitSpec spec = LoadFitSpec(kFromScratchSpec);
  Parameters start = truth;
  for (size_t j = 0; j < spec.parameters.size(); ++j) {
    const std::string& path = spec.parameters[j].path;
    SetParameter(&start, path, testing::ParameterValue(truth, path) * (j % 2 == 0 ? 1.3 : 0.7));
  }
  const RefineResult result = Refine(start, unit, spec, RefineOptions{});
  ExpectRecovered(result, truth, spec);
  ExpectHonestErrors(result, truth, spec);
  EXPECT_LT(result.final_cost, 1e-4 * result.initial_cost);
}

// From the component fits (valve and tube bench logs, friction from the
// stroke logs) fit-default.yaml recovers the ten parameters and halves the
// held-out position error.
TEST(RefineTest, RecoversTheTenDefaultParametersFromTheComponentFits) {
  const Parameters truth;
  const Unit unit = testing::WriteAndReadUnit(
      Synthesize(truth, testing::RefinementProtocol({0.6, 0.8, 1.0}, true), 31, "R"),
      "refine_recovery");
  IdentifyReport report;
  const Parameters start = Identify(unit, Parameters{}, IdentifyOptions{}, &report);
  const FitSpec spec = LoadFitSpec(kDefaultSpec);
  const RefineResult result = Refine(start, unit, spec, RefineOptions{});
  ExpectRecovered(result, truth, spec);
  ExpectHonestErrors(result, truth, spec);
  // Near the noise floor: chi^2 per residual below 2 (the position sensor's
  // 10 um quantisation adds a third to its declared 5 um noise).
  long residuals = 0;
  for (const ExperimentCost& e : result.fitted) residuals += e.residuals;
  EXPECT_LT(2.0 * result.final_cost, 2.0 * static_cast<double>(residuals));
  // The held-out position error of the paper's step is what a correct model
  // gives (issue 12's rule: at most twice the truth's plus 0.05 mm). The
  // profile's marginal stick-slip makes its error a poor judge of parameters
  // within tolerance: the truth with only the negative vs 1.8 % lower (as
  // refined here) gives 71 um instead of 6 um; it must improve on the start.
  ValidationOptions at_truth;
  at_truth.experiment_ids = {"step-1", "profile-1"};
  const ValidationReport truth_report = ValidateUnit(truth, unit, at_truth);
  ASSERT_EQ(result.held_out_after.experiments.size(), 2u);  // step-1, profile-1
  const auto x_rmse = [](const ValidationReport& report, std::size_t i) {
    return report.experiments[i].channels.at("x").rmse;
  };
  EXPECT_LE(x_rmse(result.held_out_after, 0), 2 * x_rmse(truth_report, 0) + 0.05e-3);
  for (size_t i = 0; i < 2; ++i)
    EXPECT_LT(x_rmse(result.held_out_after, i), x_rmse(result.held_out_before, i));
}

// Issue 4's horizontal unit, whose negative-direction Fd and b the friction
// component fit gets about two standard errors off (friction_fit_test):
// identify followed by the default refinement brings every friction
// coefficient of both directions within the issue's tolerances.
TEST(RefineTest, TheDefaultRefinementRecoversAHorizontalCylindersFriction) {
  Parameters truth =
      LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper-horizontal.yaml");
  truth.friction.positive = {8.0, 1.5, 4.0, 0.015};
  truth.friction.negative = {12.0, 3.0, 7.0, 0.008};
  const Unit unit = testing::WriteAndReadUnit(
      Synthesize(truth, testing::RefinementProtocol({0.45, 0.6, 0.8, 1.0}, true), 22, "H"),
      "refine_horizontal");
  IdentifyReport report;
  const Parameters identified = Identify(unit, truth, IdentifyOptions{}, &report);
  const FitSpec spec = LoadFitSpec(kDefaultSpec);
  const RefineResult result = Refine(identified, unit, spec, RefineOptions{});
  ExpectRecovered(result, truth, spec);
  // The runs' starts are estimated (initial_pressures: fit): taken as logged,
  // the 40 Pa error of a logged start, amplified by stick-slip, was absorbed
  // by the parameters and the held-out profile got worse (x RMSE 0.10 ->
  // 0.15 mm; with the starts estimated 0.03 mm).
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_LT(result.held_out_after.experiments[i].channels.at("x").rmse,
              0.5 * result.held_out_before.experiments[i].channels.at("x").rmse);
  }
  // No ExpectHonestErrors here: fitted at rtol 1e-5 against logs simulated
  // at 1e-6, this unit's stick-slip turns the integrators' difference into a
  // misfit that pulls delta, q_max and negative Fd 2.8 to 3.9 standard
  // errors off (fitted at 1e-6, all ten stay within 2.3).
}

// pneumaid-rig/1 makes `sensors` optional: a rig that declares its meters'
// lags but no noise is identified and refined with the noise of its own logs
// (before, the refinement refused the unit: "no sigma given"). Written with
// model mismatch (smooth stick, the rig at rtol 1e-8) and the protocol's 10 um
// ADC step on 5 um of position noise. The estimates are what the rig's
// instruments put on the readings; the fits recover the truth as with the
// noise declared, and both reports name what was estimated.
TEST(RefineTest, AUnitThatDeclaresNoNoiseIsFittedWithTheNoiseOfItsOwnLogs) {
  Parameters truth =
      LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper-horizontal.yaml");
  truth.friction.positive = {8.0, 1.5, 4.0, 0.015};
  truth.friction.negative = {12.0, 3.0, 7.0, 0.008};
  Protocol protocol = testing::RefinementProtocol({0.45, 0.6, 0.8, 1.0}, true);
  protocol.mismatch.regularized_friction = true;
  protocol.mismatch.stick_velocity_m_per_s = 1e-4;
  protocol.mismatch.relative_tolerance = 1e-8;
  Unit unit = testing::WriteAndReadUnit(Synthesize(truth, protocol, 23, "N"), "refine_no_noise");
  for (auto& [column, sensor] : unit.manifest.sensors) sensor.sigma.reset();
  for (const std::string column : {"x", "p1", "p2", "q", "q_in", "q_out"}) {
    const SensorModel& rig = protocol.sensors.at(column);
    // A flow meter's noise is declared in standard volume flow; read as mass.
    const double to_si = column[0] == 'q' ? unit.manifest.rig.air_density_kg_per_m3 : 1.0;
    const double off = to_si * std::hypot(rig.sigma, rig.quantization / std::sqrt(12.0));
    const ChannelNoise noise = NoiseOf(unit, column);
    EXPECT_FALSE(noise.declared) << column;
    EXPECT_NEAR(noise.sigma, off, 0.15 * off) << column;
  }
  IdentifyReport report;
  const Parameters identified = Identify(unit, truth, IdentifyOptions{}, &report);
  EXPECT_EQ(report.noise_note.rfind("noise not declared, estimated from the logs: x ", 0), 0u)
      << report.noise_note;
  const FitSpec spec = LoadFitSpec(kDefaultSpec);
  const RefineResult result = Refine(identified, unit, spec, RefineOptions{});
  ExpectRecovered(result, truth, spec);
  EXPECT_NE(result.noise_note.find("p1 "), std::string::npos) << result.noise_note;
  EXPECT_NE(result.BriefReport().find(result.noise_note), std::string::npos);
  EXPECT_TRUE(result.explained());
}

// Component fits made blind to the outlet flow meters' 30 ms lag (not declared
// in the manifest; the inlet meter's is: a lag common to both would be taken
// up by the tube fit's valve lag) and to most of the position accuracy (50 um
// noise: the friction fit's negative direction lands far off). Refinement
// still roughly halves the held-out position error, but it stalls far above
// what the noise explains, and the trust-box starts find no better basin: the
// verdict must say so (issue 12: never "converged" two orders of magnitude
// above the threshold), with the worst runs and channels.
TEST(RefineTest, FromBiasedComponentFitsItSaysWhenTheRunsAreNotExplained) {
  const Parameters truth;
  Protocol protocol = testing::RefinementProtocol({0.6, 0.8, 1.0}, true);
  for (const char* flow : {"q", "q_out", "q1", "q2"}) protocol.sensors[flow].declared = false;
  protocol.sensors["x"].sigma = 50e-6;
  const Unit unit =
      testing::WriteAndReadUnit(Synthesize(truth, protocol, 32, "B"), "refine_biased");
  IdentifyReport report;
  const Parameters identified = Identify(unit, Parameters{}, IdentifyOptions{}, &report);
  RefineOptions options;  // one round, no polish: the verdict under test
  options.windowed_polish = false;
  options.rounds = 1;
  const RefineResult result = Refine(identified, unit, LoadFitSpec(kDefaultSpec), options);
  std::cout << report.BriefReport() << result.BriefReport();
  ASSERT_TRUE(result.has_values()) << result.reason;
  if (result.reduced_chi_square <= result.acceptable_reduced_chi_square) {
    EXPECT_EQ(result.status, FitStatus::kConverged);
  } else {
    EXPECT_EQ(result.status, FitStatus::kNotExplained);
    EXPECT_NE(result.status, FitStatus::kConverged);
    EXPECT_GT(result.rescue_starts_tried, 0);
    EXPECT_NE(result.reason.find("does not explain these logs"), std::string::npos);
    EXPECT_NE(result.reason.find(result.misfits.front().run), std::string::npos);
    EXPECT_NE(result.params.provenance_yaml.find("status: the model does not explain"),
              std::string::npos);
  }
  ASSERT_EQ(result.held_out_before.experiments.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const double before = result.held_out_before.experiments[i].channels.at("x").rmse;
    const double after = result.held_out_after.experiments[i].channels.at("x").rmse;
    EXPECT_LE(after, 0.5 * before) << result.held_out_after.experiments[i].id;
  }
}

// Transducers with a lag of their own, declared in the manifest (5 ms on
// the pressures, 2 ms on the position): the refinement and validation pass
// each simulated channel through its declared lag, so at the truth the runs
// are explained and the pressures' validation error is the noise's. Before,
// only the flows' lags were applied: at the truth a rise of 1e6 Pa/s seen
// 5 ms late left the pressures far outside their noise.
TEST(RefineTest, DeclaredTransducerLagsAreAppliedToEveryChannel) {
  const Parameters truth;
  Protocol protocol = testing::RefinementProtocol({0.7, 1.0}, false);
  protocol.sensors["p1"].tau_s = protocol.sensors["p2"].tau_s = 0.005;
  protocol.sensors["x"].tau_s = 0.002;
  const Unit unit =
      testing::WriteAndReadUnit(Synthesize(truth, protocol, 36, "T"), "refine_transducer_lag");
  ASSERT_EQ(unit.manifest.DeclaredTau("p1", 0.0), 0.005);
  const RefineResult at_truth =
      EvaluateFit(truth, unit, LoadFitSpec(kDefaultSpec), RefineOptions{});
  std::cout << at_truth.BriefReport();
  EXPECT_EQ(at_truth.status, FitStatus::kConverged) << at_truth.reason;
  EXPECT_LT(at_truth.reduced_chi_square, 3.0);
  const ValidationReport report = ValidateUnit(truth, unit, ValidationOptions{});
  for (const auto& run : report.experiments) {
    EXPECT_LT(run.channels.at("p1").rmse, 3 * 300.0) << run.id;
    EXPECT_LT(run.channels.at("x").rmse, 20e-6) << run.id;
  }
}

// The verdict itself: at the truth on a unit the model made (up to the
// integration tolerance) the runs' median reduced chi-square is near 1 and
// they are explained; with a hidden cross leakage the fitted model lacks, the
// same refinement ends far above and says the model does not explain them.
TEST(RefineTest, TheVerdictTellsAnExplainedUnitFromOneWithAMissingEffect) {
  const Parameters truth;
  const Unit unit = testing::WriteAndReadUnit(
      Synthesize(truth, testing::RefinementProtocol({0.7, 1.0}, false), 35, "V"), "refine_verdict");
  RefineOptions options;
  options.rescue_starts = 2;
  // One round, no polish: the verdict under test (the later attempts are
  // tested in refine_windowed_refit_test.cpp).
  options.windowed_polish = false;
  options.rounds = 1;
  const RefineResult explained = Refine(truth, unit, LoadFitSpec(kDefaultSpec), options);
  std::cout << explained.BriefReport();
  EXPECT_EQ(explained.status, FitStatus::kConverged) << explained.reason;
  EXPECT_LT(explained.reduced_chi_square, 3.0);
  // The same verdict without a fit (EvaluateFit), at the truth.
  const RefineResult at_truth = EvaluateFit(truth, unit, LoadFitSpec(kDefaultSpec), options);
  EXPECT_EQ(at_truth.status, FitStatus::kConverged) << at_truth.reason;
  EXPECT_LT(at_truth.reduced_chi_square, 3.0);
  Parameters leaky = truth;
  leaky.effects["cross_leakage"] = {{"c", 2e-11}};  // 8e-6 kg/s at 4 bar: 9 % of q_max
  const Unit leaking = testing::WriteAndReadUnit(
      Synthesize(leaky, testing::RefinementProtocol({0.7, 1.0}, false), 35, "L"),
      "refine_verdict_leak");
  const RefineResult missing = Refine(truth, leaking, LoadFitSpec(kDefaultSpec), options);
  std::cout << missing.BriefReport();
  EXPECT_EQ(missing.status, FitStatus::kNotExplained);
  EXPECT_EQ(EvaluateFit(truth, leaking, LoadFitSpec(kDefaultSpec), options).status,
            FitStatus::kNotExplained);
  EXPECT_GT(missing.reduced_chi_square, missing.acceptable_reduced_chi_square);
  EXPECT_EQ(missing.rescue_starts_tried, 2);  // the trust box's two
  // The default options write the refined set, whatever the verdict.
  EXPECT_FALSE(missing.start_written);
  for (const FittedCoefficient& c : missing.coefficients)
    EXPECT_EQ(testing::ParameterValue(missing.params, c.path), c.value) << c.path;
}

// A unit whose rig's chambers exchange heat with their walls (heat_transfer,
// h 0.2 W/K; the model is adiabatic) and whose rod creeps at its stick, and
// its component fits: the refinement cannot explain the strokes.
class RefineHeatTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    Parameters* truth = new Parameters;
    truth->effects["heat_transfer"] = {{"h", 0.2}};
    truth_ = truth;
    Protocol protocol = testing::RefinementProtocol({0.5, 0.8}, true);
    protocol.mismatch.regularized_friction = true;
    protocol.mismatch.stick_velocity_m_per_s = 1e-4;
    protocol.mismatch.relative_tolerance = 1e-8;
    unit_ =
        new Unit(testing::WriteAndReadUnit(Synthesize(*truth_, protocol, 53, "H"), "refine_heat"));
    IdentifyReport report;
    identified_ = new Parameters(Identify(*unit_, Parameters{}, IdentifyOptions{}, &report));
    std::cout << report.BriefReport();
  }
  static void TearDownTestSuite() {
    delete truth_;
    delete unit_;
    delete identified_;
  }
  // ForIdentify's options with the attempts to explain the runs cut to the
  // fit from the start: what they do with its result is under test.
  static RefineOptions FewAttempts() {
    RefineOptions options = RefineOptions::ForIdentify();
    options.windowed_polish = false;
    options.screen_friction_windows = false;
    options.screened_alternatives = 0;
    options.coordinate_rounds = 0;
    options.stribeck_velocity_divisor = 0;
    options.rescue_starts = 0;
    return options;
  }
  static const Parameters* truth_;
  static const Unit* unit_;
  static const Parameters* identified_;
};
const Parameters* RefineHeatTest::truth_ = nullptr;
const Unit* RefineHeatTest::unit_ = nullptr;
const Parameters* RefineHeatTest::identified_ = nullptr;

// From the component fits the refined coefficients absorb the heat exchange
// (friction at or near its bounds). identify's options write the start, the
// component fits, with the verdict and the refined values in the provenance;
// the refined set is the further from the truth. Without the option
// (diagnose's fits) the same fit writes the refined set.
TEST_F(RefineHeatTest, WhereTheModelDoesNotExplainTheLogsTheComponentFitsAreWritten) {
  const Parameters& truth = *truth_;
  const Unit& unit = *unit_;
  const Parameters& identified = *identified_;
  RefineOptions options = FewAttempts();
  // The written set under test: one round, the creep fit run however far
  // the fit ends above the threshold.
  options.rounds = 1;
  options.out_of_reach_ratio = 0;
  ASSERT_TRUE(options.write_start_unless_explained);
  const FitSpec spec = LoadFitSpec(kDefaultSpec);
  const RefineResult written = Refine(identified, unit, spec, options);
  std::cout << written.BriefReport();
  ASSERT_EQ(written.status, FitStatus::kNotExplained) << written.reason;
  EXPECT_TRUE(written.start_written);
  // How far a set's friction is from the truth: the sum of the relative
  // errors of its eight coefficients.
  const auto friction_error = [&truth](const Parameters& p) {
    double sum = 0;
    for (const char* path : {"friction.positive.Fs", "friction.positive.Fd", "friction.positive.b",
                             "friction.positive.vs", "friction.negative.Fs", "friction.negative.Fd",
                             "friction.negative.b", "friction.negative.vs"}) {
      const double t = testing::ParameterValue(truth, path);
      sum += std::fabs(testing::ParameterValue(p, path) / t - 1);
    }
    return sum;
  };
  Parameters refined = written.params;
  written.ApplyTo(&refined);
  for (const FittedCoefficient& c : written.coefficients) {
    EXPECT_EQ(testing::ParameterValue(written.params, c.path),
              testing::ParameterValue(identified, c.path))
        << c.path;
  }
  EXPECT_LT(friction_error(written.params), 0.5 * friction_error(refined));
  // The provenance says which set was written and keeps the refined values.
  const YAML::Node provenance = YAML::Load(written.params.provenance_yaml);
  const YAML::Node entry = provenance["refine_not_written"];
  ASSERT_TRUE(entry.IsMap()) << written.params.provenance_yaml;
  for (const FittedCoefficient& c : written.coefficients)
    EXPECT_DOUBLE_EQ(entry["refined"][c.path].as<double>(), c.value) << c.path;
  EXPECT_EQ(entry["status"].as<std::string>(), ToString(FitStatus::kNotExplained));
  // The start's own words on its values stay (identify's entries), and no
  // `refine` entry claims the written values were refined.
  EXPECT_FALSE(provenance["refine"]) << written.params.provenance_yaml;
  EXPECT_TRUE(provenance["friction"]) << written.params.provenance_yaml;
  // The whole set is identify's under the unit's conditions: errors and
  // effects too (no creep speed the creep fit may have found).
  const Parameters conditioned = WithRigConditions(identified, unit);
  EXPECT_EQ(written.params.uncertainty, conditioned.uncertainty);
  EXPECT_EQ(written.params.effects, conditioned.effects);
  EXPECT_NE(written.BriefReport().find("written: the start's coefficients"), std::string::npos);
  // The held-out runs are reported as validated with what is written.
  const ValidationReport held_out = ValidateUnit(written.params, unit, ValidationOptions{});
  ASSERT_EQ(written.held_out_after.experiments.size(), held_out.experiments.size());
  for (std::size_t i = 0; i < held_out.experiments.size(); ++i) {
    EXPECT_NEAR(written.held_out_after.experiments[i].channels.at("x").rmse,
                held_out.experiments[i].channels.at("x").rmse, 1e-9);
  }
  // The option changes what is written, not the fit: the creep fit's inner
  // fits are compared as refined (they had written their starts).
  options.write_start_unless_explained = false;
  const RefineResult refined_written = Refine(identified, unit, spec, options);
  EXPECT_FALSE(refined_written.start_written);
  ASSERT_NE(written.creep_report.find("v held at"), std::string::npos) << written.creep_report;
  EXPECT_EQ(refined_written.creep_report, written.creep_report);
  ASSERT_EQ(refined_written.coefficients.size(), written.coefficients.size());
  for (std::size_t i = 0; i < written.coefficients.size(); ++i) {
    const FittedCoefficient& c = refined_written.coefficients[i];
    EXPECT_EQ(c.value, written.coefficients[i].value) << c.path;
    EXPECT_EQ(testing::ParameterValue(refined_written.params, c.path), c.value) << c.path;
  }
}

// A first round far above the threshold (out_of_reach_ratio, 100 by
// ForIdentify) ends the refinement: no second round, no creep fit, each
// report saying why; the start is written as after any fit not explained.
TEST_F(RefineHeatTest, AFitFarAboveTheThresholdRunsNoLaterRoundNorTheCreepFit) {
  RefineOptions options = FewAttempts();
  ASSERT_EQ(options.rounds, 2);
  ASSERT_TRUE(options.fit_stick_creep);
  ASSERT_EQ(options.out_of_reach_ratio, 100);
  const FitSpec spec = LoadFitSpec(kDefaultSpec);
  const RefineResult far = Refine(*identified_, *unit_, spec, options);
  std::cout << far.BriefReport();
  ASSERT_EQ(far.status, FitStatus::kNotExplained) << far.reason;
  ASSERT_GT(far.reduced_chi_square, 100 * options.acceptable_reduced_chi_square);
  EXPECT_EQ(far.rounds_report.rfind("round 2: not run, the first round ends", 0), 0u)
      << far.rounds_report;
  EXPECT_NE(far.creep_report.find(": not run, the first round ends"), std::string::npos)
      << far.creep_report;
  EXPECT_TRUE(far.start_written);
  // The provenance says why the creep fit did not run.
  const YAML::Node provenance = YAML::Load(far.params.provenance_yaml);
  EXPECT_EQ(provenance["refine_not_written"]["creep_fit"].as<std::string>(""), far.creep_report)
      << far.params.provenance_yaml;
  // The verdict is the first round's: one round without the creep fit ends
  // the same.
  RefineOptions one = options;
  one.rounds = 1;
  one.fit_stick_creep = false;
  const RefineResult first = Refine(*identified_, *unit_, spec, one);
  EXPECT_EQ(first.reduced_chi_square, far.reduced_chi_square);
  EXPECT_TRUE(first.rounds_report.empty()) << first.rounds_report;
  EXPECT_TRUE(first.creep_report.empty()) << first.creep_report;
  // The second round runs with the ratio just above where the first round
  // ends, and where the refined set is written whatever the verdict (the
  // rule's premise: such a set would not be written).
  RefineOptions near = options;
  near.fit_stick_creep = false;
  near.out_of_reach_ratio = 1.01 * far.reduced_chi_square / options.acceptable_reduced_chi_square;
  RefineOptions refined_written = options;
  refined_written.fit_stick_creep = false;
  refined_written.write_start_unless_explained = false;
  for (const RefineOptions& runs : {near, refined_written}) {
    const RefineResult again = Refine(*identified_, *unit_, spec, runs);
    EXPECT_EQ(again.rounds_report.rfind("round 2 (", 0), 0u) << again.rounds_report;
    EXPECT_LE(again.reduced_chi_square, far.reduced_chi_square);
  }
}

class RefineSpecTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    unit_ = new Unit(testing::WriteAndReadUnit(
        Synthesize(Parameters{}, testing::RefinementProtocol({1.0}, false), 33, "S"),
        "refine_spec"));
  }
  static void TearDownTestSuite() { delete unit_; }

  // Two free parameters on the one stroke log: a small, fast problem.
  static FitSpec TwoParameters() {
    return ParseFitSpec(R"(format: pneumaid-fit/1
parameters:
  friction.positive.Fd: {min: 0.05, max: 5}
  friction.negative.Fd: {min: 0.5, max: 20}
experiments: {fit: [stroke-100], hold_out: []}
)",
                        "two.yaml");
  }

  static Unit* unit_;
};
Unit* RefineSpecTest::unit_ = nullptr;

TEST_F(RefineSpecTest, MultistartKeepsTheBestOfItsSeededLatinHypercubeStarts) {
  Parameters start;
  start.friction.positive.dynamic_force_N *= 1.05;
  start.friction.negative.dynamic_force_N *= 0.95;
  const RefineResult single = Refine(start, *unit_, TwoParameters(), RefineOptions{});
  FitSpec spec = TwoParameters();
  spec.multistart = 3;
  spec.max_iterations = 12;  // per start: enough to tell the starts apart
  const RefineResult multi = Refine(start, *unit_, spec, RefineOptions{});
  const RefineResult again = Refine(start, *unit_, spec, RefineOptions{});
  std::cout << single.BriefReport() << multi.BriefReport();
  EXPECT_EQ(single.starts, 1);
  EXPECT_EQ(multi.starts, 4);
  ASSERT_EQ(multi.status, FitStatus::kConverged) << multi.reason;
  EXPECT_LE(multi.final_cost, single.final_cost * (1 + 1e-9));
  EXPECT_EQ(multi.best_start, again.best_start);  // seeded: the same starts
  EXPECT_EQ(multi.params.friction.negative.dynamic_force_N,
            again.params.friction.negative.dynamic_force_N);
  EXPECT_NEAR(single.params.friction.positive.dynamic_force_N, 0.5, 0.1);
  EXPECT_NEAR(single.params.friction.negative.dynamic_force_N, 5.0, 0.25);
  for (const FittedCoefficient& p : multi.coefficients) EXPECT_GT(p.standard_error, 0) << p.path;
}

// A coefficient the runs push past its range ends on the bound: fitted, but
// with no standard error, so no `uncertainty` entry, and named in the
// provenance's refine.at_bound (the report's "fitted, at a bound"); the
// other coefficient keeps its error and is not named.
TEST_F(RefineSpecTest, ACoefficientOnItsBoundIsNamedInTheProvenance) {
  FitSpec spec = TwoParameters();
  spec.parameters[0].lower = 1.0;  // positive Fd: the truth's 0.5 lies below
  Parameters start;
  start.friction.positive.dynamic_force_N = 1.5;
  const RefineResult result = Refine(start, *unit_, spec, RefineOptions{});
  std::cout << result.BriefReport();
  ASSERT_TRUE(result.has_values()) << result.reason;
  EXPECT_NEAR(result.params.friction.positive.dynamic_force_N, 1.0, 1e-6);
  EXPECT_EQ(ProvenanceList(result.params.provenance_yaml, "refine", "at_bound"),
            std::vector<std::string>{"friction.positive.Fd"});
  EXPECT_EQ(result.params.uncertainty.count("friction.positive.Fd"), 0u);
  EXPECT_EQ(result.params.uncertainty.count("friction.negative.Fd"), 1u);
  const FittedCoefficient* bounded = result.Find("friction.positive.Fd");
  ASSERT_NE(bounded, nullptr);
  EXPECT_TRUE(bounded->at_bound);
  EXPECT_FALSE(result.Find("friction.negative.Fd")->at_bound);
  // The entry records this refinement's counts (stages was once written 0).
  const YAML::Node entry = YAML::Load(result.params.provenance_yaml)["refine"];
  EXPECT_EQ(entry["stages"].as<int>(), result.stages);
  EXPECT_EQ(result.stages, 1);
  EXPECT_EQ(entry["starts"].as<int>(), result.starts);
  EXPECT_EQ(entry["iterations"].as<int>(), result.iterations);
}

// A stop raised during the fit (a batch unit's time limit) ends it at the
// point reached: values, but never "converged" (the stall rule once took the
// failing trial steps after a stop for a stall), and no later attempt runs.
// With two stages, a stop in the first keeps its values (the second could
// not simulate). The stop is raised from the log sink after the first
// step's line: this start (Fd three times the truth's) takes more steps.
TEST_F(RefineSpecTest, AStopRaisedDuringTheFitEndsItNotConverged) {
  FitSpec staged = TwoParameters();
  staged.stages = {FitStage{{"friction.positive.Fd"}}, FitStage{}};
  for (const FitSpec& spec : {TwoParameters(), staged}) {
    std::atomic<bool> stop{false};
    RefineOptions options;
    options.simulation.stop = &stop;
    int lines = 0;
    options.log = [&](const std::string&) {
      if (++lines == 2) stop = true;  // after the first step
    };
    Parameters start;
    start.friction.positive.dynamic_force_N = 1.5;
    const RefineResult result = Refine(start, *unit_, spec, options);
    std::cout << result.BriefReport();
    const std::string stages = std::to_string(spec.stages.size()) + " stage(s)";
    EXPECT_EQ(result.status, FitStatus::kNotConverged) << stages;
    EXPECT_EQ(result.reason, spec.stages.empty() ? "stopped" : "stopped after stage 1") << stages;
    EXPECT_TRUE(result.has_values()) << stages;
    EXPECT_GE(result.iterations, 1);
    EXPECT_LE(result.iterations, 3);  // the step logged, and the one whose trial the stop failed
    EXPECT_EQ(result.coordinate_report, "");
    EXPECT_EQ(result.velocity_report, "");
    EXPECT_EQ(result.robust_report, "");
  }
}

// A stop raised before the fit (a batch unit's time limit passed during
// identify) starts no solve: nothing to evaluate, nothing for Ceres to log.
TEST_F(RefineSpecTest, AStopRaisedBeforeTheFitStartsNoSolve) {
  std::atomic<bool> stop{true};
  RefineOptions options;
  options.simulation.stop = &stop;
  int lines = 0;
  options.log = [&](const std::string&) { ++lines; };
  const RefineResult result = Refine(Parameters{}, *unit_, TwoParameters(), options);
  EXPECT_NE(result.status, FitStatus::kConverged);
  EXPECT_NE(result.reason.find("stopped"), std::string::npos) << result.reason;
  EXPECT_EQ(result.iterations, 0);
  EXPECT_EQ(lines, 0);  // no solver progress or report
}

// A log sink that throws loses its lines, not the fit (nothing may throw
// through Ceres' callbacks).
TEST_F(RefineSpecTest, ALogSinkThatThrowsLosesItsLinesNotTheFit) {
  RefineOptions options;
  int lines = 0;
  options.log = [&](const std::string&) {
    ++lines;
    throw std::runtime_error("sink full");
  };
  Parameters start;
  start.friction.positive.dynamic_force_N = 1.5;
  const RefineResult result = Refine(start, *unit_, TwoParameters(), options);
  EXPECT_GT(lines, 2);
  ASSERT_EQ(result.status, FitStatus::kConverged) << result.reason;
  EXPECT_NEAR(result.params.friction.positive.dynamic_force_N, 0.5, 0.1);
}

// A coefficient whose prior (here its start's error, 1e-9 N, and a fraction
// of 1e-6) carries more information than the fitted runs is held toward the
// prior's centre: named with why in the result and in the provenance's
// refine.held (the report's "held by the refinement"); the other is fitted
// and not named.
TEST_F(RefineSpecTest, ACoefficientThePriorDeterminesIsNamedHeldInTheProvenance) {
  Parameters start;
  start.friction.positive.dynamic_force_N = 0.55;
  start.uncertainty = {{"friction.positive.Fd", 1e-9}};
  RefineOptions options;
  options.start_prior_fraction = 1e-6;
  options.coordinate_rounds = 0;  // the prior alone (that start would move the coefficient off it)
  const RefineResult result = Refine(start, *unit_, TwoParameters(), options);
  std::cout << result.BriefReport();
  ASSERT_TRUE(result.has_values()) << result.reason;
  const FittedCoefficient* held = result.Find("friction.positive.Fd");
  ASSERT_NE(held, nullptr);
  EXPECT_FALSE(held->determined());
  EXPECT_NEAR(held->value, 0.55, 1e-6);  // where the prior holds it
  EXPECT_TRUE(result.Find("friction.negative.Fd")->determined());
  const std::map<std::string, std::string> named =
      ProvenanceStrings(result.params.provenance_yaml, "refine", "held");
  ASSERT_EQ(named.size(), 1u);
  EXPECT_EQ(named.count("friction.positive.Fd"), 1u);
  EXPECT_EQ(named.at("friction.positive.Fd"), held->held);
  EXPECT_EQ(ProvenanceList(result.params.provenance_yaml, "refine", "free"),
            (std::vector<std::string>{"friction.negative.Fd", "friction.positive.Fd"}));
  // Refined again with the other coefficient alone free: what the first
  // refinement said of the one held stays (its value and error are still
  // that refinement's).
  const FitSpec other = ParseFitSpec(R"(format: pneumaid-fit/1
parameters:
  friction.negative.Fd: {min: 0.5, max: 20}
experiments: {fit: [stroke-100], hold_out: []}
)",
                                     "other.yaml");
  const RefineResult again = Refine(result.params, *unit_, other, RefineOptions{});
  ASSERT_TRUE(again.has_values()) << again.reason;
  EXPECT_EQ(ProvenanceStrings(again.params.provenance_yaml, "refine", "held"), named);
}

// A last stage by multiple shooting fits windows, but its costs and verdict
// are the whole runs' (one simulation of them gives both): the reported cost
// is the whole run's at the fitted values, the verdict that of EvaluateFit.
TEST_F(RefineSpecTest, AWindowedLastStageReportsTheWholeRunsCostAndVerdict) {
  FitSpec spec = TwoParameters();
  spec.stages = ParseFitSpec(R"(format: pneumaid-fit/1
parameters:
  friction.positive.Fd: {min: 0.05, max: 5}
  friction.negative.Fd: {min: 0.5, max: 20}
experiments: {fit: [stroke-100], hold_out: []}
stages:
  - {windows: true, parameters: all}
)",
                             "windowed.yaml")
                    .stages;
  ASSERT_TRUE(spec.stages.size() == 1 && spec.stages[0].windows);
  Parameters start;
  start.friction.negative.dynamic_force_N *= 0.9;
  const RefineResult result = Refine(start, *unit_, spec, RefineOptions{});
  std::cout << result.BriefReport();
  ASSERT_TRUE(result.has_values()) << result.reason;
  const std::vector<ExperimentCost> whole =
      refine_internal::WholeRunCosts(result.params, *unit_, spec, RefineOptions{});
  ASSERT_EQ(result.fitted.size(), 1u);
  ASSERT_EQ(whole.size(), 1u);
  EXPECT_EQ(result.fitted[0].id, "stroke-100");
  EXPECT_EQ(result.fitted[0].residuals, whole[0].residuals);
  EXPECT_DOUBLE_EQ(result.fitted[0].after, whole[0].after);
  EXPECT_DOUBLE_EQ(result.final_cost, whole[0].after);
  const RefineResult judged = EvaluateFit(result.params, *unit_, spec, RefineOptions{});
  EXPECT_DOUBLE_EQ(result.reduced_chi_square, judged.reduced_chi_square);
  for (const ChannelMisfit& m : result.misfits) EXPECT_EQ(m.run, "stroke-100");
}

// A spec that fits the position alone still estimates each run's initial
// pressures (initial_pressures: fit) with the unit's pressure noise: the
// pressures it does not fit are the unit's (declared here), not missing.
TEST_F(RefineSpecTest, StartsAreEstimatedWithThePressureNoiseOfAChannelNotFitted) {
  const FitSpec spec = ParseFitSpec(R"(format: pneumaid-fit/1
parameters:
  friction.negative.Fd: {min: 0.5, max: 20}
channels: {x: {}}
experiments: {fit: [stroke-100], hold_out: []}
initial_pressures: fit
)",
                                    "position-only.yaml");
  ASSERT_TRUE(spec.fit_initial_pressures);
  ASSERT_EQ(spec.channels.count("p1"), 0u);
  Parameters start;
  start.friction.negative.dynamic_force_N *= 0.95;
  const RefineResult result = Refine(start, *unit_, spec, RefineOptions{});
  ASSERT_TRUE(result.has_values()) << result.reason;
  ASSERT_EQ(result.estimated_starts.size(), 1u);
  // The estimates are written for whoever simulates the run again: the
  // logged values moved by their offsets, in Pa absolute, under the run's id.
  const EstimatedStart& e = result.estimated_starts.front();
  EXPECT_EQ(e.run, "stroke-100");
  EXPECT_GT(e.logged_p1_Pa, 0.5e5);  // absolute: about 1 bar at this start
  EXPECT_NE(e.p1_Pa, e.logged_p1_Pa);
  // A start estimated within a few kPa of its log (the moves are tens of
  // standard errors of a mean of 0.1 bar noise at most).
  EXPECT_LT(std::fabs(e.p1_Pa - e.logged_p1_Pa), 5e3);
  EXPECT_LT(std::fabs(e.p2_Pa - e.logged_p2_Pa), 5e3);
  const YAML::Node written =
      YAML::Load(result.params.provenance_yaml)["refine"]["initial_pressures_Pa"]["stroke-100"];
  ASSERT_TRUE(written.IsSequence()) << result.params.provenance_yaml;
  EXPECT_EQ(written[0].as<double>(), e.p1_Pa);  // shortest text that reads back the same
  EXPECT_EQ(written[1].as<double>(), e.p2_Pa);
}

// The InputError of Refine(start, unit, spec), which must name each of `names`.
void ExpectRefusedNaming(const Parameters& start, const Unit& unit, const FitSpec& spec,
                         const std::vector<std::string>& names) {
  try {
    Refine(start, unit, spec, RefineOptions{});
    ADD_FAILURE() << "refined; expected a refusal naming " << names.front();
  } catch (const InputError& error) {
    for (const std::string& name : names)
      EXPECT_NE(std::string(error.what()).find(name), std::string::npos) << error.what();
  }
}

// The line of Refine(start, unit, spec)'s InputError, which must name `file`.
int RefusedAtLine(const Parameters& start, const Unit& unit, const FitSpec& spec,
                  const std::string& file) {
  try {
    Refine(start, unit, spec, RefineOptions{});
  } catch (const InputError& error) {
    EXPECT_EQ(error.file(), file) << error.what();
    return error.line();
  }
  ADD_FAILURE() << "refined; expected a refusal";
  return -1;
}

// What the spec file says and the unit does not match is refused at the
// spec's line that says it (a spec built in code has none).
TEST_F(RefineSpecTest, RefusesAtTheSpecsLineThatDoesNotFitTheUnit) {
  const auto spec = [](const std::string& negative_max, const std::string& fit,
                       const std::string& hold_out, const std::string& source) {
    return ParseFitSpec(
        "format: pneumaid-fit/1\n"
        "parameters:\n"
        "  friction.positive.Fd: {min: 0.05, max: 5}\n"
        "  friction.negative.Fd: {min: 0.5, max: " +
            negative_max +
            "}\n"
            "experiments:\n"
            "  fit: [" +
            fit +
            "]\n"
            "  hold_out:\n"
            "    - validation\n"
            "    - " +
            hold_out + "\n",
        source);
  };
  // Both fitted and held out: the hold-out entry's line.
  EXPECT_EQ(RefusedAtLine(Parameters{}, *unit_, spec("20", "stroke-100", "stroke-100", "s.yaml"),
                          "s.yaml"),
            9);
  // An experiment the unit lacks: its entry's line.
  EXPECT_EQ(RefusedAtLine(Parameters{}, *unit_, spec("20", "stroke-999", "validation", "s.yaml"),
                          "s.yaml"),
            6);
  // A start outside the bounds (the paper's negative Fd, 5 N, above 2): the
  // parameter's line.
  EXPECT_EQ(RefusedAtLine(Parameters{}, *unit_, spec("2", "stroke-100", "validation", "s.yaml"),
                          "s.yaml"),
            4);
  // A spec built in code has no line to name.
  FitSpec in_code;
  in_code.parameters = {{"friction.negative.Fd", 0.5, 2.0}};
  in_code.channels["x"] = ChannelWeight{};
  in_code.fit = {"stroke-100"};
  in_code.hold_out = {};
  EXPECT_EQ(RefusedAtLine(Parameters{}, *unit_, in_code, "fit spec"), 0);
  in_code.parameters[0].upper = 20.0;
  in_code.hold_out = {"stroke-100"};
  EXPECT_EQ(RefusedAtLine(Parameters{}, *unit_, in_code, "fit spec"), 0);
}

TEST_F(RefineSpecTest, RefusesSpecsThatDoNotFitTheUnit) {
  FitSpec spec = TwoParameters();
  spec.fit = {"stroke-999"};
  EXPECT_THROW(Refine(Parameters{}, *unit_, spec, RefineOptions{}), InputError);
  spec = TwoParameters();
  spec.fit = {"valve"};  // not simulable, and not present
  EXPECT_THROW(Refine(Parameters{}, *unit_, spec, RefineOptions{}), InputError);
  // A kind the unit does not log: the message says that there is no run.
  Unit no_strokes = *unit_;
  no_strokes.experiments.clear();
  spec = TwoParameters();
  spec.fit = {"stroke"};
  ExpectRefusedNaming(Parameters{}, no_strokes, spec,
                      {"the unit has no stroke experiment, and the fit spec two.yaml fits"});
  spec.source.clear();  // built in code: no file to name
  ExpectRefusedNaming(Parameters{}, no_strokes, spec,
                      {"the unit has no stroke experiment, and the fit spec fits 'stroke'"});
  spec = TwoParameters();
  spec.hold_out = {"stroke-100"};  // both fitted and held out
  EXPECT_THROW(Refine(Parameters{}, *unit_, spec, RefineOptions{}), InputError);
  spec = TwoParameters();
  Parameters outside;
  outside.friction.negative.dynamic_force_N = 30;  // above its max of 20
  ExpectRefusedNaming(outside, *unit_, spec, {"friction.negative.Fd"});
  // A friction replay fits the paper's law with exact stick: not a model for
  // a set with an effect that acts on friction (a rod that creeps, friction
  // that scales with the pressures); an effect that does not is no reason.
  spec.stages = {FitStage{}, FitStage{}};
  spec.stages[0].friction_replay = true;
  Parameters creeping;
  creeping.effects["stick_creep"]["v"] = 1e-4;
  ExpectRefusedNaming(creeping, *unit_, spec, {"stage 1 replays friction", "stick_creep"});
  Parameters pressure_scaled;
  pressure_scaled.effects["friction_pressure"]["kp"] = 1e-7;
  ExpectRefusedNaming(pressure_scaled, *unit_, spec,
                      {"stage 1 replays friction", "friction_pressure"});
  Parameters lagging;
  lagging.effects["valve_lag"]["tau"] = 0.004;
  EXPECT_NO_THROW(CheckRefinable(lagging, *unit_, spec, RefineOptions{}));
}

// CheckRefinable refuses what only the unit, the spec, the prior and the
// options decide before any component fit: a coefficient of an effect the
// prior lacks, options whose validation simulation is not valid, a channel
// with no sigma anywhere.
TEST_F(RefineSpecTest, CheckRefinableRefusesBeforeAnyFitWhatNoFitCanChange) {
  const auto refused = [](const Unit& unit, const FitSpec& spec, const RefineOptions& options,
                          const std::string& name) {
    try {
      CheckRefinable(Parameters{}, unit, spec, options);
      ADD_FAILURE() << "accepted; expected a refusal naming " << name;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(name), std::string::npos) << error.what();
    }
  };
  FitSpec creep = TwoParameters();
  creep.parameters.push_back({"effects.stick_creep.v", 1e-5, 1e-3, ParameterScale::kLog});
  refused(*unit_, creep, RefineOptions{}, "effects.stick_creep.v");
  RefineOptions options;
  options.validation.relative_tolerance = 2;
  refused(*unit_, TwoParameters(), options, "validation.relative_tolerance");
  FitSpec flat = TwoParameters();
  flat.channels["p1"] = ChannelWeight{};  // sigma 0: the manifest's, and here none is declared
  Unit quiet = *unit_;
  quiet.manifest.sensors.clear();
  for (Experiment& e : quiet.experiments) {
    for (double& p : e.columns["p1"]) p = 5e5;  // a log that never changes
  }
  refused(quiet, flat, RefineOptions{}, "channel p1");
  // A prior of another bore is no reason: identify puts the unit's own
  // constants over it before the refinement.
  Parameters other_bore;
  other_bore.cylinder.area_1_m2 *= 1.5;
  other_bore.cylinder.area_2_m2 *= 1.5;
  ASSERT_THROW(WithRigConditions(other_bore, *unit_), InputError);  // the rig's check
  EXPECT_NO_THROW(CheckRefinable(other_bore, *unit_, TwoParameters(), RefineOptions{}));
}

// On data with model mismatch (smooth stick, the rig integrated tighter) the
// event model's cost is rougher than its stall tolerance at the scale of the
// errors: the stencil measures it, and the errors it widens are the same
// fit's, never narrower, still honest (ExpectHonestErrors). The roughness
// one pair reads depends on the last bits of the arithmetic: on this unit
// 2.2e-3 of the cost on one machine, 1.1e-3 on another (an AVX-512 EPYC,
// session 57), where two pairs read 2.4e-3 (of four seeds there, two read
// none at all: the stick/slip switches that make the roughness move with
// the noise). So the test measures with two pairs.
TEST(RefineTest, TheMeasuredCostResolutionWidensTheErrorsOnAMismatchedUnit) {
  Parameters truth = testing::HeavyHorizontalTruth();
  truth.friction.negative = {8.0, 1.0, 10.0, 0.02};
  const Unit unit = testing::MismatchedStrokes(truth, 23, "C", "refine_cost_resolution");
  const FitSpec spec = LoadFitSpec(kDefaultSpec);
  RefineOptions fixed;
  fixed.cost_resolution_directions = 0;
  RefineOptions two_pairs;
  two_pairs.cost_resolution_directions = 2;
  const RefineResult plain = Refine(truth, unit, spec, fixed);
  const RefineResult measured = Refine(truth, unit, spec, two_pairs);
  ASSERT_TRUE(plain.has_values() && measured.has_values());
  EXPECT_EQ(plain.cost_resolution, fixed.stall_tolerance);
  EXPECT_GT(measured.cost_resolution, 1.2 * fixed.stall_tolerance);
  EXPECT_FALSE(plain.cost_resolution_measured);
  EXPECT_TRUE(measured.cost_resolution_measured);
  EXPECT_NE(measured.BriefReport().find("measured one standard error out"), std::string::npos);
  ASSERT_EQ(plain.coefficients.size(), measured.coefficients.size());
  int wider = 0;
  for (size_t i = 0; i < plain.coefficients.size(); ++i) {
    const FittedCoefficient &a = plain.coefficients[i], &b = measured.coefficients[i];
    EXPECT_EQ(a.value, b.value) << a.path;
    EXPECT_GE(b.standard_error, a.standard_error) << a.path;
    wider += b.standard_error > 1.05 * a.standard_error;
  }
  EXPECT_GT(wider, 0);
  ExpectHonestErrors(measured, truth, spec);
}

TEST(RefineOptionsTest, IsValidNamesTheBadField) {
  std::string error;
  EXPECT_TRUE(RefineOptions{}.IsValid(&error)) << error;
  const std::pair<const char*, void (*)(RefineOptions*)> bad[] = {
      {"threads", [](RefineOptions* o) { o->threads = 0; }},
      {"correlation_flag", [](RefineOptions* o) { o->correlation_flag = 1.5; }},
      {"earlier_stage_stall_tolerance",
       [](RefineOptions* o) { o->earlier_stage_stall_tolerance = -1; }},
      {"clustered_error_block_s", [](RefineOptions* o) { o->clustered_error_block_s = -0.1; }},
      {"cost_resolution_directions", [](RefineOptions* o) { o->cost_resolution_directions = -1; }},
      {"screen_windows_max", [](RefineOptions* o) { o->screen_windows_max = -1; }},
      {"rounds", [](RefineOptions* o) { o->rounds = 0; }},
      {"out_of_reach_ratio", [](RefineOptions* o) { o->out_of_reach_ratio = 0.5; }},
      {"simulation.relative_tolerance",
       [](RefineOptions* o) { o->simulation.relative_tolerance = 0; }},
      {"validation.relative_tolerance",
       [](RefineOptions* o) { o->validation.relative_tolerance = 2; }},
  };
  for (const auto& [field, spoil] : bad) {
    RefineOptions options;
    spoil(&options);
    EXPECT_FALSE(options.IsValid(&error)) << field;
    EXPECT_NE(error.find(field), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace pneumaid
