// The friction fit's rod model against closed-form motions, its stick, and
// its Jet derivatives against central differences.
#include "pneumaid/ident/rod_replay.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace pneumaid {
namespace {

constexpr double kMass = 0.15, kPeriod = 1e-3;

// Coulomb friction f (Fs = Fd = f, no viscous term): the motion is closed-form.
StribeckCoefficients<double> Coulomb(double f) { return {f, f, 0.0, 0.01}; }

RodReplayInput Input(const std::vector<double>& force) {
  RodReplayInput input;
  input.force_N = force.data();
  input.samples = force.size();
  input.period_s = kPeriod;
  input.mass_kg = kMass;
  input.initial_position_m = 0.002;
  return input;
}

TEST(RodReplayTest, ConstantForceAboveCoulombFrictionAcceleratesUniformly) {
  const std::vector<double> force(50, 5.0);
  std::vector<double> x(force.size());
  ReplayRod(Input(force), Coulomb(2.0), Coulomb(2.0), x.data());
  const double a = (5.0 - 2.0) / kMass;
  for (std::size_t j = 0; j < x.size(); ++j) {
    const double t = j * kPeriod;
    EXPECT_NEAR(x[j], 0.002 + 0.5 * a * t * t, 1e-12) << j;
  }
}

TEST(RodReplayTest, ForceBelowStaticFrictionHoldsTheRodExactly) {
  std::vector<double> force;
  for (int j = 0; j < 200; ++j) force.push_back(9.9 * std::sin(0.05 * j));  // |F| < Fs = 10
  std::vector<double> x(force.size());
  const StribeckCoefficients<double> paper{10.0, 0.5, 5.0, 0.01};
  ReplayRod(Input(force), paper, paper, x.data());
  for (double value : x) EXPECT_EQ(value, 0.002);
}

TEST(RodReplayTest, BreakawayIsLocatedInsideTheSampleInterval) {
  // F = k t crosses Fs = 2 N at t_b = 2.35 ms; then M x'' = k (t - t_b).
  const double k = 2.0 / 2.35e-3;
  std::vector<double> force;
  for (int j = 0; j < 30; ++j) force.push_back(k * j * kPeriod);
  std::vector<double> x(force.size());
  ReplayRod(Input(force), Coulomb(2.0), Coulomb(2.0), x.data());
  for (std::size_t j = 0; j < x.size(); ++j) {
    const double after = std::max(0.0, j * kPeriod - 2.35e-3);
    EXPECT_NEAR(x[j], 0.002 + k * after * after * after / (6 * kMass), 1e-12) << j;
  }
}

TEST(RodReplayTest, TraceRecordsTheDirectionsSlidIn) {
  // The friction fit differentiates a replay that slid one way only in that
  // direction's coefficients: the trace must not miss a slide the other way.
  std::vector<double> force(40, 5.0);
  std::vector<double> x(force.size());
  RodReplayTrace up;
  ReplayRod(Input(force), Coulomb(2.0), Coulomb(2.0), x.data(), &up);
  EXPECT_TRUE(up.slid_positive);
  EXPECT_FALSE(up.slid_negative);

  for (std::size_t j = 20; j < force.size(); ++j) force[j] = -8.0;  // pushed back
  RodReplayTrace both;
  ReplayRod(Input(force), Coulomb(2.0), Coulomb(2.0), x.data(), &both);
  EXPECT_TRUE(both.slid_positive);
  EXPECT_TRUE(both.slid_negative);

  const std::vector<double> held(40, 1.0);  // below Fs: never slides
  RodReplayTrace none;
  ReplayRod(Input(held), Coulomb(2.0), Coulomb(2.0), x.data(), &none);
  EXPECT_FALSE(none.slid_positive || none.slid_negative);
}

TEST(RodReplayTest, SlideUnderCoulombFrictionStopsWhereItShould) {
  // Pushed at 5 N for 10 ms, then released (F = 0): decelerates at f/M and
  // sticks.
  std::vector<double> force(60, 0.0);
  for (int j = 0; j <= 10; ++j) force[j] = 5.0;
  std::vector<double> x(force.size());
  ReplayRod(Input(force), Coulomb(2.0), Coulomb(2.0), x.data());
  // Closed form: uniform acceleration for 10 ms, then the force ramps from
  // 5 N to 0 over the next sample interval (tau), then uniform deceleration.
  const double t1 = 10e-3, tau = 1e-3;
  const double v1 = 3.0 / kMass * t1, x1 = 0.002 + 0.5 * 3.0 / kMass * t1 * t1;
  const double v2 = v1 + 0.5 * tau / kMass;  // integral of (5 (1 - s/tau) - 2) / M
  const double x2 = x1 + v1 * tau + (2.0 / 3.0) * tau * tau / kMass;
  const double stop = x2 + v2 * v2 / (2 * 2.0 / kMass);
  EXPECT_NEAR(x.back(), stop, 1e-6 * (stop - 0.002));
  EXPECT_EQ(x[x.size() - 1], x[x.size() - 2]);  // stuck, not creeping
}

TEST(RodReplayTest, BackwardFromTheArrestMatchesUniformDeceleration) {
  // Coulomb friction 2 N, no force: before stopping at t_s the rod slid
  // towards +x with v = f/M (t_s - t).
  const std::vector<double> force(20, 0.0);
  std::vector<double> x(force.size());
  const double stop_time = 14.3e-3, stop_x = 0.004;
  ReplayArrestBackward(Input(force), stop_time, stop_x, +1, 3, Coulomb(2.0), Coulomb(2.0),
                       x.data());
  for (std::size_t j = 3; j < x.size(); ++j) {
    const double before = std::max(0.0, stop_time - j * kPeriod);
    EXPECT_NEAR(x[j], stop_x - 2.0 / kMass * before * before / 2, 1e-12) << j;
  }
}

// Sample times at irregular intervals: 0.6 to 1.4 ms, drawn once.
std::vector<double> IrregularTimes(std::size_t n) {
  std::vector<double> t = {0.0};
  for (std::size_t j = 1; j < n; ++j)
    t.push_back(t.back() + (1.0 + 0.4 * std::sin(2.7 * j)) * 1e-3);
  return t;
}

TEST(RodReplayTest, AtIrregularTimesTheBreakawayAndSlideAreTheClosedForm) {
  // As above, F = k t crossing Fs at t_b = 2.35 ms, sampled at irregular times.
  const double k = 2.0 / 2.35e-3;
  const std::vector<double> t = IrregularTimes(30);
  std::vector<double> force;
  for (double time : t) force.push_back(k * time);
  RodReplayInput input = Input(force);
  input.time_s = t.data();
  std::vector<double> x(force.size());
  ReplayRod(input, Coulomb(2.0), Coulomb(2.0), x.data());
  for (std::size_t j = 0; j < x.size(); ++j) {
    const double after = std::max(0.0, t[j] - 2.35e-3);
    EXPECT_NEAR(x[j], 0.002 + k * after * after * after / (6 * kMass), 1e-12) << j;
  }
}

TEST(RodReplayTest, AtIrregularTimesTheBackwardArrestIsTheClosedForm) {
  const std::vector<double> t = IrregularTimes(20);
  const std::vector<double> force(t.size(), 0.0);
  RodReplayInput input = Input(force);
  input.time_s = t.data();
  std::vector<double> x(force.size());
  const double stop_time = 14.3e-3, stop_x = 0.004;
  ReplayArrestBackward(input, stop_time, stop_x, +1, 3, Coulomb(2.0), Coulomb(2.0), x.data());
  for (std::size_t j = 3; j < x.size(); ++j) {
    const double before = std::max(0.0, stop_time - t[j]);
    EXPECT_NEAR(x[j], stop_x - 2.0 / kMass * before * before / 2, 1e-12) << j;
  }
}

// On a clock that keeps no time each interval takes the substeps its own
// length needs (RodReplayInput::step_s): a lost row's interval of 2.8 ms in
// steps of at most 0.25 ms (the friction fit's default) follows a replay in
// 64 substeps per interval to within 3 um, below a position noise, where 2
// substeps in every interval are 11 times further off (32 um).
TEST(RodReplayTest, AtIrregularTimesALongIntervalTakesMoreSubsteps) {
  std::vector<double> t = IrregularTimes(40);
  for (std::size_t j = 21; j < t.size(); ++j) t[j] += 1.4e-3;  // a lost row after sample 20
  std::vector<double> force;
  for (double time : t) force.push_back(std::min(12.0, 800.0 * time));  // breaks away, slides
  const StribeckCoefficients<double> paper{10.0, 0.5, 5.0, 0.01};
  const auto replay = [&](int substeps, double step_s) {
    RodReplayInput input = Input(force);
    input.time_s = t.data();
    input.substeps = substeps;
    input.step_s = step_s;
    input.max_substeps = 64;
    std::vector<double> x(force.size());
    ReplayRod(input, paper, paper, x.data());
    return x;
  };
  const std::vector<double> reference = replay(64, 0), stepped = replay(2, 0.25e-3),
                            fixed = replay(2, 0);
  double stepped_error = 0, fixed_error = 0;
  for (std::size_t j = 0; j < t.size(); ++j) {
    stepped_error = std::max(stepped_error, std::fabs(stepped[j] - reference[j]));
    fixed_error = std::max(fixed_error, std::fabs(fixed[j] - reference[j]));
  }
  EXPECT_GT(reference.back(), 0.002 + 1e-3);  // it slid
  EXPECT_LT(stepped_error, 4e-6);
  EXPECT_GT(fixed_error, 10 * stepped_error);
}

// x at every sample for the paper's friction under a stick-slip force.
template <typename T>
std::vector<T> Replay(const std::vector<double>& force, const T* theta) {
  std::vector<T> x(force.size());
  const StribeckCoefficients<T> positive{theta[0], theta[1], theta[2], theta[3]};
  const StribeckCoefficients<T> negative{theta[4], theta[5], theta[6], theta[7]};
  RodReplayInput input = Input(force);
  ReplayRod(input, positive, negative, x.data());
  return x;
}

TEST(RodReplayTest, JetDerivativesAgreeWithCentralDifferences) {
  // A rising force that breaks the rod away, a dip that arrests it, and a
  // reversal; the paper's coefficients.
  std::vector<double> force;
  for (int j = 0; j < 120; ++j) {
    const double t = j * kPeriod;
    force.push_back(12.0 * std::sin(2 * M_PI * t / 0.08) + 1.3 * std::sin(2 * M_PI * t / 0.011));
  }
  const double theta[8] = {10.0, 0.5, 5.0, 0.01, 9.0, 5.0, 4.0, 0.012};
  using Jet = ceres::Jet<double, 8>;
  Jet jet_theta[8];
  for (int i = 0; i < 8; ++i) jet_theta[i] = Jet(theta[i], i);
  const std::vector<Jet> x = Replay(force, jet_theta);
  int moved = 0;
  for (int i = 0; i < 8; ++i) {
    const double step = 1e-6 * std::fabs(theta[i]);
    double up[8], down[8];
    std::copy(theta, theta + 8, up);
    std::copy(theta, theta + 8, down);
    up[i] += step;
    down[i] -= step;
    const std::vector<double> x_up = Replay(force, up), x_down = Replay(force, down);
    for (std::size_t j = 0; j < x.size(); ++j) {
      const double central = (x_up[j] - x_down[j]) / (2 * step);
      EXPECT_NEAR(x[j].v[i], central, 1e-5 * std::fabs(central) + 1e-9)
          << "theta " << i << " j " << j;
      moved += std::fabs(central) > 1e-6;
    }
  }
  EXPECT_GT(moved, 100);  // the check covers slides in both directions
}

}  // namespace
}  // namespace pneumaid
