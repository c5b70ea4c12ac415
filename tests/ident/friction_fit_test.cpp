// Recovery of the Stribeck friction from synthetic stroke logs with a known
// truth, both orientations, and honest standard errors over seeds.
#include "pneumaid/ident/friction_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <random>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "../synth/synth_test_util.h"
#include "friction_test_util.h"
#include "pneumaid/io/log_notes.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/protocol.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid {
namespace {

Unit SyntheticStrokes(const Parameters& truth, std::uint64_t seed, int cycles = 3) {
  return testing::WriteAndReadUnit(Synthesize(truth, testing::StrokeProtocol(cycles), seed, "F"),
                                   "friction_fit_" + std::to_string(seed));
}

// The tolerances, per coefficient in the order Fs, Fd, b, vs: 5 % or
// 0.1 N; 5 % or 0.1 N; 15 % or 0.5 N s/m; 25 % or 1 mm/s.
const char* const kNames[] = {"Fs", "Fd", "b", "vs"};
std::array<double, 4> Values(const StribeckParams& p) {
  return {p.static_force_N, p.dynamic_force_N, p.viscous_N_s_per_m, p.stribeck_velocity_m_per_s};
}
double Tolerance(int i, double truth) {
  const double fraction[] = {0.05, 0.05, 0.15, 0.25}, floor[] = {0.1, 0.1, 0.5, 1e-3};
  return std::max(fraction[i] * std::fabs(truth), floor[i]);
}

void ExpectWithinTolerance(const StribeckParams& fit, const StribeckParams& truth,
                           const char* direction) {
  const auto values = Values(fit), real = Values(truth);
  for (int i = 0; i < 4; ++i)
    EXPECT_NEAR(values[i], real[i], Tolerance(i, real[i])) << direction << " " << kNames[i];
}

// The truth's coefficients of `direction` ("positive" or "negative"), in
// kNames' order.
std::array<double, 4> TruthOf(const Parameters& truth, const std::string& direction) {
  return Values(direction == "positive" ? truth.friction.positive : truth.friction.negative);
}

using testing::ThirtyPercentOff;

// The coefficient "friction.<direction>.<name>" of a fit (every fit lists all eight).
const FittedCoefficient& Coefficient(const FrictionFitResult& fit, const std::string& direction,
                                     const std::string& name) {
  const FittedCoefficient* c = fit.Find("friction." + direction + "." + name);
  if (c == nullptr) throw std::logic_error("no coefficient friction." + direction + "." + name);
  return *c;
}

// How many of a direction's coefficients the logs determined.
int Determined(const FrictionFitResult& fit, const std::string& direction) {
  int count = 0;
  for (const char* name : {"Fs", "Fd", "b", "vs"})
    count += Coefficient(fit, direction, name).determined();
  return count;
}

// The fit of `unit` from 30 % off the truth recovers it; the fit in `out`.
void ExpectRecoveryFrom(const Unit& unit, const Parameters& truth,
                        FrictionFitResult* out = nullptr) {
  const FrictionFitResult fit =
      FitFriction(unit, ThirtyPercentOff(truth.friction), FrictionFitOptions{});
  if (out != nullptr) *out = fit;
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  ASSERT_GT(Determined(fit, "positive"), 0);
  ASSERT_GT(Determined(fit, "negative"), 0);
  ExpectWithinTolerance(fit.positive.params, truth.friction.positive, "positive");
  ExpectWithinTolerance(fit.negative.params, truth.friction.negative, "negative");
  EXPECT_GT(fit.excluded_segments, 0);  // stroke ends with slides mid-stroke are left out
  EXPECT_LT(fit.position_rms_m, 20e-6);
}

// Whether every stroke log of `unit` is on a clock that keeps no time (the
// friction fit replays it at its logged times) or not.
void ExpectStrokeClocks(const Unit& unit, bool irregular) {
  for (const Experiment& e : unit.experiments) {
    if (e.entry.kind != ExperimentKind::kStroke) continue;
    EXPECT_EQ(IrregularClock(e.column("t")), irregular) << e.entry.id;
  }
}

void ExpectRecovery(const Parameters& truth, std::uint64_t seed) {
  ExpectRecoveryFrom(SyntheticStrokes(truth, seed), truth);
}

TEST(FrictionFitTest, RecoversBothDirectionsOfAVerticalCylinder) {
  ExpectRecovery(Parameters{}, 21);
}

// Not yet met for every coefficient (issue 4 stays open): on this unit the
// negative direction's Fd and b, correlated at -0.99, come out about two
// standard errors off (2.80 and 8.65 for 3 and 7), outside the 5 % /
// 15 %. What the test holds: Fs and vs within the tolerances, and the
// sliding friction Fd + b |v| at 0.1 m/s, which the logs do determine, within 3 %.
TEST(FrictionFitTest, RecoversAHorizontalCylindersBreakawayAndSlidingFriction) {
  Parameters truth =
      LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper-horizontal.yaml");
  // Different coefficients per direction, so that a swap would show.
  truth.friction.positive = {8.0, 1.5, 4.0, 0.015};
  truth.friction.negative = {12.0, 3.0, 7.0, 0.008};
  const FrictionFitResult fit = FitFriction(SyntheticStrokes(truth, 22),
                                            ThirtyPercentOff(truth.friction), FrictionFitOptions{});
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  for (const auto& [fitted, exact] :
       {std::make_pair(&fit.positive.params, &truth.friction.positive),
        std::make_pair(&fit.negative.params, &truth.friction.negative)}) {
    EXPECT_NEAR(fitted->static_force_N, exact->static_force_N, 0.05 * exact->static_force_N);
    EXPECT_NEAR(fitted->stribeck_velocity_m_per_s, exact->stribeck_velocity_m_per_s,
                0.25 * exact->stribeck_velocity_m_per_s);
    const auto sliding = [](const StribeckParams& p) {
      return p.dynamic_force_N + p.viscous_N_s_per_m * 0.1;
    };
    EXPECT_NEAR(sliding(*fitted), sliding(*exact), 0.03 * sliding(*exact));
  }
}

// A lossy logger drops 2 % of the rows of every stroke log, so no log is
// sampled uniformly. Each is read on a uniform clock at its median interval
// (interpolated across the gaps) and the fit recovers the vertical cylinder
// as from complete logs; before, every stroke log was skipped ("not
// uniformly sampled") and no slide was found.
TEST(FrictionFitTest, ALoggerThatDropsRowsIsReadOnAUniformClock) {
  const Parameters truth;
  Protocol protocol = testing::StrokeProtocol(3);
  protocol.dropped_samples = 0.02;
  const Unit unit =
      testing::WriteAndReadUnit(Synthesize(truth, protocol, 21, "D"), "friction_dropped_21");
  std::size_t gaps = 0;
  for (const Experiment& e : unit.experiments) {
    const auto& t = e.column("t");
    for (std::size_t i = 2; i < t.size(); ++i) gaps += t[i] - t[i - 1] > 1.5 * (t[1] - t[0]);
  }
  EXPECT_GT(gaps, 100u);
  ExpectStrokeClocks(unit, false);  // a uniform clock that lost rows
  FrictionFitResult fit;
  ExpectRecoveryFrom(unit, truth, &fit);
  EXPECT_EQ(fit.reason.find("not used"), std::string::npos) << fit.reason;
}

// A logger whose loop does not keep time: every interval 0.6 to 1.4 ms (the
// rig's command changes at its rows). The replays step from row to row as
// logged and the slides' v and a are a quadratic in time, so the fit recovers
// the vertical cylinder as from a uniform clock. Read on a uniform clock at
// the median interval instead (interpolated), the positive vs came out 32 %
// low and the negative 47 % (a fleet unit, session 51).
// A logger whose intervals spread by +-40 % and that loses `dropped` of its
// rows: its stroke logs are replayed at their logged times and the paper
// rod's friction recovered.
void ExpectRecoveryFromAnIrregularClock(double dropped, std::uint64_t seed,
                                        const std::string& name) {
  const Parameters truth;
  Protocol protocol = testing::StrokeProtocol(3);
  protocol.clock_jitter = 0.4;
  protocol.dropped_samples = dropped;
  const Unit unit = testing::WriteAndReadUnit(Synthesize(truth, protocol, seed, "J"), name);
  ExpectStrokeClocks(unit, true);
  ExpectRecoveryFrom(unit, truth);
}

TEST(FrictionFitTest, AnIrregularClockIsReplayedAtItsLoggedTimes) {
  ExpectRecoveryFromAnIrregularClock(0.0, 21, "friction_jitter_21");
}

// The same logger losing 1 % of its rows: still replayed at its logged times
// (a lost row an interval twice as long). Read on a uniform clock, as a
// uniform logger that loses rows is, the negative vs came out 41 % low over
// ten such units (a probe's, session 51).
TEST(FrictionFitTest, AnIrregularClockThatLosesRowsIsReplayedAtItsLoggedTimes) {
  ExpectRecoveryFromAnIrregularClock(0.01, 8, "friction_jitter_lossy_8");
}

TEST(FrictionFitTest, StandardErrorsAreHonestOverTenSeeds) {
  const Parameters truth;
  const FrictionParams prior = ThirtyPercentOff(truth.friction);
  int inside = 0, total = 0;
  double sum_sq = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const FrictionFitResult fit =
        FitFriction(SyntheticStrokes(truth, 100 + seed, 1), prior, FrictionFitOptions{});
    ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
    for (const auto& [direction, fitted, exact] :
         {std::make_tuple("positive", &fit.positive, &truth.friction.positive),
          std::make_tuple("negative", &fit.negative, &truth.friction.negative)}) {
      const double values[4] = {fitted->params.static_force_N, fitted->params.dynamic_force_N,
                                fitted->params.viscous_N_s_per_m,
                                fitted->params.stribeck_velocity_m_per_s};
      const double truths[4] = {exact->static_force_N, exact->dynamic_force_N,
                                exact->viscous_N_s_per_m, exact->stribeck_velocity_m_per_s};
      const char* names[4] = {"Fs", "Fd", "b", "vs"};
      for (int i = 0; i < 4; ++i) {
        const double z =
            (values[i] - truths[i]) / Coefficient(fit, direction, names[i]).standard_error;
        std::cout << "seed " << seed << " " << names[i] << " z " << z << "\n";
        inside += std::fabs(z) <= 3;
        sum_sq += z * z;
        ++total;
      }
    }
  }
  const double spread = std::sqrt(sum_sq / total);
  std::cout << "within 3 SE: " << inside << "/" << total << ", z spread " << spread << "\n";
  EXPECT_GE(inside, 0.9 * total);
  EXPECT_GE(spread, 0.5);
  EXPECT_LE(spread, 2.0);
}

TEST(FrictionFitTest, ADirectionWithoutSlidesKeepsThePriorAndSaysSo) {
  Unit unit = SyntheticStrokes(Parameters{}, 5, 1);
  // Keep only the extending halves: cut every log where the command turns negative.
  for (Experiment& e : unit.experiments) {
    const auto& u = e.columns.at("u");
    std::size_t end = 0;
    while (end < u.size() && u[end] >= 0) ++end;
    for (auto& [name, column] : e.columns) column.resize(end);
  }
  FrictionParams prior;
  prior.negative.static_force_N = 7.0;
  const FrictionFitResult fit = FitFriction(unit, prior, FrictionFitOptions{});
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_GT(Determined(fit, "positive"), 0);
  EXPECT_EQ(Determined(fit, "negative"), 0);
  EXPECT_EQ(fit.negative.params.static_force_N, 7.0);
  for (const char* name : {"Fs", "Fd", "b", "vs"}) {
    EXPECT_EQ(Coefficient(fit, "negative", name).held, "no slide this way") << name;
    EXPECT_EQ(Coefficient(fit, "negative", name).standard_error, 0.0) << name;
  }
  EXPECT_NE(fit.BriefReport().find("no slide this way"), std::string::npos);
}

TEST(FrictionFitTest, ADisturbedSlideIsBoundedByTheRobustLoss) {
  const Parameters truth;
  Unit unit = SyntheticStrokes(truth, 7);
  // A knock on the rod: 0.3 mm added to 30 samples in the middle of a log.
  auto& x = unit.experiments[2].columns.at("x");
  for (std::size_t i = x.size() / 3; i < x.size() / 3 + 30; ++i) x[i] += 3e-4;
  const FrictionFitResult fit =
      FitFriction(unit, ThirtyPercentOff(truth.friction), FrictionFitOptions{});
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_GE(fit.outlier_segments, 1);
  EXPECT_NEAR(fit.positive.params.static_force_N, 10.0, 0.5);
  EXPECT_NEAR(fit.negative.params.static_force_N, 10.0, 0.5);
  EXPECT_NEAR(fit.negative.params.dynamic_force_N, 5.0, 0.25);
}

// Logs the fitted model did not make: stick as a smooth law (creep below
// 0.1 mm/s), integrated at rtol 1e-8, the rod logged at `rate_Hz` with 10 um
// quantisation, strokes at `levels`.
Unit MismatchedStrokes(const Parameters& truth, std::uint64_t seed, double rate_Hz,
                       std::vector<double> levels, int cycles, double margin_m = -1) {
  Protocol protocol = testing::MismatchedStrokeProtocol(cycles, std::move(levels));
  protocol.sample_rate_Hz = rate_Hz;
  if (margin_m >= 0) protocol.stroke_margin_m = margin_m;
  return testing::WriteAndReadUnit(Synthesize(truth, protocol, seed, "M"),
                                   "friction_mismatch_" + std::to_string(seed));
}

// `base` with `mass_kg` and this friction.
Parameters WithLoad(Parameters base, double mass_kg, const StribeckParams& positive,
                    const StribeckParams& negative) {
  base.cylinder.load_mass_kg = mass_kg;
  base.friction.positive = positive;
  base.friction.negative = negative;
  return base;
}

// The paper's horizontal cylinder with `mass_kg` and this friction.
Parameters HorizontalTruth(double mass_kg, const StribeckParams& positive,
                           const StribeckParams& negative) {
  return WithLoad(LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper-horizontal.yaml"),
                  mass_kg, positive, negative);
}

// The paper's vertical cylinder with `mass_kg` and this friction.
Parameters VerticalTruth(double mass_kg, const StribeckParams& positive,
                         const StribeckParams& negative) {
  return WithLoad(Parameters{}, mass_kg, positive, negative);
}

// Every coefficient is within the tolerances (vs, with `errors` > 0, also
// within that many of its standard errors) or reported as held, never a
// wrong value with a small error; `fitted` names those that must be fitted.
void ExpectWithinToleranceOrHeld(const FrictionFitResult& result, const char* direction,
                                 const StribeckParams& truth,
                                 const std::vector<std::string>& fitted, double errors = 0) {
  const StribeckParams& params =
      std::string(direction) == "positive" ? result.positive.params : result.negative.params;
  const auto values = Values(params), real = Values(truth);
  for (int i = 0; i < 4; ++i) {
    const FittedCoefficient& c = Coefficient(result, direction, kNames[i]);
    EXPECT_EQ(c.value, values[i]);
    const bool held = !c.determined();
    EXPECT_EQ(held, c.standard_error == 0) << direction << " " << kNames[i];
    if (std::find(fitted.begin(), fitted.end(), kNames[i]) != fitted.end()) {
      EXPECT_FALSE(held) << direction << " " << kNames[i] << ": " << c.held;
    }
    if (held) continue;
    const double error_allowance = i == 3 ? errors * c.standard_error : 0.0;  // vs only
    EXPECT_NEAR(values[i], real[i], std::max(Tolerance(i, real[i]), error_allowance))
        << direction << " " << kNames[i];
  }
}

// The heavy-load case: a horizontal 1.5 kg load slides through the
// stroke without stick-slip: no stuck phase mid-stroke, so the sliding
// friction comes from the force balance and Fs (and the Stribeck drop after
// it) from the breakaways at the stops. Fs and vs are poorly separable there:
// vs within tolerance or within two of its standard errors.
TEST(FrictionFitTest, AHeavyLoadThatNeverSticksMidStrokeGetsItsFrictionFromSlidesAndStops) {
  const Parameters truth = HorizontalTruth(1.5, {8.0, 2.0, 6.0, 0.012}, {12.0, 4.0, 12.0, 0.006});
  const Unit unit = MismatchedStrokes(truth, 7, 2000, {0.6, 1.0}, 1);
  const FrictionFitResult fit = FitFriction(unit, FrictionParams{}, FrictionFitOptions{});
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_GT(fit.smooth_samples, 1000);
  ExpectWithinToleranceOrHeld(fit, "positive", truth.friction.positive, {"Fs", "Fd", "b"}, 2);
  ExpectWithinToleranceOrHeld(fit, "negative", truth.friction.negative, {"Fs", "Fd", "b"}, 2);
}

// Two stroke cycles at 0.4, 0.6 and 0.8 V (model mismatch) whose instruments
// `lagged` lag tau_s, declared in the manifest.
Unit LaggedStrokes(const Parameters& truth, const std::vector<std::string>& lagged, double tau_s,
                   std::uint64_t seed, const std::string& dir) {
  Protocol protocol = testing::MismatchedStrokeProtocol(2, {0.4, 0.6, 0.8});
  for (const std::string& column : lagged) protocol.sensors[column].tau_s = tau_s;
  Unit unit = testing::WriteAndReadUnit(Synthesize(truth, protocol, seed, "L"), dir);
  for (const std::string& column : lagged)
    EXPECT_DOUBLE_EQ(unit.manifest.DeclaredTau(column, 0), tau_s) << column;
  return unit;
}

// The friction fit of `unit` with the lags of `lagged` left undeclared: the
// logs read as they are logged.
FrictionFitResult FitAsLogged(Unit unit, const std::vector<std::string>& lagged) {
  for (const std::string& column : lagged) unit.manifest.sensors[column].tau_s.reset();
  FrictionFitResult fit = FitFriction(unit, FrictionParams{}, FrictionFitOptions{});
  std::cout << fit.BriefReport();
  return fit;
}

// Pressure transmitters with a declared 5 ms lag on a 1.4 kg horizontal rod
// at 1 kHz: the replays are driven by the pressures as they were, the lag
// undone (src/ident/meter_lag.h). Read as they are logged (the same unit with
// the lag left undeclared) the positive Fs comes 22 % low, b 30 % high and vs
// 68 % high.
TEST(FrictionFitTest, ADeclaredPressureLagIsUndoneBeforeTheReplays) {
  const Parameters truth = HorizontalTruth(1.4, {10.0, 0.5, 5.0, 0.01}, {10.0, 5.0, 5.0, 0.01});
  const Unit unit = LaggedStrokes(truth, {"p1", "p2"}, 5e-3, 6, "friction_pressure_lag");
  const FrictionFitResult fit = FitFriction(unit, FrictionParams{}, FrictionFitOptions{});
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  for (const auto& [direction, params, real] :
       {std::make_tuple("positive", fit.positive.params, truth.friction.positive),
        std::make_tuple("negative", fit.negative.params, truth.friction.negative)}) {
    const auto values = Values(params), expected = Values(real);
    for (int i = 0; i < 3; ++i) {  // Fs, Fd and b; vs within 40 %
      EXPECT_NEAR(values[i], expected[i], Tolerance(i, expected[i])) << direction << kNames[i];
    }
    EXPECT_NEAR(values[3], expected[3], 0.4 * expected[3]) << direction;
  }
  EXPECT_LT(FitAsLogged(unit, {"p1", "p2"}).positive.params.static_force_N, 9.0);
}

// The same for a position transducer's lag (a 3 ms filter at 1 kHz): the
// replays and the stuck phases read x with it undone. Read as logged, a light
// rod's replays lag the log by a slip (position RMS 0.23 mm for 0.016: the
// refinement then starts outside the basin and the unit is "not explained").
TEST(FrictionFitTest, ADeclaredPositionLagIsUndoneBeforeTheReplays) {
  const Parameters truth = HorizontalTruth(0.15, {10.0, 0.5, 5.0, 0.01}, {10.0, 5.0, 5.0, 0.01});
  const Unit unit = LaggedStrokes(truth, {"x"}, 3e-3, 3, "friction_position_lag");
  const FrictionFitResult fit = FitFriction(unit, FrictionParams{}, FrictionFitOptions{});
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_LT(fit.position_rms_m, 4e-5);
  for (const auto& [direction, params, real] :
       {std::make_tuple("positive", fit.positive.params, truth.friction.positive),
        std::make_tuple("negative", fit.negative.params, truth.friction.negative)}) {
    EXPECT_NEAR(params.static_force_N, real.static_force_N, Tolerance(0, real.static_force_N))
        << direction;
  }
  EXPECT_GT(FitAsLogged(unit, {"x"}).position_rms_m, 1e-4);
}

// The fit without the breakaways from the stops (end_slide_m = 0), then with.
std::pair<FrictionFitResult, FrictionFitResult> FitWithoutAndWithStops(
    const Unit& unit, const FrictionFitOptions& options = {}) {
  FrictionFitOptions mid_stroke_only = options;
  mid_stroke_only.end_slide_m = 0;
  FrictionFitResult without = FitFriction(unit, FrictionParams{}, mid_stroke_only);
  FrictionFitResult with = FitFriction(unit, FrictionParams{}, options);
  std::cout << without.BriefReport() << with.BriefReport();
  return {std::move(without), std::move(with)};
}

// Strokes that run from stop to stop with a heavy vertical rod, the common
// protocol of a rig engineer: the rod never sticks mid-stroke, so every
// breakaway is one from an end stop. Replayed over their first end_slide_m,
// those give each direction's Fs (and the Stribeck drop after it); without
// them (end_slide_m = 0) Fs is held or known no better than its tolerance.
TEST(FrictionFitTest, StrokesFromStopToStopGetFsFromTheBreakawaysAtTheStops) {
  const Parameters truth = VerticalTruth(0.75, {11.3, 0.2, 14.7, 0.018}, {15.2, 4.4, 8.8, 0.004});
  const Unit unit = MismatchedStrokes(truth, 11, 5000, {0.45, 0.7, 0.95}, 2, 0.0);
  const auto [held, fit] = FitWithoutAndWithStops(unit);
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  // Without the stops each Fs is held or known no better than its tolerance.
  for (const char* direction : {"positive", "negative"}) {
    const FittedCoefficient& without = Coefficient(held, direction, "Fs");
    const FittedCoefficient& with = Coefficient(fit, direction, "Fs");
    const double tolerance =
        Tolerance(0, Values(direction == std::string("positive") ? truth.friction.positive
                                                                 : truth.friction.negative)[0]);
    EXPECT_TRUE(!without.determined() || without.standard_error > tolerance) << direction;
    EXPECT_TRUE(with.determined()) << direction;
    EXPECT_LT(with.standard_error, tolerance) << direction;
  }
  ExpectWithinToleranceOrHeld(fit, "positive", truth.friction.positive, {"Fs", "Fd", "b", "vs"});
  ExpectWithinToleranceOrHeld(fit, "negative", truth.friction.negative, {"Fs", "Fd", "b", "vs"});
}

// A position transducer zeroed off (x logged 0.3 mm low, or 1 mm high; the
// rests at the stops show it, ReadPositionZero) is read less its zero, as
// refinement and validation read it: the stops, the end zones and the
// replays from a stop are where the rod was. Read as logged, the bundled
// unit's positive Fs came out 18.6 N for 10 at -0.3 mm, and the negative Fs
// 14.0 N at +1 mm, both "converged".
TEST(FrictionFitTest, ATransducersZeroIsTakenOffBeforeTheStops) {
  const std::string dir = std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig";
  const Unit unit = ReadUnit(dir);
  const Parameters truth = LoadParams(dir + "/truth.yaml");
  const FrictionFitResult as_zeroed = FitFriction(unit, Parameters{}.friction, {});
  for (const double offset_m : {-3e-4, 1e-3}) {
    const FrictionFitResult fit =
        FitFriction(testing::WithPositionOffset(unit, offset_m), Parameters{}.friction, {});
    ASSERT_EQ(fit.status, FitStatus::kConverged) << offset_m << ": " << fit.reason;
    ExpectWithinTolerance(fit.positive.params, truth.friction.positive, "positive");
    ExpectWithinTolerance(fit.negative.params, truth.friction.negative, "negative");
    const auto values = Values(fit.positive.params), zeroed = Values(as_zeroed.positive.params);
    const auto negative = Values(fit.negative.params);
    const auto negative_zeroed = Values(as_zeroed.negative.params);
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(values[i], zeroed[i], 0.01 * std::fabs(zeroed[i])) << offset_m << kNames[i];
      EXPECT_NEAR(negative[i], negative_zeroed[i], 0.01 * std::fabs(negative_zeroed[i]))
          << offset_m << kNames[i];
    }
  }
}

// A logger whose clock stamps each row up to 2 % of an interval off its 1 ms
// grid (the rows themselves sampled on it): the logs are read on that grid,
// and the fit is the one from the exact stamps. Before, a stamp 1 % off sent
// the log to the uniform clock at its median interval, whose interpolation
// took the negative vs 16 to 37 % low (a fleet unit, +-8 to 20 us).
TEST(FrictionFitTest, TimeStampsWithJitterAreReadOnTheLoggersGrid) {
  const Parameters truth = VerticalTruth(0.4, {8.3, 0.7, 9.1, 0.012}, {11.4, 5.2, 4.7, 0.009});
  const Unit exact = MismatchedStrokes(truth, 31, 1000, {0.45, 0.7, 0.95}, 2);
  Unit jittered = exact;
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> jitter(-0.02e-3, 0.02e-3);
  for (Experiment& e : jittered.experiments) {
    std::vector<double>& t = e.columns.at("t");
    for (std::size_t i = 1; i + 1 < t.size(); ++i) t[i] += jitter(rng);
  }
  const FrictionFitResult a = FitFriction(exact, FrictionParams{}, FrictionFitOptions{});
  const FrictionFitResult b = FitFriction(jittered, FrictionParams{}, FrictionFitOptions{});
  std::cout << a.BriefReport() << b.BriefReport();
  ASSERT_EQ(b.status, FitStatus::kConverged) << b.reason;
  for (const auto& [mine, theirs] : {std::make_pair(&b.positive.params, &a.positive.params),
                                     std::make_pair(&b.negative.params, &a.negative.params)}) {
    const auto got = Values(*mine), want = Values(*theirs);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(got[i], want[i], 1e-6 * std::fabs(want[i])) << i;
  }
}

// A light horizontal rod at low commands, strokes into the stops: the few
// slides that break away mid-stroke one way leave that direction's Fs
// undetermined, so the fit runs again with the breakaways from the stops.
// Replayed in 8 RK4 steps per sample interval: in the default 4 (1 kHz) the
// mid-stroke slides alone give the negative Fs here (4.84 +- 0.08 N for 5.0),
// and the stops are not needed.
TEST(FrictionFitTest, AnFsTheMidStrokeSlidesLeaveOpenIsReadAtTheStops) {
  const Parameters truth =
      HorizontalTruth(0.14, {6.1, 1.77, 4.4, 0.0133}, {5.0, 0.77, 13.7, 0.0025});
  Unit unit = MismatchedStrokes(truth, 1, 1000, {0.31, 0.36, 0.4}, 3, 0.0);
  FrictionFitOptions eight_steps;
  eight_steps.replay_step_s = 1e-3 / 8;
  const auto [held, fit] = FitWithoutAndWithStops(unit, eight_steps);
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_GE(held.negative.segments, 3);  // enough to count, too few to tell Fs
  EXPECT_FALSE(Coefficient(held, "negative", "Fs").determined());
  EXPECT_TRUE(Coefficient(fit, "negative", "Fs").determined());
  EXPECT_GT(fit.negative.segments, held.negative.segments);  // fitted again with the stops
  ExpectWithinToleranceOrHeld(fit, "positive", truth.friction.positive, {"Fs", "Fd", "b"});
  // The negative vs is not checked: read through the stops' short replays it
  // comes out 0.44 +- 0.4 mm/s for 2.5 (docs/identification.md).
  const auto values = Values(fit.negative.params), real = Values(truth.friction.negative);
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(Coefficient(fit, "negative", kNames[i]).determined()) << kNames[i];
    EXPECT_NEAR(values[i], real[i], Tolerance(i, real[i])) << "negative " << kNames[i];
  }
}

TEST(FrictionFitTest, ADirectionWithAnUndeterminedVsStillGetsItsSlidingFriction) {
  Parameters truth =
      LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper-horizontal.yaml");
  truth.friction.negative = {6.0, 5.95, 3.0, 0.02};
  const Unit unit = MismatchedStrokes(truth, 6, 1000, {0.5, 0.7, 1.0}, 2);
  const FrictionFitResult fit = FitFriction(unit, FrictionParams{}, FrictionFitOptions{});
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  for (const char* name : {"Fd", "b"})
    EXPECT_TRUE(Coefficient(fit, "negative", name).determined()) << name;
  EXPECT_NEAR(fit.negative.params.dynamic_force_N, 5.95, 0.05 * 5.95);
  EXPECT_NEAR(fit.negative.params.viscous_N_s_per_m, 3.0, 0.5);
  EXPECT_EQ(Determined(fit, "positive"), 4);
  EXPECT_NEAR(fit.positive.params.static_force_N, 10.0, 0.5);
}

// How many of the eight coefficients are within the tolerances.
int WithinTolerance(const FrictionFitResult& fit, const FrictionParams& truth) {
  int count = 0;
  for (int d = 0; d < 2; ++d) {
    const auto values = Values(d == 0 ? fit.positive.params : fit.negative.params);
    const auto real = Values(d == 0 ? truth.positive : truth.negative);
    for (int i = 0; i < 4; ++i) count += std::fabs(values[i] - real[i]) <= Tolerance(i, real[i]);
  }
  return count;
}

// A light rod with a strong Stribeck drop slips violently and gives no
// smooth slide, so Fd, b and vs start from the prior; from a prior far off
// (Fd 6 N where the truth has 0.71, vs 4 mm/s for 24) the replay fit ends in
// another basin. The screen of starts finds the truth's. (Before the
// breakaway was read where the rod leaves its rest, even the paper's prior
// failed here: Fs started where the slip was a quarter done.)
TEST(FrictionFitTest, TheStartScreenFindsTheBasinOfALightRodThatSticksAndSlips) {
  const Parameters truth =
      HorizontalTruth(0.14, {20.0, 0.71, 12.5, 0.0236}, {16.0, 4.96, 9.0, 0.0224});
  const Unit unit = MismatchedStrokes(truth, 2, 2000, {0.5, 0.7, 0.9}, 1, 0.0);
  FrictionParams prior;
  prior.positive = {10.0, 6.0, 2.0, 0.004};
  prior.negative = {10.0, 0.5, 2.0, 0.004};
  // Replayed in 8 RK4 steps per sample interval, as the sweep's unit was
  // when this was written: in the default 2 (2 kHz) the fit without the
  // screen finds this basin too.
  FrictionFitOptions screened;
  screened.replay_step_s = 0.5e-3 / 8;
  FrictionFitOptions unscreened = screened;
  unscreened.screen_starts = false;
  const FrictionFitResult plain = FitFriction(unit, prior, unscreened);
  std::cout << plain.BriefReport();
  EXPECT_LE(WithinTolerance(plain, truth.friction), 5);
  const FrictionFitResult fit = FitFriction(unit, prior, screened);
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_EQ(fit.start_screen.candidates, 144);
  EXPECT_TRUE(fit.start_screen.used);
  EXPECT_NE(fit.BriefReport().find("start screened (144 candidates)"), std::string::npos);
  EXPECT_EQ(WithinTolerance(fit, truth.friction), 8);
  ExpectWithinToleranceOrHeld(fit, "positive", truth.friction.positive, {"Fs", "Fd", "b", "vs"});
  ExpectWithinToleranceOrHeld(fit, "negative", truth.friction.negative, {"Fs", "Fd", "b", "vs"});
}

// A heavy vertical rod with a strong Stribeck drop, logged at 500 Hz: each
// stroke breaks away from rest and slides for 0.1 s. A forward replay is
// then off by the velocity error of a slightly misplaced escape (0.2 mm at
// the true coefficients on noise-free logs), which weights for the force's
// noise alone read as friction (on the sweep's unit of this kind: b 25 N s/m
// and Fd 0 for 12.2 and 1.1). With the escape's timing error in the weights
// the force balance of the slides carries Fd and b.
TEST(FrictionFitTest, AHeavyRodLoggedAt500HzGetsItsSlidingFriction) {
  const Parameters truth =
      VerticalTruth(1.15, {19.9, 1.12, 12.2, 0.0045}, {10.7, 0.67, 7.3, 0.0022});
  const Unit unit = MismatchedStrokes(truth, 3, 500, {0.5, 0.7, 0.9}, 2, 0.005);
  FrictionFitOptions untimed;
  untimed.breakaway_timing_per_s = 0;
  const FrictionFitResult plain = FitFriction(unit, FrictionParams{}, untimed);
  std::cout << plain.BriefReport();
  EXPECT_GT(std::fabs(plain.positive.params.viscous_N_s_per_m - 12.2), Tolerance(2, 12.2));
  const FrictionFitResult fit = FitFriction(unit, FrictionParams{}, FrictionFitOptions{});
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  // vs is not checked: it trades off with Fs at -0.995 in both directions
  // here (the slides leave the Stribeck region within a sample or two), and
  // the refinement through the simulator is what places it.
  for (const char* direction : {"positive", "negative"}) {
    const auto real = Values(std::string(direction) == "positive" ? truth.friction.positive
                                                                  : truth.friction.negative);
    for (int i = 0; i < 3; ++i) {  // Fs, Fd, b
      const FittedCoefficient& c = Coefficient(fit, direction, kNames[i]);
      EXPECT_TRUE(c.determined()) << direction << " " << kNames[i];
      EXPECT_NEAR(c.value, real[i], Tolerance(i, real[i])) << direction << " " << kNames[i];
    }
  }
}

// At 250 Hz the paper rod's sticks (4 to 40 ms, a stuck phase needs 5
// samples) are mostly too short to be found, and the stick-slip between
// those found read as smooth slides: the force balance took in F - M a
// swinging between 1 and 11 N at a steady-looking speed, and the fit ran out
// of iterations at b = 0 both ways with Fd 2.1 and 6.1 N (for 0.5 and 5).
// A window the quadratic does not follow is no smooth slide now.
TEST(FrictionFitTest, StickSlipTooShortToBeFoundIsNoSmoothSlide) {
  const Parameters truth;  // the paper's vertical rod: Fs 10 N, Fd 0.5 and 5 N
  const Unit unit = MismatchedStrokes(truth, 2, 250, {0.4, 1.0}, 1);
  const FrictionFitResult fit =
      FitFriction(unit, ThirtyPercentOff(truth.friction), FrictionFitOptions{});
  std::cout << fit.BriefReport();
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_EQ(fit.smooth_samples, 0);
  // Each coefficient held, or within its tolerance or 3 of its standard
  // errors (the replays run through the sticks not found: the component fit
  // is a start here, refinement the estimate); Fs within tolerance, b off 0.
  for (const char* direction : {"positive", "negative"}) {
    const auto real = Values(std::string(direction) == "positive" ? truth.friction.positive
                                                                  : truth.friction.negative);
    for (int i = 0; i < 4; ++i) {
      const FittedCoefficient& c = Coefficient(fit, direction, kNames[i]);
      if (i == 0) {
        EXPECT_NEAR(c.value, real[i], Tolerance(i, real[i])) << direction;
      }
      if (!c.determined()) continue;
      EXPECT_NEAR(c.value, real[i], std::max(Tolerance(i, real[i]), 3 * c.standard_error))
          << direction << " " << kNames[i];
    }
    EXPECT_GT(Coefficient(fit, direction, "b").value, 2.0) << direction;
  }
}

// A logger that lost 21 rows at a time, four times in each stroke log: the
// replays run through the gaps on the forces interpolated across them and
// are compared with the logged positions only, not with a line drawn
// between them, and no smooth slide is read off such a line. Before, these
// gaps left the fit not converged, its position RMS ten times the whole
// logs' (measured on `pneumaid synth` units of configs/paper.yaml).
TEST(FrictionFitTest, RowsTheLoggerLostAreNoMeasurement) {
  const Parameters truth;
  const Unit whole = MismatchedStrokes(truth, 3, 1000, {0.4, 0.6, 1.0}, 2);
  Unit gaps = whole;
  std::size_t lost = 0;
  for (Experiment& e : gaps.experiments) {
    const std::size_t n = e.samples();
    for (std::size_t part = 4; part >= 1; --part) {
      const auto at = static_cast<std::ptrdiff_t>(part * n / 5);
      for (auto& [name, column] : e.columns)
        column.erase(column.begin() + at, column.begin() + at + 21);
      lost += 21;
    }
  }
  ASSERT_GT(lost, 0u);
  const FrictionFitResult reference =
      FitFriction(whole, ThirtyPercentOff(truth.friction), FrictionFitOptions{});
  const FrictionFitResult fit =
      FitFriction(gaps, ThirtyPercentOff(truth.friction), FrictionFitOptions{});
  std::cout << reference.BriefReport() << fit.BriefReport();
  ASSERT_EQ(reference.status, FitStatus::kConverged) << reference.reason;
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  EXPECT_LT(fit.position_rms_m, 1.5 * reference.position_rms_m);
  for (const char* direction : {"positive", "negative"}) {
    EXPECT_EQ(Determined(fit, direction), Determined(reference, direction)) << direction;
    const auto real = Values(std::string(direction) == "positive" ? truth.friction.positive
                                                                  : truth.friction.negative);
    for (int i = 0; i < 4; ++i) {
      const FittedCoefficient& c = Coefficient(fit, direction, kNames[i]);
      if (!c.determined()) continue;
      EXPECT_NEAR(c.value, real[i], std::max(Tolerance(i, real[i]), 3 * c.standard_error))
          << direction << " " << kNames[i];
    }
  }
}

// At 5 kHz a sample interval is one RK4 step of the replay (0.2 ms, below
// the 0.25 ms of replay_step_s): the coefficients are those of 8 steps per
// interval within a fifth of their tolerances, in a fraction of the time.
TEST(FrictionFitTest, AFastLogIsReplayedInStepsOfTheSameLengthAsASlowOne) {
  const Parameters truth = VerticalTruth(0.75, {11.3, 0.2, 14.7, 0.018}, {15.2, 4.4, 8.8, 0.004});
  const Unit unit = MismatchedStrokes(truth, 11, 5000, {0.45, 0.7, 0.95}, 2, 0.0);
  FrictionFitOptions fine;
  fine.replay_step_s = 0.2e-3 / 8;
  const FrictionFitResult reference = FitFriction(unit, FrictionParams{}, fine);
  const FrictionFitResult fit = FitFriction(unit, FrictionParams{}, FrictionFitOptions{});
  ASSERT_EQ(reference.status, FitStatus::kConverged) << reference.reason;
  ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
  for (const char* direction : {"positive", "negative"}) {
    for (int i = 0; i < 4; ++i) {
      const FittedCoefficient& a = Coefficient(reference, direction, kNames[i]);
      const FittedCoefficient& b = Coefficient(fit, direction, kNames[i]);
      EXPECT_EQ(a.determined(), b.determined()) << direction << " " << kNames[i];
      EXPECT_NEAR(b.value, a.value, 0.2 * Tolerance(i, a.value)) << direction << " " << kNames[i];
    }
  }
}

// Under mismatch (smooth stick, the rig at rtol 1e-8) the linearised errors
// see the noise but not the model's error: a Stribeck valley or a stick the
// model does not have moves Fs and vs by many of them (on the robustness
// sweep, seed 12, 79 % of identify's coefficients lay within 3 errors of the
// truth, 44 % within 1). An error is widened where the fit disagrees with its
// reading off the logs by more than both errors (sweep: 91 % and 62 %). Six
// units of other tests' kinds, light to heavy, 500 Hz to 5 kHz, mid-stroke
// stick-slip to stop-to-stop strokes: 43 of the 48 determined coefficients
// within 3 errors of the truth (without the widening 37, 77 %), and the
// errors not so wide that nearly all are within 1 (25 of 48).
TEST(FrictionFitTest, ErrorsCoverTheTruthUnderModelMismatch) {
  struct Case {
    Parameters truth;
    std::uint64_t seed;
    double rate_Hz;
    std::vector<double> levels;
    int cycles;
    double margin_m;
  };
  const std::vector<Case> cases = {
      {HorizontalTruth(1.5, {8.0, 2.0, 6.0, 0.012}, {12.0, 4.0, 12.0, 0.006}),
       7,
       2000,
       {0.6, 1.0},
       1,
       -1},
      {VerticalTruth(0.75, {11.3, 0.2, 14.7, 0.018}, {15.2, 4.4, 8.8, 0.004}),
       11,
       5000,
       {0.45, 0.7, 0.95},
       2,
       0.0},
      {HorizontalTruth(0.14, {6.1, 1.77, 4.4, 0.0133}, {5.0, 0.77, 13.7, 0.0025}),
       1,
       1000,
       {0.31, 0.36, 0.4},
       3,
       0.0},
      {HorizontalTruth(0.14, {20.0, 0.71, 12.5, 0.0236}, {16.0, 4.96, 9.0, 0.0224}),
       2,
       2000,
       {0.5, 0.7, 0.9},
       1,
       0.0},
      {VerticalTruth(1.15, {19.9, 1.12, 12.2, 0.0045}, {10.7, 0.67, 7.3, 0.0022}),
       3,
       500,
       {0.5, 0.7, 0.9},
       2,
       0.005},
      {HorizontalTruth(0.15, {10.0, 0.5, 5.0, 0.01}, {6.0, 5.95, 3.0, 0.02}),
       6,
       1000,
       {0.5, 0.7, 1.0},
       2,
       -1},
  };
  int inside = 0, within_1 = 0, total = 0;
  for (const Case& c : cases) {
    const Unit unit = MismatchedStrokes(c.truth, c.seed, c.rate_Hz, c.levels, c.cycles, c.margin_m);
    const FrictionFitResult fit = FitFriction(unit, FrictionParams{}, FrictionFitOptions{});
    ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
    for (const char* direction : {"positive", "negative"}) {
      const auto real = TruthOf(c.truth, direction);
      for (int i = 0; i < 4; ++i) {
        const FittedCoefficient& k = Coefficient(fit, direction, kNames[i]);
        if (!k.determined()) continue;
        const double z = (k.value - real[i]) / k.standard_error;
        std::cout << "seed " << c.seed << " " << direction << " " << kNames[i] << " " << k.value
                  << " +- " << k.standard_error << " (truth " << real[i] << "), z " << z << "\n";
        inside += std::fabs(z) <= 3;
        within_1 += std::fabs(z) <= 1;
        ++total;
      }
    }
  }
  std::cout << "within 3 SE: " << inside << "/" << total << ", within 1: " << within_1 << "\n";
  EXPECT_GE(total, 40);
  EXPECT_GE(inside, 0.85 * total);
  EXPECT_LE(within_1, 0.8 * total);
}

// One stroke level and one cycle: a segment per direction for its four
// coefficients, too few clusters for the cluster-robust sandwich (its errors
// were 30 to 90 times too small: positive Fd 0.296 +- 0.001 for 0.2). The
// errors of what the fit determines cover the truth, and each direction
// still gets its breakaway and sliding friction.
TEST(FrictionFitTest, OneStrokeLevelsErrorsCoverTheTruth) {
  struct Case {
    Parameters truth;
    std::uint64_t seed;
    double rate_Hz, level;
  };
  const std::vector<Case> cases = {
      {HorizontalTruth(0.5, {8.0, 2.0, 6.0, 0.012}, {15.0, 4.0, 12.0, 0.006}), 7, 1000, 0.6},
      {HorizontalTruth(1.5, {8.0, 2.0, 6.0, 0.012}, {12.0, 4.0, 12.0, 0.006}), 8, 2000, 0.5},
      {VerticalTruth(0.75, {11.3, 0.2, 14.7, 0.018}, {15.2, 4.4, 8.8, 0.004}), 9, 5000, 0.7},
  };
  for (const Case& c : cases) {
    const Unit unit = MismatchedStrokes(c.truth, c.seed, c.rate_Hz, {c.level}, 1, 0.0);
    const FrictionFitResult fit = FitFriction(unit, FrictionParams{}, FrictionFitOptions{});
    ASSERT_EQ(fit.status, FitStatus::kConverged) << fit.reason;
    ASSERT_EQ(fit.segments, 2);
    for (const char* direction : {"positive", "negative"}) {
      const auto real = TruthOf(c.truth, direction);
      for (int i = 0; i < 4; ++i) {
        const FittedCoefficient& k = Coefficient(fit, direction, kNames[i]);
        if (i < 2) {
          EXPECT_TRUE(k.determined()) << direction << " " << kNames[i] << ": " << k.held;
        }
        if (!k.determined()) continue;
        EXPECT_LE(std::fabs(k.value - real[i]), 3 * k.standard_error)
            << "seed " << c.seed << " " << direction << " " << kNames[i] << " " << k.value << " +- "
            << k.standard_error << " (truth " << real[i] << ")";
      }
    }
  }
}

// The shortest stuck phases the options allow (2 samples) are fitted, not a
// crash: the force of a stuck run of 3 samples or fewer is left unsmoothed
// (an index below the run's start once wrapped around).
TEST(FrictionFitTest, TheShortestStuckPhasesTheOptionsAllowAreFitted) {
  FrictionFitOptions options;
  options.min_stuck_samples = 2;
  ASSERT_TRUE(options.IsValid(nullptr));
  const Parameters truth;
  const FrictionFitResult fit = FitFriction(MismatchedStrokes(truth, 2, 250, {0.4, 1.0}, 1),
                                            ThirtyPercentOff(truth.friction), options);
  std::cout << fit.BriefReport();
  EXPECT_TRUE(fit.has_values()) << fit.reason;
  EXPECT_GT(fit.segments, 29);  // more than the default's 5 samples find
}

TEST(FrictionFitTest, InvalidOptionsAreNamed) {
  FrictionFitOptions options;
  options.max_substeps = 0;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("max_substeps"), std::string::npos);
  options = FrictionFitOptions();
  options.replay_step_s = 0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("replay_step_s"), std::string::npos);
}

}  // namespace
}  // namespace pneumaid

namespace pneumaid {
namespace {

// friction_pressure read off the force balance of validation runs alone (the
// paper's step and the rich profile, smooth stick in the rig, noise): kp and
// the sliding friction of both directions near the truth, as a start for the
// simulation fits whose basins in them are narrow under stick-slip. Paper
// prior as the start, other seeds than the bundled unit's.
TEST(FrictionPressureStartTest, ReadsKpAndTheSlidingFrictionOffValidationRuns) {
  const std::string configs = std::string(PNEUMAID_SOURCE_DIR) + "/configs/";
  const Parameters paper = LoadParams(configs + "paper.yaml");
  for (const double kp : {1e-6, 2e-6, 3e-6}) {
    Parameters truth = paper;
    truth.effects["friction_pressure"] = {{"kp", kp}};
    const Unit unit = testing::WriteAndReadUnit(
        Synthesize(truth, LoadProtocol(configs + "protocol-validation.yaml"), 31, "FP"),
        "friction_pressure_start");
    SlideFrictionOptions with_fs;
    with_fs.static_friction = true;
    const SlideFrictionStart start = FrictionFromSlides(
        unit, {"step-1", "profile-1"}, paper.friction, FrictionFitOptions{}, with_fs);
    ASSERT_TRUE(start.ok) << start.why;
    std::cout << "kp " << kp << ": read " << start.kp_per_Pa << " from " << start.samples
              << " samples; Fd+ " << start.friction.positive.dynamic_force_N << " Fd- "
              << start.friction.negative.dynamic_force_N << "\n";
    EXPECT_NEAR(start.kp_per_Pa, kp, 0.15 * kp);
  }
  // No slides, no start: a unit of valve and tube logs only.
  const Unit valve_only = ReadUnit(std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig");
  const SlideFrictionStart none =
      FrictionFromSlides(valve_only, {"valve-staircase"}, paper.friction, FrictionFitOptions{}, {});
  EXPECT_FALSE(none.ok);
  EXPECT_NE(none.why.find("too few smooth slide samples"), std::string::npos) << none.why;
}

}  // namespace
}  // namespace pneumaid
