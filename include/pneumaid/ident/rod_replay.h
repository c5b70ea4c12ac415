// The rod's equation of motion (seed paper Eq. 9 with Eq. 12, stick included)
// replayed under a measured driving force: the friction fit's model.
//
//   M x'' = F(t) - F_friction(v),  F(t) = p1 A1 - p2 A2 - p_atm A_h - M g
//
// F(t) comes from the logged chamber pressures, linear between samples, so
// the two-state rod model needs no valve, tube or chamber model. The rod
// sticks while |F| stays below the static force of the direction it pushes
// in; breakaway and the return to stick are located inside a sample interval
// (the crossing of the linear F, the zero of v), so the replayed positions are
// continuous in the friction coefficients and ceres::Jet differentiates them.
// Sliding is integrated by classical RK4 with a fixed number of substeps per
// sample interval near the Stribeck region: the drop there is fast
// (M vs / (Fs - Fd), 0.16 ms with the paper's values) but bounded. Above
// 4 vs a quarter of them suffices (the rod is then a slow first-order system).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "pneumaid/model/friction.h"

namespace pneumaid {

// One stretch of a log to replay: the driving force at each sample, starting
// stuck at `initial_position_m`.
struct RodReplayInput {
  const double* force_N = nullptr;  // F at samples 0 .. samples-1
  std::size_t samples = 0;
  double period_s = 1e-3;
  // The times of samples 0 .. samples-1 [s, any origin] of a log sampled at
  // irregular intervals; null: every period_s.
  const double* time_s = nullptr;
  double mass_kg = 0.15;
  double initial_position_m = 0;
  int substeps = 8;  // RK4 substeps per sample interval while sliding
  // With time_s: the longest RK4 step [s], so that an interval longer than
  // the median (up to twice it and more where a row was lost) takes more
  // substeps, at most max_substeps; 0: `substeps` in every interval.
  double step_s = 0;
  int max_substeps = 8;
  // Stick/slip switches followed inside one sample interval at most (bounded
  // work; a Zeno sequence would be cut there and stay stuck).
  int max_switches = 4;

  // The interval from sample i to sample i + 1.
  double Interval(std::size_t i) const {
    return time_s == nullptr ? period_s : time_s[i + 1] - time_s[i];
  }
  // RK4 substeps while sliding over the interval from sample i.
  int SubstepsOver(std::size_t i) const {
    if (time_s == nullptr || !(step_s > 0)) return substeps;
    const double steps = std::ceil(Interval(i) / step_s - 1e-9);
    return static_cast<int>(std::clamp(steps, 1.0, static_cast<double>(max_substeps)));
  }
  // The time of sample i after sample 0.
  double Elapsed(std::size_t i) const {
    return time_s == nullptr ? static_cast<double>(i) * period_s : time_s[i] - time_s[0];
  }
};

// Which directions a replay slid in, so that a caller can tell which
// friction coefficients its positions depend on.
struct RodReplayTrace {
  bool slid_positive = false;
  bool slid_negative = false;

  void Record(int direction) {
    if (direction > 0) slid_positive = true;
    if (direction < 0) slid_negative = true;
  }
};

namespace rod_replay_detail {

template <typename T>
struct RodState {
  T x, v;
  int direction;  // 0 stuck, +1 sliding towards +x, -1 towards -x
};

inline double ScalarPart(double value) { return value; }
template <typename Jet>
double ScalarPart(const Jet& value) {
  return value.a;
}

// Acceleration while sliding in `direction`: friction opposes that direction
// with the Stribeck magnitude at the speed along it (0 when v has crossed).
template <typename T>
T SlidingAcceleration(const T& force_N, const T& v, int direction,
                      const StribeckCoefficients<T>& positive,
                      const StribeckCoefficients<T>& negative, double mass_kg) {
  const T speed = T(direction) * v;
  const T along = speed > T(0.0) ? speed : T(0.0);
  const T friction =
      direction > 0 ? StribeckMagnitude(along, positive) : StribeckMagnitude(along, negative);
  return (force_N - T(direction) * friction) / T(mass_kg);
}

// Earliest time in [from, h] at which the linear force F_a -> F_b leaves the
// stick band (-Fs_neg, Fs_pos); sets `direction`. False when it stays inside.
template <typename T>
bool FindBreakaway(const T& from, double h, double force_a, double force_b,
                   const StribeckCoefficients<T>& positive, const StribeckCoefficients<T>& negative,
                   T* at, int* direction) {
  const T slope = T((force_b - force_a) / h);
  const T force_from = T(force_a) + slope * from;
  if (force_from > positive.static_force_N) {
    *at = from, *direction = +1;
    return true;
  }
  if (force_from < -negative.static_force_N) {
    *at = from, *direction = -1;
    return true;
  }
  if (force_b > positive.static_force_N) {
    *at = (positive.static_force_N - T(force_a)) / slope, *direction = +1;
    return true;
  }
  if (force_b < -negative.static_force_N) {
    *at = (-negative.static_force_N - T(force_a)) / slope, *direction = -1;
    return true;
  }
  return false;
}

// Slides from local time `from` to `to` (either way: backward when to < from)
// of a sample interval whose force is force_a + slope t, in `substeps` RK4
// steps, or until v reaches zero; then the rod is stuck from the located
// time, which is returned.
template <typename T>
T Slide(const T& from, const T& to, double force_a, double slope, int substeps,
        const StribeckCoefficients<T>& positive, const StribeckCoefficients<T>& negative,
        double mass_kg, RodState<T>* s) {
  const T dt = (to - from) / T(substeps);
  T t = from;
  const auto accel = [&](const T& time, const T& v) {
    return SlidingAcceleration(T(force_a) + T(slope) * time, v, s->direction, positive, negative,
                               mass_kg);
  };
  for (int k = 0; k < substeps; ++k) {
    const T half = T(0.5) * dt;
    const T a1 = accel(t, s->v);
    const T v2 = s->v + half * a1;
    const T a2 = accel(t + half, v2);
    const T v3 = s->v + half * a2;
    const T a3 = accel(t + half, v3);
    const T v4 = s->v + dt * a3;
    const T a4 = accel(t + dt, v4);
    const T v_next = s->v + dt / T(6.0) * (a1 + T(2.0) * a2 + T(2.0) * a3 + a4);
    const T x_next = s->x + dt / T(6.0) * (s->v + T(2.0) * v2 + T(2.0) * v3 + v4);
    if (T(s->direction) * v_next <= T(0.0)) {
      // v reached zero inside this substep: linear in v, so x gains half the
      // distance at the starting speed over the located fraction.
      const T fraction = s->v == T(0.0) ? T(0.0) : s->v / (s->v - v_next);
      s->x = s->x + T(0.5) * s->v * fraction * dt;
      s->v = T(0.0);
      s->direction = 0;
      return t + fraction * dt;
    }
    s->x = x_next, s->v = v_next, t = t + dt;
  }
  return to;
}

// Substeps for the next interval: the full count near the Stribeck region,
// a quarter well above it (there the rod is a slow first-order system, b/M).
template <typename T>
int SubstepsAt(const RodState<T>& s, const StribeckCoefficients<T>& positive,
               const StribeckCoefficients<T>& negative, int substeps) {
  const double stribeck = std::max(ScalarPart(positive.stribeck_velocity_m_per_s),
                                   ScalarPart(negative.stribeck_velocity_m_per_s));
  return std::fabs(ScalarPart(s.v)) > 4.0 * stribeck ? std::max(1, substeps / 4) : substeps;
}

}  // namespace rod_replay_detail

// Replays the rod over `input` and writes x at every sample (position[0] is
// the initial position); `trace`, if given, records the directions slid in.
template <typename T>
void ReplayRod(const RodReplayInput& input, const StribeckCoefficients<T>& positive,
               const StribeckCoefficients<T>& negative, T* position,
               RodReplayTrace* trace = nullptr) {
  using namespace rod_replay_detail;
  if (input.samples == 0) return;
  RodState<T> s{T(input.initial_position_m), T(0.0), 0};
  position[0] = s.x;
  for (std::size_t i = 0; i + 1 < input.samples; ++i) {
    const double h = input.Interval(i);
    const double force_a = input.force_N[i], force_b = input.force_N[i + 1];
    T t(0.0);
    for (int switches = 0; switches <= input.max_switches; ++switches) {
      if (s.direction == 0 &&
          !FindBreakaway(t, h, force_a, force_b, positive, negative, &t, &s.direction)) {
        break;
      }
      if (trace != nullptr) trace->Record(s.direction);
      t = Slide(t, T(h), force_a, (force_b - force_a) / h,
                SubstepsAt(s, positive, negative, input.SubstepsOver(i)), positive, negative,
                input.mass_kg, &s);
      if (s.direction != 0) break;  // still sliding at the interval's end
    }
    position[i + 1] = s.x;
  }
}

// Replays the end of a slide backward in time from its arrest: the rod came
// to rest at `stop_position_m` at time `stop_time_s` (from sample 0), sliding
// in `direction` before. Writes x at samples [first, samples): those at or
// after the arrest hold the rest position. Backward in time the Stribeck drop
// is stable and v = 0 at the arrest is known exactly, so the slow end of a
// slide is predicted without the velocity error that a forward replay
// accumulates from the force's noise over the whole slide.
template <typename T>
void ReplayArrestBackward(const RodReplayInput& input, const T& stop_time_s, double stop_position_m,
                          int direction, std::size_t first, const StribeckCoefficients<T>& positive,
                          const StribeckCoefficients<T>& negative, T* position) {
  using namespace rod_replay_detail;
  // The interval k that holds the arrest.
  std::size_t k = 0;
  if (input.time_s == nullptr) {
    const double stop = ScalarPart(stop_time_s) / input.period_s;
    k = stop <= 0 ? 0 : static_cast<std::size_t>(stop);
  } else {
    while (k + 1 < input.samples && input.Elapsed(k + 1) <= ScalarPart(stop_time_s)) ++k;
  }
  if (k >= input.samples - 1) k = input.samples - 2;
  // Samples before `first` belong to the forward replay: never overwritten.
  for (std::size_t j = std::max(k + 1, first); j < input.samples; ++j) {
    position[j] = T(stop_position_m);
  }
  RodState<T> s{T(stop_position_m), T(0.0), direction};
  T from = stop_time_s - T(input.Elapsed(k));
  for (std::size_t j = k + 1; j-- > first;) {
    const double force_a = input.force_N[j], force_b = input.force_N[j + 1];
    if (s.direction != 0) {
      Slide(from, T(0.0), force_a, (force_b - force_a) / input.Interval(j),
            SubstepsAt(s, positive, negative, input.SubstepsOver(j)), positive, negative,
            input.mass_kg, &s);
    }
    position[j] = s.x;
    if (j > 0) from = T(input.Interval(j - 1));
  }
}

}  // namespace pneumaid
