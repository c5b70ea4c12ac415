// Refinement's creep fit (RefineOptions::fit_stick_creep): where the rod
// creeps below its breakaway force (a real seal, or a rig whose stick is a
// regularised law), the paper model's event stick makes up for the creep
// with its friction; fitted with the creep speed, the friction comes back.
// Logs written with model mismatch (the rig integrated at rtol 1e-8), the
// stick as the rig's smooth law or as events.
#include "../../src/ident/refine_creep.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <string>

#include "pneumaid/ident/refine.h"
#include "pneumaid/model/actuator.h"
#include "pneumaid/synth/synthetic_rig.h"
#include "refine_mismatch_util.h"

namespace pneumaid {
namespace {

// Strokes at 0.5, 0.7 and 0.9 V of the heavy horizontal unit, the rig's rod
// creeping at up to `creep_m_per_s` below Fs (0: event stick); synthetic,
// seeded.
Unit Strokes(const Parameters& truth, double creep_m_per_s, const std::string& id) {
  Protocol protocol = testing::RefinementProtocol({0.5, 0.7, 0.9}, false);
  protocol.mismatch.regularized_friction = creep_m_per_s > 0;
  if (creep_m_per_s > 0) protocol.mismatch.stick_velocity_m_per_s = creep_m_per_s;
  protocol.mismatch.relative_tolerance = 1e-8;
  return testing::WriteAndReadUnit(Synthesize(truth, protocol, 31, id), "refine_creep_" + id);
}

// The truth's friction moved as a component fit might leave it.
Parameters StartOff(const Parameters& truth) {
  Parameters start = truth;
  for (StribeckParams* d : {&start.friction.positive, &start.friction.negative}) {
    d->static_force_N *= 1.1;
    d->viscous_N_s_per_m *= 0.8;
    d->stribeck_velocity_m_per_s *= 1.3;
  }
  return start;
}

RefineResult RefineWithCreepFit(const Parameters& start, const Unit& unit) {
  return Refine(start, unit, LoadFitSpec(testing::kDefaultFitSpec), RefineOptions::ForIdentify());
}

// A rig regularised at 1 mm/s: the creep fit finds the rig's creep speed,
// explains the runs better than the event stick by more than the keep ratio,
// and every friction coefficient is within the tolerances.
TEST(RefineCreepTest, ARodThatCreepsGetsItsFrictionBackWithTheCreepSpeed) {
  const Parameters truth = testing::HeavyHorizontalTruth();
  const Unit unit = Strokes(truth, 1e-3, "C");
  const RefineResult r = RefineWithCreepFit(StartOff(truth), unit);
  std::cout << r.BriefReport();
  ASSERT_TRUE(r.has_values()) << r.reason;
  EXPECT_TRUE(r.explained()) << r.BriefReport();
  ASSERT_TRUE(Creeps(r.params)) << r.creep_report;
  EXPECT_NE(r.creep_report.find(": kept"), std::string::npos) << r.creep_report;
  // Told in the frame of the paper fit: the given start's values and costs,
  // the held-out runs validated with the creep fit.
  EXPECT_NEAR(testing::ParameterValue(r.params, "friction.positive.Fs"), 10.0, 0.5);
  for (const FittedCoefficient& c : r.coefficients) {
    if (c.path == "friction.positive.Fs") {
      EXPECT_DOUBLE_EQ(c.start, 11.0);
    }
  }
  EXPECT_GT(r.initial_cost, r.final_cost);
  EXPECT_EQ(r.held_out_after.experiments.size(), r.held_out_before.experiments.size());
  EXPECT_NE(r.params.provenance_yaml.find("creep_fit"), std::string::npos);
  // Freed from the profile's best, so it has a standard error of its own.
  EXPECT_NE(r.creep_report.find("(fitted)"), std::string::npos) << r.creep_report;
  EXPECT_EQ(r.params.uncertainty.count("effects.stick_creep.v"), 1u);
  const double v = testing::ParameterValue(r.params, "effects.stick_creep.v");
  EXPECT_GT(v, 0.5e-3);
  EXPECT_LT(v, 2e-3);
  testing::ExpectFrictionWithinTolerance(r.params, truth);
}

// Event stick, as the paper's model has it: no creep speed explains the runs
// better, so the paper model's fit is what comes back.
TEST(RefineCreepTest, ARodThatSticksKeepsThePaperModel) {
  const Parameters truth = testing::HeavyHorizontalTruth();
  const Unit unit = Strokes(truth, 0, "E");
  const RefineResult r = RefineWithCreepFit(StartOff(truth), unit);
  ASSERT_TRUE(r.has_values()) << r.reason;
  EXPECT_FALSE(Creeps(r.params)) << r.creep_report;
  EXPECT_NE(r.creep_report.find("not kept"), std::string::npos) << r.creep_report;
  testing::ExpectFrictionWithinTolerance(r.params, truth);
}

TEST(RefineCreepTest, NotRunForAStartThatCreepsAlreadyOrAnEventStickReplay) {
  const Parameters truth = testing::HeavyHorizontalTruth();
  const Unit unit = Strokes(truth, 1e-4, "N");
  // The library's defaults fit the spec's model only (diagnose's base refits).
  const RefineResult plain =
      Refine(truth, unit, LoadFitSpec(testing::kDefaultFitSpec), RefineOptions{});
  EXPECT_TRUE(plain.creep_report.empty()) << plain.creep_report;
  EXPECT_FALSE(Creeps(plain.params));
  // A last stage without friction: holding the friction at each v says nothing.
  FitSpec timing = LoadFitSpec(testing::kDefaultFitSpec);
  timing.stages.clear();
  timing.parameters.erase(
      std::remove_if(timing.parameters.begin(), timing.parameters.end(),
                     [](const FreeParameter& p) { return p.path.rfind("friction.", 0) == 0; }),
      timing.parameters.end());
  const RefineResult t = Refine(truth, unit, timing, RefineOptions::ForIdentify());
  EXPECT_NE(t.creep_report.find("not run, the spec's last stage frees no friction coefficient"),
            std::string::npos)
      << t.creep_report;
  Parameters creeping = truth;
  creeping.effects["stick_creep"]["v"] = 1e-4;
  const RefineResult r = RefineWithCreepFit(creeping, unit);
  EXPECT_NE(r.creep_report.find("not run, the start has stick_creep already"), std::string::npos)
      << r.creep_report;
  FitSpec replay = LoadFitSpec(testing::kDefaultFitSpec);
  replay.stages.insert(replay.stages.begin(), FitStage{{}, false, true});
  const RefineResult e = Refine(truth, unit, replay, RefineOptions::ForIdentify());
  EXPECT_NE(e.creep_report.find("not run, the spec replays the friction fit"), std::string::npos)
      << e.creep_report;
  EXPECT_FALSE(Creeps(e.params));
}

TEST(RefineCreepTest, ACreepSpeedHeldAtAProfilePointIsListedAsHeldWithWhy) {
  RefineResult r;
  r.status = FitStatus::kConverged;
  FittedCoefficient fs;
  fs.path = "friction.positive.Fs";
  fs.value = 11;
  fs.standard_error = 0.2;
  r.coefficients = {fs};
  r.covariance = Eigen::MatrixXd::Constant(1, 1, 0.04);
  r.params.effects["stick_creep"]["v"] = 1e-4;
  refine_internal::ListHeldCreepSpeed(1e-4, "held at a point of the creep fit's profile", &r);
  const FittedCoefficient* v = r.Find("effects.stick_creep.v");
  ASSERT_NE(v, nullptr);
  EXPECT_FALSE(v->determined());
  EXPECT_DOUBLE_EQ(v->value, 1e-4);
  EXPECT_EQ(v->standard_error, 0);
  EXPECT_EQ(r.status, FitStatus::kConverged);  // held is no failure of the fit
  ASSERT_EQ(r.covariance.rows(), 2);
  EXPECT_DOUBLE_EQ(r.covariance(0, 0), 0.04);
  EXPECT_EQ(r.covariance(1, 1), 0);
  EXPECT_NE(r.CoefficientReport("", 0.95).find("held: held at a point of the creep fit's profile"),
            std::string::npos)
      << r.CoefficientReport("", 0.95);
  // A fit without a covariance gets none from the held coefficient either.
  RefineResult bare;
  bare.coefficients = {fs};
  refine_internal::ListHeldCreepSpeed(1e-4, "held", &bare);
  EXPECT_EQ(bare.coefficients.size(), 2u);
  EXPECT_EQ(bare.covariance.size(), 0);
}

TEST(RefineCreepTest, OptionsNameTheBadField) {
  RefineOptions o = RefineOptions::ForIdentify();
  std::string error;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.stick_creep_keep_ratio = 1.5;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("stick_creep_keep_ratio"), std::string::npos) << error;
  o = RefineOptions::ForIdentify();
  o.stick_creep_profile = {1e-4, 1e-2};
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("stick_creep_profile"), std::string::npos) << error;
  o = RefineOptions::ForIdentify();
  o.stick_creep_freed_ratio = 0.9;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("stick_creep_freed_ratio"), std::string::npos) << error;
  EXPECT_FALSE(RefineOptions{}.fit_stick_creep);  // diagnose's base refits keep their model
}

// The creep fit compares its inner fits as refined: with identify's options
// an inner fit that is not explained had returned its start, and on a gate
// unit (0.09 kg, 500 Hz) the freed fit then started from the profile's start
// and ended at 166 per residual instead of 113.
TEST(RefineCreepTest, TheInnerFitsReturnTheirRefinedSets) {
  const RefineOptions outer = RefineOptions::ForIdentify();
  ASSERT_TRUE(outer.write_start_unless_explained);
  const RefineOptions inner = refine_internal::InnerOptions(outer);
  EXPECT_FALSE(inner.write_start_unless_explained);
  EXPECT_FALSE(inner.fit_stick_creep);
  EXPECT_EQ(inner.rounds, 1);
  EXPECT_EQ(inner.coordinate_rounds, 0);
  EXPECT_EQ(inner.stribeck_velocity_divisor, 0);
}

}  // namespace
}  // namespace pneumaid
