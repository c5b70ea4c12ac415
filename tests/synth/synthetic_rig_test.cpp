// The synthetic rig: what it writes reads back as the truth passed through
// the declared sensor model, within the declared noise.
#include "pneumaid/synth/synthetic_rig.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>

#include "pneumaid/eval/lag.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/sim/simulate.h"
#include "synth_test_util.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;

Protocol SmallProtocol(double noise_scale) {
  Protocol p;
  p.sensors["x"] = {5e-6 * noise_scale, 0.0, 1e-5, true};
  p.sensors["p1"] = {300.0 * noise_scale, 0.0, 0.0, true};
  p.sensors["p2"] = {300.0 * noise_scale, 0.0, 0.0, true};
  p.sensors["q1"] = {2e-7 * noise_scale, 0.03, 0.0, true};
  p.sensors["q2"] = {2e-7 * noise_scale, 0.03, 0.0, true};
  p.sensors["q"] = {2e-7 * noise_scale, 0.03, 0.0, true};
  p.valve = true;
  p.valve_step_V = 0.25;
  p.valve_hold_s = 0.2;
  p.tube_lengths_m = {0.38};
  p.paper_step = true;
  return p;
}

using testing::WriteAndReadUnit;

const Experiment& Find(const Unit& unit, const std::string& id) {
  for (const auto& e : unit.experiments) {
    if (e.entry.id == id) return e;
  }
  throw std::runtime_error("no experiment " + id);
}

// The truth run of a logged command, at the logged times.
Trajectory TruthRun(const Parameters& truth, const Experiment& e) {
  Trajectory run;
  const auto& t = e.column("t");
  const auto summary = Simulate(truth, SampledCommand(t, e.column("u")), RetractedAtRest(truth), t,
                                SimulationOptions{}, &run);
  EXPECT_TRUE(summary.ok()) << summary.BriefReport();
  return run;
}

std::vector<double> Lagged(const std::vector<double>& signal, double period, double tau) {
  return MeasureSignal(signal, period, SensorModel{0.0, tau, 0.0, true}, nullptr);
}

TEST(SyntheticRigTest, NoiseFreeRoundTripIsTheTruthThroughTheSensorModel) {
  const Parameters truth;
  const Unit unit = WriteAndReadUnit(Synthesize(truth, SmallProtocol(0.0), 7, "RT-0"), "synth_rt0");
  EXPECT_EQ(unit.manifest.rig.position_origin, PositionOrigin::kRetracted);
  const Experiment& step = Find(unit, "step-1");
  const Trajectory run = TruthRun(truth, step);
  const auto q1_lagged = Lagged(run.q1_kg_per_s, 1e-3, 0.03);
  for (std::size_t i = 0; i < run.size(); ++i) {
    // x: the 10 um ADC step, then 7 significant digits of mm.
    EXPECT_NEAR(step.column("x")[i], run.x_m[i], 0.5e-5 + 1e-9) << i;
    EXPECT_NEAR(step.column("p1")[i], run.p1_Pa[i], 1.0) << i;  // 7 digits of bar_g
    EXPECT_NEAR(step.column("q1")[i], q1_lagged[i], 1e-9) << i;
  }
  // The run reaches the far end and comes back, as the protocol says.
  EXPECT_GT(*std::max_element(run.x_m.begin(), run.x_m.end()), 0.025 - 1.1e-3);
  EXPECT_LT(run.x_m.back(), -0.025 + 1.1e-3);
}

// The rig's controller changes its output at sample instants, so a run
// replayed from its logged command is the truth run at any rate. At 250 Hz
// the first stroke leg used to start at 0.05 s, between two samples: the
// replay started up to one sample late (90 um off here; 0.24 mm behind on
// the sweep's 0.9 kg rod).
TEST(SyntheticRigTest, AtALowRateTheLoggedCommandChangesWhereTheRigsDid) {
  const Parameters truth;
  Protocol protocol = SmallProtocol(0.0);
  protocol.sample_rate_Hz = 250;
  protocol.valve = false;
  protocol.tube_lengths_m.clear();
  protocol.stroke_levels_V = {0.7};
  protocol.rich_profile = true;
  const Unit unit = WriteAndReadUnit(Synthesize(truth, protocol, 11, "RT-250"), "synth_rt250");
  int replayed = 0;
  for (const Experiment& e : unit.experiments) {
    const Trajectory run = TruthRun(truth, e);
    for (std::size_t i = 0; i < run.size(); ++i) {
      // Half the 10 um ADC step, and the integrator's own error, which the
      // profile's slow stick-slip ramps carry into where the rod sticks.
      ASSERT_NEAR(e.column("x")[i], run.x_m[i], 2e-5) << e.entry.id << " at " << i;
    }
    ++replayed;
  }
  EXPECT_EQ(replayed, 3);  // the stroke, the step and the rich profile
  // The logged command itself: the first leg starts on the first sample after
  // 0.05 s, and each sample of the profile's ramp logs the ramp's value at
  // that sample (a knot a round-off after its sample used to be logged one
  // sample late).
  const auto& stroke_u = Find(unit, "stroke-070").column("u");
  const auto first =
      std::find_if(stroke_u.begin(), stroke_u.end(), [](double u) { return u != 0; });
  EXPECT_EQ(first - stroke_u.begin(), 13);  // t = 0.052 s
  const Experiment& profile = Find(unit, "profile-1");
  int ramp_samples = 0;
  for (std::size_t i = 0; i < profile.column("t").size(); ++i) {
    const double t = profile.column("t")[i];
    if (t < 2.5 - 1e-9 || t > 4.0 - 1e-3) continue;
    EXPECT_NEAR(profile.column("u")[i], -0.5 + (t - 2.5) / 1.5 * 1.1, 1e-5) << "t = " << t;
    ++ramp_samples;
  }
  EXPECT_EQ(ramp_samples, 375);
}

TEST(SyntheticRigTest, NoisyRoundTripResidualsMatchTheDeclaredNoise) {
  const Parameters truth;
  const Unit unit =
      WriteAndReadUnit(Synthesize(truth, SmallProtocol(1.0), 11, "RT-1"), "synth_rt1");
  const Experiment& step = Find(unit, "step-1");
  const Trajectory run = TruthRun(truth, step);
  double sum = 0, sum_sq = 0, worst_x = 0;
  for (std::size_t i = 0; i < run.size(); ++i) {
    const double r = step.column("p1")[i] - run.p1_Pa[i];
    sum += r;
    sum_sq += r * r;
    worst_x = std::max(worst_x, std::fabs(step.column("x")[i] - run.x_m[i]));
  }
  const double n = static_cast<double>(run.size());
  const double sigma = std::sqrt(sum_sq / n - (sum / n) * (sum / n));
  EXPECT_NEAR(sigma, 300.0, 30.0);  // the declared sigma of p1
  EXPECT_LT(std::fabs(sum / n), 4 * 300.0 / std::sqrt(n));
  EXPECT_LT(worst_x, 0.5e-5 + 5 * 5e-6);  // quantisation + 5 sigma
  EXPECT_DOUBLE_EQ(*unit.manifest.sensors.at("p1").sigma, 300.0);
  EXPECT_DOUBLE_EQ(*unit.manifest.sensors.at("q1").tau_s, 0.03);
}

TEST(SyntheticRigTest, ValveTestShowsBothBranchesThroughTheMeterLag) {
  const Parameters truth;
  const Unit unit = WriteAndReadUnit(Synthesize(truth, SmallProtocol(0.0), 3, "V"), "synth_valve");
  const Experiment& valve = Find(unit, "valve-staircase");
  const auto& u = valve.column("u");
  const auto& q = valve.column("q");
  // Plateau ends at u = 0.5 on the way up and on the way down: the branches differ.
  std::vector<double> at_half;
  for (std::size_t i = 1; i < u.size(); ++i) {
    if (u[i - 1] == 0.5 && u[i] != 0.5) at_half.push_back(q[i - 1]);
  }
  ASSERT_EQ(at_half.size(), 2u);
  const double q_max = truth.valve.increasing.q_max_kg_per_s;
  const double up = 10.93 * 0.0625 - 18.95 * 0.125 + 8.52 * 0.25 + 1.0 * 0.5;
  const double down = 9.86 * 0.0625 - 19.30 * 0.125 + 10.95 * 0.25 - 0.21 * 0.5;
  const double choked = 0.0404184 * 5e5 / (1181.0 * std::sqrt(293.0));  // C1 p_s / (N sqrt T)
  EXPECT_NEAR(at_half[0], q_max * up * choked, 2e-3 * q_max);
  EXPECT_NEAR(at_half[1], truth.valve.decreasing.q_max_kg_per_s * down * choked, 2e-3 * q_max);
}

// A lossy logger drops rows and changes nothing else: every kept row is the
// complete log's row (same noise), the first and last rows stay, the valve
// and tube logs are whole. A ramp's command runs 0 -> 1 -> 0 V.
TEST(SyntheticRigTest, DroppedRowsAreRowsOfTheCompleteLogAndARampIsARamp) {
  const Parameters truth;
  Protocol complete = SmallProtocol(1.0), lossy = complete;
  complete.valve_ramp_s = lossy.valve_ramp_s = 1.0;
  lossy.dropped_samples = 0.05;
  const SyntheticUnit a = Synthesize(truth, complete, 5, "D"), b = Synthesize(truth, lossy, 5, "D");
  ASSERT_EQ(a.logs.size(), b.logs.size());
  for (std::size_t k = 0; k < a.logs.size(); ++k) {
    const auto &all = a.logs[k].columns, &kept = b.logs[k].columns;
    const bool actuator = a.logs[k].entry.kind == ExperimentKind::kValidation;
    const std::size_t rows = all.front().size(), left = kept.front().size();
    if (!actuator) {
      EXPECT_EQ(all, kept) << a.logs[k].entry.id;
      continue;
    }
    EXPECT_LT(left, rows * 0.98);
    EXPECT_GT(left, rows * 0.92);
    EXPECT_EQ(kept.front().front(), all.front().front());
    EXPECT_EQ(kept.front().back(), all.front().back());
    std::size_t j = 0;
    for (std::size_t i = 0; i < left; ++i) {
      while (j < rows && all.front()[j] != kept.front()[i]) ++j;
      ASSERT_LT(j, rows);
      for (std::size_t c = 0; c < all.size(); ++c) EXPECT_EQ(kept[c][i], all[c][j]);
    }
  }
  const RigLog& ramp = a.logs.front();
  ASSERT_EQ(ramp.entry.id, "valve-ramp");
  const auto& u = ramp.columns[1];
  EXPECT_EQ(u.front(), 0.0);
  EXPECT_EQ(*std::max_element(u.begin(), u.end()), 1.0);
  EXPECT_NEAR(u[u.size() / 4], 0.5, 0.01);
  EXPECT_NEAR(u.back(), 0.0, 1e-9);
}

// A logger with an irregular clock (a loop that reads the sensors, writes the
// command and logs a row, on an operating system that is not real-time):
// every log's intervals spread over 0.7 to 1.3 of the nominal 1 ms, and each
// row holds the signals at its own time, so the truth simulated at the
// logged times under the logged command is the log, through the sensors.
TEST(SyntheticRigTest, AnIrregularClocksRowsAreTheRigAtTheirOwnTimes) {
  const Parameters truth;
  Protocol protocol = SmallProtocol(0.0);
  protocol.clock_jitter = 0.3;
  const Unit unit = WriteAndReadUnit(Synthesize(truth, protocol, 7, "J"), "synth_jitter");
  for (const Experiment& e : unit.experiments) {
    const auto& t = e.column("t");
    double shortest = 1, longest = 0;
    for (std::size_t i = 1; i < t.size(); ++i) {
      shortest = std::min(shortest, t[i] - t[i - 1]);
      longest = std::max(longest, t[i] - t[i - 1]);
    }
    EXPECT_GT(shortest, 0.7e-3 - 1e-9) << e.entry.id;
    EXPECT_LT(shortest, 0.72e-3) << e.entry.id;
    EXPECT_LT(longest, 1.3e-3 + 1e-9) << e.entry.id;
    EXPECT_GT(longest, 1.28e-3) << e.entry.id;
  }
  const Experiment& step = Find(unit, "step-1");
  const Trajectory run = TruthRun(truth, step);
  const auto& t = step.column("t");
  std::vector<double> q1_lagged = run.q1_kg_per_s;
  ApplyFirstOrderLag([&t](std::size_t i) { return t[i] - t[i - 1]; }, 0.03, &q1_lagged);
  for (std::size_t i = 0; i < run.size(); ++i) {
    EXPECT_NEAR(step.column("x")[i], run.x_m[i], 0.5e-5 + 1e-9) << i;
    EXPECT_NEAR(step.column("p1")[i], run.p1_Pa[i], 1.0) << i;
    EXPECT_NEAR(step.column("q1")[i], q1_lagged[i], 1e-9) << i;
  }
  EXPECT_GT(*std::max_element(run.x_m.begin(), run.x_m.end()), 0.025 - 1.1e-3);
}

TEST(SyntheticRigTest, DeterministicPerSeed) {
  const Parameters truth;
  const auto a = UnitFiles(Synthesize(truth, SmallProtocol(1.0), 5, "D"));
  const auto b = UnitFiles(Synthesize(truth, SmallProtocol(1.0), 5, "D"));
  const auto c = UnitFiles(Synthesize(truth, SmallProtocol(1.0), 6, "D"));
  EXPECT_EQ(a, b);
  EXPECT_NE(a.at("step-1.csv"), c.at("step-1.csv"));
}

// A stroke margin of half the stroke or more is reached before the rod moves:
// every leg would end at once and no retract leg be written. Bad input, named.
TEST(SyntheticRigTest, AStrokeMarginOfHalfTheStrokeIsBadInput) {
  const Parameters truth;  // a 50 mm stroke
  Protocol protocol = SmallProtocol(1.0);
  protocol.valve = false;
  protocol.tube_lengths_m.clear();
  protocol.paper_step = false;
  protocol.stroke_levels_V = {0.7};
  protocol.stroke_margin_m = 0.025;
  try {
    Synthesize(truth, protocol, 5, "D");
    FAIL() << "a margin of half the stroke was accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what())
                  .find("stroke.margin: 25 mm, expected less than half the truth's stroke (25 mm)"),
              std::string::npos)
        << error.what();
  }
  protocol.stroke_margin_m = 0.02;
  const SyntheticUnit unit = Synthesize(truth, protocol, 5, "D");
  ASSERT_EQ(unit.logs.size(), 1u);
}

TEST(SyntheticRigTest, SpreadStaysInsideItsBoundsAndScaleIsExact) {
  const Parameters base;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const Parameters p = ApplySpread(base, {{"valve.*.q_max", 0.05}, {"friction.*.*", 0.15}}, seed);
    EXPECT_LE(std::fabs(p.valve.increasing.q_max_kg_per_s / 9.25e-5 - 1), 0.05);
    EXPECT_LE(std::fabs(p.friction.negative.static_force_N / 10.0 - 1), 0.15);
    EXPECT_EQ(p.pipeline.delta_per_s, base.pipeline.delta_per_s);
  }
  EXPECT_NE(ApplySpread(base, {{"pipeline.delta", 0.1}}, 1).pipeline.delta_per_s, 8.0);
  EXPECT_EQ(ApplyScale(base, {{"friction.positive.Fs", 3.0}}).friction.positive.static_force_N,
            30.0);
  EXPECT_THROW(ApplyScale(base, {{"friction.sideways.Fs", 3.0}}), InputError);
}

TEST(SyntheticRigTest, MeasureSignalLagIsExactForHeldInput) {
  std::vector<double> step(200, 1.0);
  step[0] = 0.0;
  const auto out = Lagged(step, 1e-3, 0.03);
  for (std::size_t i = 1; i < out.size(); ++i) {
    EXPECT_NEAR(out[i], 1.0 - std::exp(-(static_cast<double>(i) - 1) * 1e-3 / 0.03), 1e-12) << i;
  }
}

TEST(SyntheticRigTest, HiddenEffectActsWithoutBeingDeclared) {
  Parameters truth;
  truth.effects["flow_sensor_lag"] = {{"tau", 0.05}};
  const Unit hidden =
      WriteAndReadUnit(Synthesize(truth, SmallProtocol(0.0), 1, "H"), "synth_hidden");
  const Parameters without;  // named: GCC 12 warns falsely on a Parameters{} temporary here
  const Unit plain =
      WriteAndReadUnit(Synthesize(without, SmallProtocol(0.0), 1, "H"), "synth_plain");
  EXPECT_EQ(hidden.manifest.sensors.at("q1").tau_s, plain.manifest.sensors.at("q1").tau_s);
  const auto& q_hidden = Find(hidden, "pipe-038").column("q_in");
  const auto& q_plain = Find(plain, "pipe-038").column("q_in");
  EXPECT_LT(q_hidden[150], 0.9 * q_plain[150]);  // 50 ms after the step: slower
}

}  // namespace
}  // namespace pneumaid
