// A channel's noise (channel_noise.h): the manifest's declaration wins; an
// undeclared channel's noise is estimated from its logs whatever the signal
// does (ramps, curves, steps), on readings that lie on an ADC step too.
#include "pneumaid/io/channel_noise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace pneumaid {
namespace {

// A rod's position over 4 s at 1 kHz: held, a ramp, a curve and steps of
// 5 mm (a stroke into a stop, the signal a noise estimate must not read as
// noise), with white noise of `sigma` and readings rounded to `quantum`;
// `clean` gets the signal without either.
std::vector<double> Position(double sigma, double quantum, std::uint64_t seed,
                             std::vector<double>* clean = nullptr) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<double> x(4000);
  if (clean) clean->resize(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double t = 1e-3 * static_cast<double>(i);
    double signal = 0.0100037;                                  // between two steps of the ADC
    if (t > 1 && t <= 2) signal += 0.02 * (t - 1);              // 20 mm/s
    if (t > 2) signal += 0.02 + 0.005 * std::sin(3 * (t - 2));  // a slow curve
    if (i % 400 > 200) signal += 0.005;                         // steps
    double value = signal + (sigma > 0 ? noise(rng) : 0.0);
    if (quantum > 0) value = quantum * std::round(value / quantum);
    x[i] = value;
    if (clean) (*clean)[i] = signal;
  }
  return x;
}

TEST(ChannelNoiseTest, WhiteNoiseIsReadThroughRampsCurvesAndSteps) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const std::vector<double> x = Position(5e-6, 0, seed);
    const ChannelNoise noise = EstimateNoise({&x});
    EXPECT_NEAR(noise.sigma, 5e-6, 0.05 * 5e-6) << seed;
    EXPECT_FALSE(noise.declared);
    EXPECT_EQ(noise.quantum, 0.0);
    EXPECT_EQ(noise.samples, x.size() - 4);
  }
}

// A rod sliding at 0.1 m/s, logged by a loop that keeps no time (intervals
// 0.6 to 1.4 ms): read by index its fourth differences see the clock's
// jitter times the speed (tens of um), divided by the logged times they
// cancel the slide as on a uniform clock.
TEST(ChannelNoiseTest, OnAClockThatKeepsNoTimeTheDifferencesAreInTime) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> stretch(0.6, 1.4);
  std::normal_distribution<double> noise(0.0, 5e-6);
  std::vector<double> t = {0.0}, x;
  while (t.size() < 4000) t.push_back(t.back() + 1e-3 * stretch(rng));
  for (double time : t) x.push_back(0.1 * time - 0.3 * time * time + noise(rng));
  EXPECT_NEAR(EstimateNoise({&x}, {&t}).sigma, 5e-6, 0.05 * 5e-6);
  EXPECT_GT(EstimateNoise({&x}).sigma, 2 * 5e-6);  // by index: 2.4 times
  const std::vector<double> uniform = Position(5e-6, 0, 1);
  std::vector<double> grid;
  for (std::size_t i = 0; i < uniform.size(); ++i) grid.push_back(1e-3 * static_cast<double>(i));
  EXPECT_EQ(EstimateNoise({&uniform}, {&grid}).sigma, EstimateNoise({&uniform}).sigma);
}

// Noise and rounding add: the estimate is within 15 % of how far the
// readings are from the signal, from a noise of a quarter of the step to one
// above it.
TEST(ChannelNoiseTest, AnAdcStepAddsItsRoundingToTheNoise) {
  for (double quantum : {5e-6, 1e-5, 2e-5}) {
    std::vector<double> clean;
    const std::vector<double> x = Position(5e-6, quantum, 7, &clean);
    double squares = 0;
    for (std::size_t i = 0; i < x.size(); ++i) squares += std::pow(x[i] - clean[i], 2);
    const double off = std::sqrt(squares / static_cast<double>(x.size()));
    const ChannelNoise noise = EstimateNoise({&x});
    EXPECT_NEAR(noise.quantum, quantum, 1e-12) << quantum;
    EXPECT_NEAR(noise.sigma, off, 0.15 * off) << quantum;
  }
}

// A noise-free signal on an ADC step repeats its readings: the fourth
// differences are mostly 0, and the noise is the rounding's.
TEST(ChannelNoiseTest, ANoiseFreeQuantisedSignalHasItsRoundingAsNoise) {
  const std::vector<double> x = Position(0, 1e-5, 1);
  const ChannelNoise noise = EstimateNoise({&x});
  EXPECT_NEAR(noise.quantum, 1e-5, 1e-12);
  EXPECT_GE(noise.sigma, 1e-5 / std::sqrt(12.0) * (1 - 1e-9));
  EXPECT_LT(noise.sigma, 1e-5);
}

// A signal that is not smooth at the sampling rate most of the time (a
// pressure oscillating with a period of five samples, 70 % of the log, as a
// light rod's slips at 250 Hz) has fourth differences of its own: the spread
// over the log reads three times the noise, its quiet stretches the noise
// (within 5 %; the 10th percentile of the blocks alone read 18 to 24 % high
// here, a third of the way up the quiet ones').
TEST(ChannelNoiseTest, ASignalNotSmoothAtTheSamplingRateIsReadByItsQuietStretches) {
  for (std::uint64_t seed : {4, 5}) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, 300.0);
    std::vector<double> p(8000);
    for (std::size_t i = 0; i < p.size(); ++i) {
      const bool quiet = (i / 64) % 10 < 3;
      p[i] = 3e5 + (quiet ? 0.0 : 6000.0 * std::sin(2 * M_PI * static_cast<double>(i) / 5)) +
             noise(rng);
    }
    EXPECT_NEAR(EstimateNoise({&p}).sigma, 300, 0.05 * 300) << seed;
  }
}

// Several logs pool their differences (none across the boundary between two
// logs); a log too short for a fourth difference adds nothing.
TEST(ChannelNoiseTest, LogsArePooledWithoutTheirBoundaries) {
  const std::vector<double> a = Position(300, 0, 4);
  std::vector<double> b = Position(300, 0, 5);
  for (double& v : b) v += 2e5;  // another level: a jump between the logs
  const std::vector<double> short_log = {1, 2, 3, 4};
  const ChannelNoise noise = EstimateNoise({&a, &short_log, &b});
  EXPECT_EQ(noise.samples, a.size() + b.size() - 8);
  EXPECT_NEAR(noise.sigma, 300, 15);
}

// A column at rest more than half the time (its fourth differences mostly
// exactly 0) still has a noise: the scale of its moves. A single jump of a
// noise-free column, or a few set points, is no ADC step.
TEST(ChannelNoiseTest, AColumnMostlyAtRestOrWithOneJumpIsNoAdc) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 300.0);
  std::vector<double> resting(4000, 4e5);
  for (std::size_t i = 3000; i < resting.size(); ++i) resting[i] += noise(rng);
  const ChannelNoise moving = EstimateNoise({&resting});
  EXPECT_GT(moving.sigma, 0.0);
  EXPECT_EQ(moving.quantum, 0.0);
  std::vector<double> jump(1000, 0.0);
  for (std::size_t i = 500; i < jump.size(); ++i) jump[i] = 1e-3;
  EXPECT_EQ(EstimateNoise({&jump}).quantum, 0.0);
  std::vector<double> set_points(1000, 2e5);
  for (std::size_t i = 0; i < set_points.size(); ++i) set_points[i] += 1e5 * (i / 200);
  EXPECT_EQ(EstimateNoise({&set_points}).quantum, 0.0);
}

// A noise-free smooth log is known to the digits it was written with: at
// least 1e-6 of its largest reading.
TEST(ChannelNoiseTest, ANoiseFreeLogIsKnownToSixDigits) {
  std::vector<double> smooth(2000);
  for (std::size_t i = 0; i < smooth.size(); ++i)
    smooth[i] = 3e5 + 1e5 * std::sin(1e-3 * static_cast<double>(i));
  EXPECT_NEAR(EstimateNoise({&smooth}).sigma, 1e-6 * 4e5, 0.01 * 1e-6 * 4e5);
}

TEST(ChannelNoiseTest, NothingToEstimateFromIsZero) {
  const std::vector<double> constant(100, 4e5), four = {1, 2, 3, 4};
  EXPECT_EQ(EstimateNoise({}).sigma, 0.0);
  EXPECT_EQ(EstimateNoise({&four}).sigma, 0.0);
  EXPECT_EQ(EstimateNoise({&constant}).sigma, 0.0);
}

Unit TwoLogUnit() {
  Unit unit;
  unit.manifest.sensors["x"].sigma = 5e-6;
  unit.manifest.sensors["q"].tau_s = 0.03;  // a lag, no sigma: undeclared noise
  for (std::uint64_t seed : {11, 12}) {
    Experiment e;
    e.columns["x"] = Position(20e-6, 0, seed);
    e.columns["p1"] = Position(0, 0, seed);
    for (double& p : e.columns["p1"]) p = 3e5 + 1e7 * p;
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, 400.0);
    for (double& p : e.columns["p1"]) p += noise(rng);
    unit.experiments.push_back(std::move(e));
  }
  return unit;
}

TEST(ChannelNoiseTest, TheDeclaredNoiseWinsOverTheLogs) {
  const Unit unit = TwoLogUnit();
  const ChannelNoise x = NoiseOf(unit, "x");
  EXPECT_TRUE(x.declared);
  EXPECT_EQ(x.sigma, 5e-6);  // the logs' own 20 um is not read
  const ChannelNoise p1 = NoiseOf(unit, "p1");
  EXPECT_FALSE(p1.declared);
  EXPECT_NEAR(p1.sigma, 400, 20);
  EXPECT_EQ(NoiseSigma(unit, "p1"), p1.sigma);
  EXPECT_EQ(NoiseOf(unit, "q").sigma, 0.0);  // declared without sigma, never logged
}

TEST(ChannelNoiseTest, TheNoteNamesTheEstimatedChannels) {
  const Unit unit = TwoLogUnit();
  const std::string note = ChannelNoiseNote(unit, {"p1", "q"});
  EXPECT_EQ(note.rfind("noise not declared, estimated from the logs: p1 ", 0), 0u) << note;
  EXPECT_NE(note.find(" Pa"), std::string::npos) << note;
  EXPECT_EQ(note.find("declared noise"), std::string::npos) << note;
}

// x declares 5 um where its logs carry 20: named, with the noise of the logs'
// quietest stretches (a floor: 15 um here), after the estimated channels; the
// fits still weigh by the declared 5 um.
TEST(ChannelNoiseTest, TheNoteNamesADeclaredNoiseTheLogsContradict) {
  Unit unit = TwoLogUnit();
  const std::string note = ChannelNoiseNote(unit, {"x", "p1"});
  const std::size_t at = note.find(
      "; declared noise below what the logs show: x 5e-06 m declared, "
      "the logs' quietest stretches 1.5");
  EXPECT_NE(at, std::string::npos) << note;
  EXPECT_EQ(note.rfind("noise not declared, estimated from the logs: p1 ", 0), 0u) << note;
  EXPECT_EQ(NoiseSigma(unit, "x"), 5e-6);
  // Within a factor 2 of the floor (15 um against 12 declared): not named.
  unit.manifest.sensors["x"].sigma = 12e-6;
  EXPECT_EQ(ChannelNoiseNote(unit, {"x"}), "");
  unit.manifest.sensors["x"].sigma = 7e-6;
  EXPECT_NE(ChannelNoiseNote(unit, {"x"}).find("x 7e-06 m declared"), std::string::npos);
}

}  // namespace
}  // namespace pneumaid
