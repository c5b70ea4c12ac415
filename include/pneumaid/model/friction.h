// Stribeck friction, seed paper Eq. 12, separate coefficients per direction,
// with a stiff viscous regularisation of sticking.
//
// While the rod sticks, the exact model holds it still until the net force
// exceeds Fs. We replace that switch by a smooth saturation of width
// stick_velocity around v = 0: inside it friction can take any value up to
// the Stribeck magnitude, so a net force below Fs is balanced at a creep speed
// below stick_velocity. This keeps the right-hand side continuous (no events,
// no Zeno chattering at breakaway) at the price of a documented creep.
#pragma once

#include <cmath>

#include "pneumaid/model/parameters.h"

namespace pneumaid {

template <typename T>
struct StribeckCoefficients {
  T static_force_N, dynamic_force_N, viscous_N_s_per_m, stribeck_velocity_m_per_s;
};

template <typename T>
StribeckCoefficients<T> MakeStribeckCoefficients(const StribeckParams& p) {
  return {T(p.static_force_N), T(p.dynamic_force_N), T(p.viscous_N_s_per_m),
          T(p.stribeck_velocity_m_per_s)};
}

// Eq. 12 magnitude at sliding speed |v| >= 0: Fd + b|v| + (Fs - Fd) exp(-(v/vs)^2).
template <typename T>
T StribeckMagnitude(const T& speed_m_per_s, const StribeckCoefficients<T>& c) {
  using std::exp;
  const T s = speed_m_per_s / c.stribeck_velocity_m_per_s;
  const T sliding = c.dynamic_force_N + c.viscous_N_s_per_m * speed_m_per_s;
  // Beyond 6 vs the Stribeck term is below 3e-16 of (Fs - Fd): skipping it
  // changes nothing representable and saves the exponential in fast slides.
  if (s > T(6.0) || s < T(-6.0)) return sliding;
  return sliding + (c.static_force_N - c.dynamic_force_N) * exp(-s * s);
}

// C1 odd saturation: 1.5 s - 0.5 s^3 inside [-1, 1], +-1 outside.
template <typename T>
T SmoothSaturation(const T& s) {
  if (s >= T(1.0)) return T(1.0);
  if (s <= T(-1.0)) return T(-1.0);
  return s * (T(1.5) - T(0.5) * s * s);
}

// Friction force [N] acting against the motion at velocity v; positive when it
// pushes towards -x (that is, for v > 0).
template <typename T>
T FrictionForce(const T& velocity_m_per_s, const StribeckCoefficients<T>& positive,
                const StribeckCoefficients<T>& negative, const T& stick_velocity_m_per_s) {
  const T weight = SmoothSaturation(velocity_m_per_s / stick_velocity_m_per_s);
  if (velocity_m_per_s >= T(0.0)) return weight * StribeckMagnitude(velocity_m_per_s, positive);
  return weight * StribeckMagnitude(-velocity_m_per_s, negative);
}

}  // namespace pneumaid
