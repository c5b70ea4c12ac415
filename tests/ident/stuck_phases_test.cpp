// The one rule of "stuck" (stuck_phases.h), on positions made here: a rod at
// rest in noise, a slow slide, the apex of a reversal without stick.
#include "../../src/ident/stuck_phases.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace pneumaid {
namespace {

constexpr double kSigmaM = 2e-6;  // position noise

internal::StuckRule Rule(double period_s) {
  return internal::StuckRuleOf(FrictionFitOptions{}, kSigmaM, 0, period_s);
}

// x(t) sampled every period_s, with seeded Gaussian noise of sigma_m.
template <typename F>
std::vector<double> Logged(double period_s, int samples, F x, double sigma_m = kSigmaM) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, sigma_m);
  std::vector<double> out(samples);
  for (int i = 0; i < samples; ++i) out[i] = x(i * period_s) + noise(rng);
  return out;
}

// The options in SI, per sample at the log's rate: min_stuck_s (4 ms) sets
// the shortest phase at 5 kHz, min_stuck_samples at 250 Hz.
TEST(StuckPhasesTest, TheRuleTakesTheOptionsPerSample) {
  const FrictionFitOptions options;
  const internal::StuckRule fast = internal::StuckRuleOf(options, kSigmaM, 0, 2e-4);
  const internal::StuckRule slow = internal::StuckRuleOf(options, kSigmaM, 0, 4e-3);
  EXPECT_EQ(fast.min_samples, 20);
  EXPECT_EQ(slow.min_samples, options.min_stuck_samples);
  EXPECT_DOUBLE_EQ(fast.max_slope_m_per_sample, options.max_stuck_speed_m_per_s * 2e-4);
  EXPECT_DOUBLE_EQ(slow.max_curvature_m_per_sample2,
                   options.max_stuck_acceleration_m_per_s2 * 16e-6);
}

// A rod at rest logged at 1 kHz for 0.3 s with 8 um of noise: stuck all
// along under the rule of its own noise (a band of 25 + 48 um), in pieces
// under the rule of 2 um noise (25 + 12 um: the noise spreads further
// within tens of samples).
TEST(StuckPhasesTest, TheBandWidensWithTheNoise) {
  const std::vector<double> x = Logged(
      1e-3, 300, [](double) { return 0.0; }, 8e-6);
  const auto longest = [&x](double sigma_m) {
    std::size_t most = 0;
    for (const auto& [begin, end] :
         internal::StuckRuns(x, internal::StuckRuleOf(FrictionFitOptions{}, sigma_m, 0, 1e-3))) {
      most = std::max(most, end - begin);
    }
    return most;
  };
  EXPECT_EQ(longest(8e-6), x.size());
  EXPECT_LT(longest(2e-6), x.size() / 2);
}

// At 1 kHz: stuck 0.1 s, a slide of 20 mm/s for 0.1 s, stuck again: two
// phases, the slide in neither, each ending where the rod leaves the band.
TEST(StuckPhasesTest, ARodAtRestBetweenSlidesIsStuckTwice) {
  const std::vector<double> x = Logged(
      1e-3, 300, [](double t) { return t < 0.1 ? 0.0 : (t < 0.2 ? 0.02 * (t - 0.1) : 0.002); });
  const internal::Runs runs = internal::StuckRuns(x, Rule(1e-3));
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].first, 0u);
  EXPECT_NEAR(static_cast<double>(runs[0].second), 102, 3);  // 37 um band at 20 um per sample
  EXPECT_NEAR(static_cast<double>(runs[1].first), 198, 3);
  EXPECT_EQ(runs[1].second, x.size());
}

// At 1 kHz a slide of 4 mm/s stays within the 37 um band for 10 samples, more
// than the shortest phase (5): the band alone would call it stuck, its slope
// (above max_stuck_speed_m_per_s, 2 mm/s) does not. At 1 mm/s it is stuck.
TEST(StuckPhasesTest, ASlideFasterThanTheStuckSpeedIsNotStuckInsideTheBand) {
  const internal::StuckRule rule = Rule(1e-3);
  ASSERT_LT(4e-3 * 1e-3 * rule.min_samples, rule.band_m);
  const std::vector<double> slide = Logged(1e-3, 400, [](double t) { return 4e-3 * t; });
  EXPECT_TRUE(internal::StuckRuns(slide, rule).empty());
  const std::vector<double> creep = Logged(1e-3, 400, [](double t) { return 1e-3 * t; });
  EXPECT_FALSE(internal::StuckRuns(creep, rule).empty());
}

// At 5 kHz the apex of a reversal without stick (10 m/s^2) stays within the
// band for about 5 ms, longer than the shortest phase (4 ms): its curvature
// says it is not stuck. The same apex a hundred times gentler is stuck.
TEST(StuckPhasesTest, TheApexOfAReversalIsNotStuck) {
  const auto apex = [](double acceleration) {
    return Logged(2e-4, 2000,
                  [acceleration](double t) { return -0.5 * acceleration * (t - 0.2) * (t - 0.2); });
  };
  EXPECT_TRUE(internal::StuckRuns(apex(10.0), Rule(2e-4)).empty());
  EXPECT_FALSE(internal::StuckRuns(apex(0.1), Rule(2e-4)).empty());
}

// At 1 kHz a rod that comes to rest from 100 um away (20 mm/s, slowing with
// a 5 ms time constant) and at 0.2 s accelerates away at 20 m/s^2: one stuck
// phase, which begins while the rod still slows down (inside the band, the
// fitted slope over the phase's first four fifths below 2 mm/s). The rod arrives within 3 sigma (6
// um) of its rest after 5 ms ln(100 / 6) = 14 ms, and leaves it after 0.2 s + 0.8 ms.
TEST(StuckPhasesTest, TheRodArrivesAfterThePhaseBeginsAndBreaksAwayWhereItLeavesItsRest) {
  const auto truth = [](double t) {
    return t < 0.2 ? -1e-4 * std::exp(-t / 0.005) : 10.0 * (t - 0.2) * (t - 0.2);
  };
  const std::vector<double> x = Logged(1e-3, 300, truth);
  const internal::Runs runs = internal::StuckRuns(x, Rule(1e-3));
  ASSERT_EQ(runs.size(), 1u);
  const std::size_t arrival = internal::ArrivalSample(x, runs[0], Rule(1e-3));
  EXPECT_GT(arrival, runs[0].first);
  EXPECT_NEAR(static_cast<double>(arrival), 14, 4);  // noise moves the crossing
  EXPECT_NEAR(static_cast<double>(internal::BreakawaySample(x, runs[0], Rule(1e-3))), 200, 1);
  EXPECT_NEAR(internal::RestPosition(x, runs[0]), 0.0, kSigmaM);
}

// A quantised log (20 um steps, 5 um of noise, 500 Hz) flickers by one step
// at rest, more than 3 sigma: the rest tolerance is 1.25 steps, so the
// breakaway is where the rod leaves its rest, not at the last flicker
// before it (with 3 sigma alone: sample 95, five samples early, where the
// force is lower and the slide's first samples look faster than they are).
TEST(StuckPhasesTest, AQuantisedRodFlickeringAtRestBreaksAwayWhereItLeavesItsRest) {
  constexpr double kStepM = 2e-5, kNoiseM = 5e-6, kPeriodS = 2e-3;
  std::vector<double> x(150);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double flicker = i % 7 == 3 ? kStepM : (i % 7 == 5 ? -kStepM : 0.0);
    const double slide = i < 100 ? 0.0 : 20.0 * std::pow((i - 99.5) * kPeriodS, 2);
    x[i] = i < 100 ? flicker : kStepM * std::round(slide / kStepM);
  }
  x[97] = -kStepM;  // the last readings at rest flicker
  x[98] = x[99] = kStepM;
  EXPECT_DOUBLE_EQ(internal::PositionQuantum(x), kStepM);
  const internal::StuckRule rule =
      internal::StuckRuleOf(FrictionFitOptions{}, kNoiseM, internal::PositionQuantum(x), kPeriodS);
  EXPECT_DOUBLE_EQ(rule.rest_tolerance_m, internal::kRestQuanta * kStepM);
  EXPECT_DOUBLE_EQ(
      internal::StuckRuleOf(FrictionFitOptions{}, kNoiseM, 0, kPeriodS).rest_tolerance_m,
      internal::kRestSigmas * kNoiseM);
  const internal::Runs runs = internal::StuckRuns(x, rule);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].first, 0u);
  const std::size_t breakaway = internal::BreakawaySample(x, runs[0], rule);
  EXPECT_GE(breakaway, 99u);
  EXPECT_LE(breakaway, 100u);
  EXPECT_EQ(internal::RestPosition(x, runs[0]), 0.0);
  // A log that is not quantised changes by far less than its noise somewhere.
  EXPECT_LT(internal::PositionQuantum(Logged(1e-3, 300, [](double) { return 0.0; })),
            0.1 * kSigmaM);
}

// A rod at rest halfway between two levels of a coarse position ADC (0.1 mm
// steps, 2 um of noise, 2 kHz) flickers between them at random: a span of
// 0.1 mm, wider than 25 um + 6 sigma. The band takes 1.25 quanta there, so
// the rest is one phase up to where the rod slides away (with 6 sigma
// alone: pieces of a few samples); at the sweep's quanta (at most 20 um for
// 5 um of noise) the band stays 25 um + 6 sigma.
TEST(StuckPhasesTest, ARestFlickeringBetweenTwoCoarseQuantaIsOnePhase) {
  constexpr double kStepM = 1e-4, kPeriodS = 5e-4;
  std::vector<double> x = Logged(kPeriodS, 600, [](double t) {
    return 0.5 * kStepM + (t < 0.2 ? 0.0 : 0.05 * (t - 0.2));  // 50 mm/s from 0.2 s
  });
  for (double& value : x) value = kStepM * std::round(value / kStepM);
  const double quantum = internal::PositionQuantum(x);
  ASSERT_NEAR(quantum, kStepM, 1e-12);  // (the lattice's levels rounded)
  const internal::StuckRule rule =
      internal::StuckRuleOf(FrictionFitOptions{}, kSigmaM, quantum, kPeriodS);
  EXPECT_NEAR(rule.band_m, FrictionFitOptions{}.stuck_band_m + internal::kRestQuanta * kStepM,
              1e-12);
  const internal::Runs runs = internal::StuckRuns(x, rule);
  ASSERT_FALSE(runs.empty());
  EXPECT_EQ(runs[0].first, 0u);
  EXPECT_GE(runs[0].second, 395u);
  EXPECT_LE(runs[0].second, 410u);
  const std::size_t breakaway = internal::BreakawaySample(x, runs[0], rule);
  EXPECT_GE(breakaway, 395u);
  EXPECT_LE(breakaway, 405u);
  std::size_t longest = 0;
  for (const auto& [begin, end] : internal::StuckRuns(x, Rule(kPeriodS)))
    longest = std::max(longest, end - begin);
  EXPECT_LT(longest, 100u);
  EXPECT_DOUBLE_EQ(internal::StuckRuleOf(FrictionFitOptions{}, 5e-6, 2e-5, kPeriodS).band_m,
                   FrictionFitOptions{}.stuck_band_m + 6 * 5e-6);
}

}  // namespace
}  // namespace pneumaid
