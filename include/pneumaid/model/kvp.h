// Empirical valve gain K_vp(u), seed paper Eq. 3.
//
// K_vp = q_max (a u^4 + b u^3 + c u^2 + d u) below u_sat, q_max above, never
// negative (Table 2's decreasing polynomial dips below zero near u = 0.01).
// Table 2 is not continuous at u_sat: the jump is kept, as published.
#pragma once

#include "pneumaid/model/parameters.h"

namespace pneumaid {

template <typename T>
struct KvpCoefficients {
  T a, b, c, d, q_max_kg_per_s, u_sat_V;
};

template <typename T>
KvpCoefficients<T> MakeKvpCoefficients(const KvpBranchParams& p) {
  return {T(p.a), T(p.b), T(p.c), T(p.d), T(p.q_max_kg_per_s), T(p.u_sat_V)};
}

// The polynomial part, q_max (a u^4 + b u^3 + c u^2 + d u), unclamped.
template <typename T>
T KvpPolynomial(const T& opening, const KvpCoefficients<T>& c) {
  const T& u = opening;
  return c.q_max_kg_per_s * (((c.a * u + c.b) * u + c.c) * u + c.d) * u;
}

// K_vp [kg/s] at valve opening u [V] (0 = closed).
template <typename T>
T Kvp(const T& opening, const KvpCoefficients<T>& c) {
  if (opening <= T(0.0)) return T(0.0);
  if (opening >= c.u_sat_V) return c.q_max_kg_per_s;
  const T value = KvpPolynomial(opening, c);
  return value > T(0.0) ? value : T(0.0);
}

}  // namespace pneumaid
