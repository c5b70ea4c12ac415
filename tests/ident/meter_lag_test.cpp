// The friction fit's reading of lagged instruments (src/ident/meter_lag.h):
// the exact inverse of the rig's first-order lag where its noise gain is
// small, a bounded-noise mean of it where it is not.
#include "../../src/ident/meter_lag.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "pneumaid/eval/lag.h"

namespace pneumaid::internal {
namespace {

std::vector<double> Clock(double rate_Hz, int samples) {
  std::vector<double> t(samples);
  for (int i = 0; i < samples; ++i) t[i] = i / rate_Hz;
  return t;
}

std::vector<double> Lagged(const std::vector<double>& t, std::vector<double> signal, double tau) {
  ApplyFirstOrderLag([&t](std::size_t i) { return t[i] - t[i - 1]; }, tau, &signal);
  return signal;
}

TEST(MeterLagTest, AFastEnoughLogIsReadBackExactly) {
  // 1 kHz through 1.5 ms: the exact inverse's noise gain is 2.3, no mean.
  const std::vector<double> t = Clock(1000, 400);
  ASSERT_EQ(PlanLagInverse(1e-3, 1.5e-3).samples, 1);
  std::vector<double> signal(t.size());
  for (std::size_t i = 0; i < t.size(); ++i)
    signal[i] = 2e5 + 1e5 * (t[i] > 0.1) + 3e4 * std::sin(40 * t[i]);
  const std::vector<double> undone = LagUndone(t, Lagged(t, signal, 1.5e-3), 1.5e-3);
  for (std::size_t i = 0; i + 1 < t.size(); ++i) EXPECT_NEAR(undone[i], signal[i], 1e-6) << i;
}

TEST(MeterLagTest, ASlowLagComesBackAsAStepWithinItsWindowWithBoundedNoise) {
  // 5 kHz through 5 ms: the exact inverse's gain is 35.4, read as a mean of 13.
  const double rate = 5000, tau = 5e-3;
  const LagInverse plan = PlanLagInverse(1 / rate, tau);
  EXPECT_EQ(plan.samples, 13);
  EXPECT_LE(plan.noise_gain, kMaxLagNoiseGain);
  const std::size_t half = plan.samples / 2;
  const std::vector<double> t = Clock(rate, 2000);
  std::vector<double> step(t.size()), ramp(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    step[i] = i < 1000 ? 1e5 : 3e5;
    ramp[i] = 1e5 + 2e6 * t[i];
  }
  const std::vector<double> undone = LagUndone(t, Lagged(t, step, tau), tau);
  for (std::size_t i = 0; i + 1 < t.size(); ++i) {
    if (i + half < 1000 || i >= 1000 + half) {
      EXPECT_NEAR(undone[i], step[i], 1e-6) << i;  // the levels exactly
    } else {
      EXPECT_GT(undone[i], 1e5) << i;  // between them, no overshoot
      EXPECT_LT(undone[i], 3e5) << i;
    }
  }
  // Centred: a ramp comes back where it was, not a fraction of a sample early.
  const std::vector<double> ramp_undone = LagUndone(t, Lagged(t, ramp, tau), tau);
  for (std::size_t i = 0; i + 1 < t.size(); ++i) EXPECT_NEAR(ramp_undone[i], ramp[i], 1e-6) << i;
  // Noise on a constant reading: grown by about the planned gain, no more.
  std::mt19937 rng(12);
  std::normal_distribution<double> noise(0.0, 300.0);
  std::vector<double> reading(t.size(), 2e5);
  for (double& r : reading) r += noise(rng);
  const std::vector<double> read = LagUndone(t, reading, tau);
  double sum = 0, sum2 = 0;
  for (std::size_t i = 20; i + 20 < read.size(); ++i) sum += read[i], sum2 += read[i] * read[i];
  const double n = static_cast<double>(read.size() - 40);
  const double gain = std::sqrt(sum2 / n - (sum / n) * (sum / n)) / 300.0;
  EXPECT_NEAR(gain, plan.noise_gain, 0.3 * plan.noise_gain);
  EXPECT_LT(gain, 1.2 * kMaxLagNoiseGain);
}

TEST(MeterLagTest, OnlyDeclaredLagsAreUndone) {
  Experiment e;
  e.columns["t"] = Clock(1000, 50);
  e.columns["p1"] = std::vector<double>(50, 2e5);
  e.columns["p1"][25] = 3e5;
  Manifest manifest;
  EXPECT_EQ(WithLagsUndone(e, manifest, {"p1", "p2"}), nullptr);
  manifest.sensors["p2"].tau_s = 0.01;  // declared, but the log has no p2
  EXPECT_EQ(WithLagsUndone(e, manifest, {"p1", "p2"}), nullptr);
  manifest.sensors["p1"].tau_s = 0.002;
  const auto undone = WithLagsUndone(e, manifest, {"p1", "p2"});
  ASSERT_NE(undone, nullptr);
  EXPECT_EQ(undone->column("p1"), LagUndone(e.column("t"), e.column("p1"), 0.002));
  EXPECT_EQ(undone->column("t"), e.column("t"));
}

}  // namespace
}  // namespace pneumaid::internal
