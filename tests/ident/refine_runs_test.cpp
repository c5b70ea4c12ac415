// The fitted runs of a refinement (src/ident/refine_runs.h): multiple
// shooting's windows, on a run made here (1 kHz, 2 um of seeded noise).
#include "../../src/ident/refine_runs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "../../src/ident/refine_verdict.h"
#include "../../src/ident/stuck_phases.h"
#include "pneumaid/ident/fit_spec.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/validate/lag_start.h"
#include "pneumaid/validate/logged_run.h"

namespace pneumaid {
namespace {

constexpr double kSigmaM = 2e-6;
constexpr double kPeriodS = 1e-3;
constexpr int kSamples = 700;

// The rod's true position: at rest at 0 for 0.1 s, a slide at 20 mm/s that
// slows into a rest at 2 mm (its last 100 um with a 5 ms time constant), a
// slide back at 20 mm/s from 0.4 s that slows into a rest at 0.2 mm. It
// arrives within 3 sigma (6 um) of each rest 5 ms ln(100 / 6) = 14 ms after
// it starts to slow down: at 0.209 s and 0.499 s.
double TruePosition(double t) {
  if (t < 0.1) return 0.0;
  if (t < 0.195) return 0.02 * (t - 0.1);
  if (t < 0.4) return 2e-3 - 1e-4 * std::exp(-(t - 0.195) / 0.005);
  if (t < 0.485) return TruePosition(0.4 - 1e-12) - 0.02 * (t - 0.4);
  return 2e-4 + 1e-4 * std::exp(-(t - 0.485) / 0.005);
}

// The run as logged; p1 and p2 rise by 1 kPa per sample, so that a window's
// start can be told from its pressures.
refine_internal::FitExperiment Logged() {
  refine_internal::FitExperiment run;
  run.id = "stroke";
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, kSigmaM);
  for (int i = 0; i < kSamples; ++i) {
    const double t = i * kPeriodS;
    run.measured.t_s.push_back(t);
    run.measured.u_V.push_back(0.5);
    run.measured.x_m.push_back(TruePosition(t) + noise(rng));
    run.measured.p1_Pa.push_back(3e5 + 1e3 * i);
    run.measured.p2_Pa.push_back(2e5 + 1e3 * i);
  }
  run.initial.position_m = 0.0;
  run.initial.p1_Pa = 3e5;
  run.initial.p2_Pa = 2e5;
  return run;
}

// The windows start at the log's start and where the rod arrived at each
// rest, at least 20 samples apart. A slow arrival may split a rest in two
// stuck phases (its first one holds the approach: here 490-518 and 518-700
// ms); each window still starts at its phase's arrival, from its median.
TEST(RefineRunsTest, AWindowStartsWhereTheRodArrivedAtEachRestFromThatRest) {
  const refine_internal::FitExperiment run = Logged();
  const std::vector<double>& x = run.measured.x_m;
  const std::vector<refine_internal::FitExperiment> windows =
      refine_internal::Windows(run, kSigmaM, 0.025, {0, 0});
  ASSERT_GE(windows.size(), 3u);  // the first rest holds the log's start
  // The first window is the run's start, as logged.
  EXPECT_EQ(windows[0].measured.t_s.front(), 0.0);
  EXPECT_EQ(windows[0].initial.position_m, run.initial.position_m);
  EXPECT_EQ(windows[0].initial.p1_Pa, run.initial.p1_Pa);
  const internal::StuckRule rule =
      internal::StuckRuleOf(FrictionFitOptions{}, kSigmaM, 0, kPeriodS);
  const internal::Runs phases = internal::StuckRuns(x, rule);
  std::size_t samples = windows[0].measured.size();
  for (std::size_t w = 1; w < windows.size(); ++w) {
    const refine_internal::FitExperiment& window = windows[w];
    const std::size_t begin = std::lround(window.measured.t_s.front() / kPeriodS);
    const auto phase = std::find_if(phases.begin(), phases.end(), [&](const auto& p) {
      return internal::ArrivalSample(x, p, rule) == begin;
    });
    ASSERT_NE(phase, phases.end()) << "window " << w << " starts at no arrival";
    EXPECT_EQ(window.initial.position_m, internal::RestPosition(x, *phase));
    EXPECT_EQ(window.initial.p1_Pa, run.measured.p1_Pa[begin]);
    EXPECT_EQ(window.initial.p2_Pa, run.measured.p2_Pa[begin]);
    EXPECT_EQ(window.initial.lag_history_from_s, 0.0);
    EXPECT_EQ(window.parent, "stroke");
    EXPECT_GE(window.measured.size(), 20u);
    // Contiguous: each window starts where the one before ended.
    EXPECT_EQ(begin, samples);
    samples += window.measured.size();
  }
  EXPECT_EQ(samples, x.size());
  // The arrivals in closed form, and the rests.
  EXPECT_NEAR(windows[1].measured.t_s.front(), 0.209, 0.004);
  EXPECT_NEAR(windows[1].initial.position_m, 2e-3, 3 * kSigmaM);
  EXPECT_NEAR(windows[2].measured.t_s.front(), 0.499, 0.004);
  EXPECT_NEAR(windows[2].initial.position_m, 2e-4, 3 * kSigmaM);
}

// A logger's pause of 0.2 s after 0.3 s cuts the run in two pieces, each
// from its own first samples, both counted with the run; so are the windows
// of a piece.
TEST(RefineRunsTest, ALoggersPauseCutsTheRunInPiecesOfTheRun) {
  refine_internal::FitExperiment run = Logged();
  for (std::size_t i = 300; i < run.measured.size(); ++i) run.measured.t_s[i] += 0.2;
  const RigConstants rig;
  EXPECT_EQ(refine_internal::Pieces(Logged(), rig, 0.025, {0, 0}).size(), 1u);
  const std::vector<refine_internal::FitExperiment> pieces =
      refine_internal::Pieces(run, rig, 0.025, {0, 0});
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(pieces[0].measured.size(), 300u);
  EXPECT_EQ(pieces[1].measured.size(), run.measured.size() - 300);
  EXPECT_EQ(pieces[1].measured.t_s.front(), run.measured.t_s[300]);
  // Its first samples while the pressures stay within 5 kPa (1 kPa per sample).
  EXPECT_NEAR(pieces[1].initial.p1_Pa, run.measured.p1_Pa[300], kStartPressureBand_Pa);
  EXPECT_EQ(pieces[1].command.initial_V, 0.5);
  for (const auto& piece : pieces) EXPECT_EQ(piece.parent, "stroke");
  for (const auto& window : refine_internal::Windows(pieces[1], kSigmaM, 0.025, {0, 0}))
    EXPECT_EQ(window.parent, "stroke");
}

// The bundled unit's validation profile (pneumaid synth, seed 1) logged from
// 3.3 s on, inside its ramp (the command rising through 0.09 V, chamber 1
// filling 2 kPa/ms), fitted as a run: its valves' lags are read off its
// first 100 ms as validation reads them (lag_start.h), and the truth
// explains it: median reduced chi-square 3.3; started settled for the first
// command, as before, 2.4e4.
TEST(RefineRunsTest, ARunCutMidRunStartsWithTheLagsItsFirstSamplesShow) {
  const std::string dir = std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig";
  const Parameters truth = LoadParams(dir + "/truth.yaml");
  const FitSpec spec = ParseFitSpec(R"(format: pneumaid-fit/1
parameters:
  friction.negative.Fd: {min: 0.5, max: 20}
channels: {x: {}, p1: {}, p2: {}}
experiments: {fit: [profile-1], hold_out: []}
)",
                                    "profile.yaml");
  Unit cut = ReadUnit(dir);
  for (Experiment& e : cut.experiments) {
    if (e.entry.id != "profile-1") continue;
    const std::vector<double>& t = e.columns.at("t");
    const auto first = std::lower_bound(t.begin(), t.end(), 3.3) - t.begin();
    for (auto& [name, column] : e.columns) column.erase(column.begin(), column.begin() + first);
    const double t0 = e.columns.at("t").front();
    for (double& ti : e.columns.at("t")) ti -= t0;
  }
  const Parameters conditioned = WithRigConditions(truth, cut);
  const std::map<std::string, LagStart> read =
      refine_internal::ReadLagStarts(conditioned, cut, spec, SimulationOptions{});
  ASSERT_EQ(read.count("profile-1"), 1u);
  // Without them it starts as logged: no history, the lags settled.
  EXPECT_TRUE(std::isnan(refine_internal::FittedRuns(conditioned, cut, spec, false, nullptr)[0]
                             .initial.lag_history_from_s));
  const std::vector<refine_internal::FitExperiment> runs =
      refine_internal::FittedRuns(conditioned, cut, spec, false, &read);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_NEAR(runs[0].initial.lag_history_from_s, -kLagHistory_s, 1e-12);
  ASSERT_FALSE(runs[0].command.time_s.empty());
  EXPECT_LT(runs[0].command.time_s.front(), 0.0);  // the read history before the log
  // Its windows replay the lags from the history's start too.
  for (const auto& window : refine_internal::Windows(runs[0], 5e-6, 0.025, {0, 0}))
    EXPECT_NEAR(window.initial.lag_history_from_s, -kLagHistory_s, 1e-12);
  // EvaluateFit reads them at the set it evaluates: 3.34 (the whole
  // profile's stick-slip: 36.4).
  EXPECT_LT(EvaluateFit(truth, cut, spec, RefineOptions{}).reduced_chi_square, 10.0);
}

// A rest beyond the model's stroke (a rod on its stop reads a few sigma past
// it) starts its window at the stop.
TEST(RefineRunsTest, AWindowStartsWithinTheStroke) {
  const std::vector<refine_internal::FitExperiment> windows =
      refine_internal::Windows(Logged(), kSigmaM, 1.5e-3, {0, 0});
  ASSERT_EQ(windows.size(), 3u);
  EXPECT_EQ(windows[1].initial.position_m, 1.5e-3);
}

}  // namespace
}  // namespace pneumaid
