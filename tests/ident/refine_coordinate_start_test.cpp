// Refinement's coordinate start (src/ident/refine_coordinate_start.h): the
// component fits' friction is right but for one direction's Stribeck
// velocity, 17 % low, and the runs then cost a thousand times the truth's;
// neither the fit from that start nor the friction screen (which solves Fd
// and b from the slides and so moves the coefficients that were right)
// finds the basin; a start one coefficient away does. Logs written with
// model mismatch (smooth stick, the rig integrated at rtol 1e-8), a 0.5 kg
// horizontal rod at 1 kHz whose position transducer lags 3 ms.
#include "../../src/ident/refine_coordinate_start.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "../../src/ident/refine_verdict.h"
#include "../bench/sweep_draw.h"
#include "friction_test_util.h"
#include "pneumaid/ident/identify.h"
#include "pneumaid/ident/refine.h"
#include "refine_mismatch_util.h"

namespace pneumaid {
namespace {

const testing::RefineCase& OneCoefficientOff() {
  static const testing::RefineCase c = [] {
    testing::RefineCase s;
    s.truth = testing::HeavyHorizontalTruth();
    s.truth.cylinder.load_mass_kg = 0.5;
    s.truth.friction.positive = {10.0, 0.5, 5.0, 0.01};
    s.truth.friction.negative = {10.0, 5.0, 5.0, 0.01};
    Protocol protocol = testing::MismatchedStrokeProtocol(2, {0.4, 0.6, 0.8});
    protocol.sensors["x"].tau_s = 3e-3;
    s.unit =
        testing::WriteAndReadUnit(Synthesize(s.truth, protocol, 3, "C"), "refine_coordinate_start");
    s.start = s.truth;
    s.start.friction.positive.stribeck_velocity_m_per_s *= 0.83;
    return s;
  }();
  return c;
}

// Every later attempt off but the one under test.
RefineOptions OnlyTheCoordinateStart(int rounds) {
  RefineOptions options;
  options.screen_friction_starts = false;
  options.robust_refit = false;
  options.windowed_refit = false;
  options.rescue_starts = 0;
  options.windowed_polish = false;
  options.rounds = 1;
  options.coordinate_rounds = rounds;
  options.stribeck_velocity_divisor = 0;
  return options;
}

TEST(RefineCoordinateStartTest, TheOneCoefficientOffIsMovedFirst) {
  const testing::RefineCase& c = OneCoefficientOff();
  const FitSpec spec = LoadFitSpec(testing::kDefaultFitSpec);
  const RefineOptions options = OnlyTheCoordinateStart(1);
  const refine_internal::CoordinateSearch moved =
      refine_internal::SearchFrictionCoordinates(c.start, c.unit, spec, options);
  std::cout << moved.report << "\n";
  ASSERT_TRUE(moved.moved);
  EXPECT_EQ(moved.candidates, 1 + 8 * 16);
  EXPECT_LT(moved.chi_square_after, 0.2 * moved.chi_square_before);
  EXPECT_NE(moved.report.find("friction.positive.vs"), std::string::npos) << moved.report;
  // The one move, to within a grid step (5 %) of the truth; every other
  // coefficient as it was.
  EXPECT_NEAR(moved.start.friction.positive.stribeck_velocity_m_per_s,
              c.truth.friction.positive.stribeck_velocity_m_per_s,
              0.05 * c.truth.friction.positive.stribeck_velocity_m_per_s);
  EXPECT_EQ(moved.start.friction.negative.stribeck_velocity_m_per_s,
            c.start.friction.negative.stribeck_velocity_m_per_s);
  EXPECT_EQ(moved.start.friction.positive.static_force_N, c.start.friction.positive.static_force_N);
}

TEST(RefineCoordinateStartTest, TheFitFromItExplainsTheRunsWhereTheGivenStartStalls) {
  const testing::RefineCase& c = OneCoefficientOff();
  const FitSpec spec = LoadFitSpec(testing::kDefaultFitSpec);
  const RefineResult stalled = Refine(c.start, c.unit, spec, OnlyTheCoordinateStart(0));
  std::cout << stalled.BriefReport();
  EXPECT_FALSE(stalled.explained());
  EXPECT_GT(stalled.reduced_chi_square, 100.0);  // a stall, not a near miss
  const RefineResult result = Refine(c.start, c.unit, spec, OnlyTheCoordinateStart(2));
  std::cout << result.BriefReport();
  ASSERT_TRUE(result.explained()) << result.reason;
  EXPECT_NE(result.coordinate_report.find(", kept"), std::string::npos) << result.coordinate_report;
  testing::ExpectFrictionWithinTolerance(result.params, c.truth);
}

// A fit the verdict calls explained (here by a threshold of 1e6) but whose
// measure is above coordinate_start_above gets the coordinate start too, and
// gives way to its fit on a clear gain only (coordinate_start_keep_ratio).
TEST(RefineCoordinateStartTest, AnExplainedFitWellAboveTheNoiseGivesWayToAClearGainOnly) {
  const testing::RefineCase& c = OneCoefficientOff();
  const FitSpec spec = LoadFitSpec(testing::kDefaultFitSpec);
  RefineOptions options = OnlyTheCoordinateStart(2);
  options.acceptable_reduced_chi_square = 1e6;
  options.coordinate_start_above = 1e300;  // only when not explained: not run
  const RefineResult given = Refine(c.start, c.unit, spec, options);
  ASSERT_TRUE(given.explained()) << given.reason;
  EXPECT_GT(given.reduced_chi_square, 100.0);
  EXPECT_TRUE(given.coordinate_report.empty()) << given.coordinate_report;
  options.coordinate_start_above = 3.0;
  const RefineResult moved = Refine(c.start, c.unit, spec, options);
  std::cout << moved.BriefReport();
  EXPECT_NE(moved.coordinate_report.find(", kept"), std::string::npos) << moved.coordinate_report;
  EXPECT_LT(moved.reduced_chi_square, 0.01 * given.reduced_chi_square);
  testing::ExpectFrictionWithinTolerance(moved.params, c.truth);
  options.coordinate_start_keep_ratio = 1e-6;  // no gain is clear enough
  const RefineResult kept = Refine(c.start, c.unit, spec, options);
  EXPECT_NE(kept.coordinate_report.find("not kept (explained before, no clear gain)"),
            std::string::npos)
      << kept.coordinate_report;
  EXPECT_EQ(kept.final_cost, given.final_cost);
  EXPECT_GT(kept.iterations, given.iterations);  // the candidate was fitted, and counted
}

// RefineOptions::stribeck_velocity_divisor's starts: one per direction whose
// vs the spec frees, that vs alone divided, its standard error dropped.
TEST(StribeckVelocityStartsTest, EachDividesOneDirectionsVelocityAlone) {
  const FitSpec spec = LoadFitSpec(testing::kDefaultFitSpec);
  Parameters from = testing::HeavyHorizontalTruth();
  from.friction.positive = {10.0, 0.5, 5.0, 0.012};
  from.friction.negative = {8.0, 2.0, 4.0, 0.03};
  from.uncertainty = {{"friction.positive.vs", 1e-3},
                      {"friction.negative.vs", 2e-3},
                      {"friction.negative.Fs", 0.2}};
  const std::vector<refine_internal::VelocityStart> starts =
      refine_internal::StribeckVelocityStarts(from, spec, 3.0);
  ASSERT_EQ(starts.size(), 2u);
  EXPECT_EQ(starts[0].direction, "positive");
  EXPECT_EQ(starts[1].direction, "negative");
  EXPECT_DOUBLE_EQ(starts[0].start.friction.positive.stribeck_velocity_m_per_s, 0.004);
  EXPECT_EQ(starts[0].start.friction.negative.stribeck_velocity_m_per_s, 0.03);
  EXPECT_DOUBLE_EQ(starts[1].start.friction.negative.stribeck_velocity_m_per_s, 0.01);
  EXPECT_EQ(starts[1].start.friction.positive.stribeck_velocity_m_per_s, 0.012);
  EXPECT_EQ(starts[1].start.friction.negative.static_force_N, 8.0);
  EXPECT_EQ(starts[0].start.uncertainty.count("friction.positive.vs"), 0u);
  EXPECT_EQ(starts[0].start.uncertainty.count("friction.negative.vs"), 1u);
  EXPECT_EQ(starts[1].start.uncertainty.count("friction.negative.vs"), 0u);
  EXPECT_EQ(starts[1].start.uncertainty.at("friction.negative.Fs"), 0.2);
  // A vs at its lower bound (1e-4 m/s) stays there: no start for it.
  from.friction.positive.stribeck_velocity_m_per_s = 1e-4;
  const auto bounded = refine_internal::StribeckVelocityStarts(from, spec, 3.0);
  ASSERT_EQ(bounded.size(), 1u);
  EXPECT_EQ(bounded[0].direction, "negative");
  // Off, or a spec that does not free vs: none.
  EXPECT_TRUE(refine_internal::StribeckVelocityStarts(from, spec, 0.0).empty());
  FitSpec fixed = spec;
  fixed.parameters.erase(std::remove_if(fixed.parameters.begin(), fixed.parameters.end(),
                                        [](const FreeParameter& p) {
                                          return p.path.size() > 3 &&
                                                 p.path.compare(p.path.size() - 3, 3, ".vs") == 0;
                                        }),
                         fixed.parameters.end());
  EXPECT_TRUE(refine_internal::StribeckVelocityStarts(from, fixed, 3.0).empty());
}

// The velocity starts run on the coordinate start's trigger only: not on a
// fit explained at or below coordinate_start_above, nor when the first
// stage replays the friction fit (it would refit the moved vs before any
// simulation fit).
TEST(StribeckVelocityStartsTest, RunOnTheCoordinateStartsTriggerOnly) {
  const testing::RefineCase& c = OneCoefficientOff();
  const FitSpec spec = LoadFitSpec(testing::kDefaultFitSpec);
  RefineOptions options = OnlyTheCoordinateStart(0);
  options.stribeck_velocity_divisor = 3;
  options.acceptable_reduced_chi_square = 1e6;  // every fit here is explained
  options.coordinate_start_above = 1e300;
  const RefineResult near_noise = Refine(c.start, c.unit, spec, options);
  ASSERT_TRUE(near_noise.explained()) << near_noise.reason;
  EXPECT_TRUE(near_noise.velocity_report.empty()) << near_noise.velocity_report;
  options.coordinate_start_above = 1;
  ASSERT_GT(near_noise.reduced_chi_square, options.coordinate_start_above);
  const RefineResult above = Refine(c.start, c.unit, spec, options);
  EXPECT_NE(above.velocity_report.find("Stribeck velocity starts"), std::string::npos)
      << above.velocity_report;
  EXPECT_NE(above.velocity_report.find(" positive "), std::string::npos) << above.velocity_report;
  FitSpec replay = spec;
  replay.stages.insert(replay.stages.begin(), FitStage{});
  replay.stages.front().friction_replay = true;
  const RefineResult replayed = Refine(c.start, c.unit, replay, options);
  ASSERT_TRUE(replayed.has_values()) << replayed.reason;
  ASSERT_GT(replayed.reduced_chi_square, options.coordinate_start_above);
  EXPECT_TRUE(replayed.velocity_report.empty()) << replayed.velocity_report;
}

// The robustness gate's sweep-01 (seed 2026, unit 1, drawn as the sweep
// draws it: tests/bench/sweep_draw.h): a 0.84 kg vertical rod at 2 kHz,
// smooth stick, four strokes at 0.36 to 0.55 V that stop 1 mm short of the
// ends, the negative Stribeck velocity 2.1 mm/s. `identify` reads it as
// 15.7 mm/s; the fit from there stalls, explained but well above the noise,
// with that vs at 9.4 mm/s and the negative Fs 3.5 N for 5.3 (held-out x
// 0.28 mm, the limit 0.08). A third of the start's vs reaches the basin the
// fit from the truth reaches (4.2 against 8.96).
const testing::RefineCase& GateUnitOne() {
  static const testing::RefineCase c = [] {
    const sweep::Draw d = sweep::MakeDraw(2026, 1);
    testing::RefineCase s;
    s.truth = d.truth;
    s.unit = testing::WriteAndReadUnit(Synthesize(d.truth, d.protocol, 2026 + 1, "sweep-01"),
                                       "refine_velocity_start");
    const Parameters prior = LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper.yaml");
    IdentifyReport report;
    s.start = Identify(s.unit, prior, IdentifyOptions{}, &report);
    return s;
  }();
  return c;
}

TEST(StribeckVelocityStartsTest, AFitStalledAtAHighStribeckVelocityReachesTheTruthsBasin) {
  const testing::RefineCase& c = GateUnitOne();
  const FitSpec spec = LoadFitSpec(testing::kDefaultFitSpec);
  RefineOptions options = RefineOptions::ForIdentify();
  options.fit_stick_creep = false;  // the paper model's basins
  const double truth_vs = c.truth.friction.negative.stribeck_velocity_m_per_s;
  ASSERT_GT(c.start.friction.negative.stribeck_velocity_m_per_s, 3 * truth_vs);
  options.stribeck_velocity_divisor = 0;
  const RefineResult stalled = Refine(c.start, c.unit, spec, options);
  std::cout << stalled.BriefReport();
  ASSERT_TRUE(stalled.explained()) << stalled.reason;
  EXPECT_GT(stalled.reduced_chi_square, options.coordinate_start_above);
  EXPECT_TRUE(stalled.velocity_report.empty()) << stalled.velocity_report;
  options.stribeck_velocity_divisor = 3;
  const RefineResult moved = Refine(c.start, c.unit, spec, options);
  std::cout << moved.BriefReport();
  ASSERT_TRUE(moved.explained()) << moved.reason;
  EXPECT_NE(moved.velocity_report.find("the negative kept"), std::string::npos)
      << moved.velocity_report;
  EXPECT_LE(moved.reduced_chi_square,
            options.coordinate_start_keep_ratio * stalled.reduced_chi_square);
  // The basin of the fit from the truth (the starts off: the plain fit's):
  // its cost and negative friction.
  options.stribeck_velocity_divisor = 0;
  const RefineResult from_truth = Refine(c.truth, c.unit, spec, options);
  std::cout << from_truth.BriefReport();
  ASSERT_TRUE(from_truth.explained()) << from_truth.reason;
  EXPECT_NEAR(moved.reduced_chi_square, from_truth.reduced_chi_square,
              0.1 * from_truth.reduced_chi_square);
  const StribeckParams& m = moved.params.friction.negative;
  const StribeckParams& t = from_truth.params.friction.negative;
  const StribeckParams& s = stalled.params.friction.negative;
  EXPECT_NEAR(m.static_force_N, t.static_force_N, 0.1);
  EXPECT_NEAR(m.stribeck_velocity_m_per_s, t.stribeck_velocity_m_per_s, 1e-3);
  EXPECT_GT(std::fabs(s.static_force_N - t.static_force_N), 1.0);
  EXPECT_GT(s.stribeck_velocity_m_per_s - t.stribeck_velocity_m_per_s, 3e-3);
}

TEST(RefineCoordinateStartTest, OptionsNameTheBadField) {
  RefineOptions options;
  std::string error;
  options.coordinate_rounds = -1;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("coordinate_rounds"), std::string::npos) << error;
  options.coordinate_rounds = 2;
  options.coordinate_span = 1.0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("coordinate_span"), std::string::npos) << error;
  options.coordinate_span = 1.5;
  options.coordinate_start_above = 0.5;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("coordinate_start_above"), std::string::npos) << error;
  options.coordinate_start_above = 3.0;
  for (const double ratio : {0.0, 1.5}) {
    options.coordinate_start_keep_ratio = ratio;
    EXPECT_FALSE(options.IsValid(&error)) << ratio;
    EXPECT_NE(error.find("coordinate_start_keep_ratio"), std::string::npos) << error;
  }
  options.coordinate_start_keep_ratio = 0.85;
  EXPECT_TRUE(options.IsValid(&error)) << error;
  for (const double divisor : {-1.0, 0.5, 1.0}) {
    options.stribeck_velocity_divisor = divisor;
    EXPECT_FALSE(options.IsValid(&error)) << divisor;
    EXPECT_NE(error.find("stribeck_velocity_divisor"), std::string::npos) << error;
  }
  options.stribeck_velocity_divisor = 0;  // off
  EXPECT_TRUE(options.IsValid(&error)) << error;
}

}  // namespace
}  // namespace pneumaid
