// Valve mass flow, seed paper Eq. 4, with a linear region near pressure ratio 1.
//
//   q = K_vp C1 p_u / (N sqrt(T))                                   r <= p_cr
//   q = K_vp C2 p_u / (N sqrt(T)) r^(1/k) sqrt(1 - r^((k-1)/k))      p_cr < r < r_lin
//   q = (value at r_lin) (1 - r) / (1 - r_lin)                       r >= r_lin
// with r = p_d / p_u. Eq. 4's subsonic branch has an unbounded slope as r -> 1,
// which makes a stiff solver crawl when a chamber approaches supply or exhaust
// pressure; like ISO 6358 we make the last stretch linear (laminar-like). The
// flow is antisymmetric: when p_d > p_u it reverses.
#pragma once

#include <cmath>

#include "pneumaid/model/gas.h"

namespace pneumaid {

// Pressure ratio above which the flow is linear in the pressure difference.
// Above it the pressure difference is below 0.5 % of the upstream pressure.
inline constexpr double kDefaultLinearFlowRatio = 0.995;

template <typename T>
struct OrificeCoefficients {
  T C1, C2, critical_ratio;
  T inverse_k;     // 1/k
  T exponent;      // (k-1)/k
  T flow_scale;    // 1 / (N sqrt(T_gas)) [s sqrt(K) ... ] so that q has kg/s
  T linear_ratio;  // r_lin
  T linear_slope;  // phi(r_lin) / (1 - r_lin)
};

// The dimensionless shape phi(r) of Eq. 4 without the linear region.
template <typename T>
T SubsonicShape(const T& ratio, const OrificeCoefficients<T>& c) {
  using std::exp;
  using std::log;
  using std::sqrt;
  const T log_ratio = log(ratio);
  return c.C2 * exp(log_ratio * c.inverse_k) * sqrt(T(1.0) - exp(log_ratio * c.exponent));
}

template <typename T>
OrificeCoefficients<T> MakeOrificeCoefficients(double k, double gas_constant_J_per_kgK,
                                               double temperature_K, double normalization,
                                               double linear_ratio = kDefaultLinearFlowRatio) {
  const OrificeConstants constants = ComputeOrificeConstants(k, gas_constant_J_per_kgK);
  OrificeCoefficients<T> c;
  c.C1 = T(constants.C1);
  c.C2 = T(constants.C2);
  c.critical_ratio = T(constants.critical_ratio);
  c.inverse_k = T(1.0 / k);
  c.exponent = T((k - 1.0) / k);
  c.flow_scale = T(1.0 / (normalization * std::sqrt(temperature_K)));
  c.linear_ratio = T(linear_ratio);
  c.linear_slope = SubsonicShape(c.linear_ratio, c) / (T(1.0) - c.linear_ratio);
  return c;
}

// phi(r) for 0 < r <= 1, the linear region included.
template <typename T>
T FlowShape(const T& ratio, const OrificeCoefficients<T>& c) {
  if (ratio <= c.critical_ratio) return c.C1;
  if (ratio >= c.linear_ratio) return c.linear_slope * (T(1.0) - ratio);
  return SubsonicShape(ratio, c);
}

// Mass flow [kg/s] from port a to port b through a valve of gain K_vp [kg/s].
// Negative when the gas flows from b to a.
template <typename T>
T OrificeMassFlow(const T& kvp, const T& pressure_a_Pa, const T& pressure_b_Pa,
                  const OrificeCoefficients<T>& c) {
  if (pressure_a_Pa >= pressure_b_Pa) {
    return kvp * c.flow_scale * pressure_a_Pa * FlowShape(pressure_b_Pa / pressure_a_Pa, c);
  }
  return -(kvp * c.flow_scale * pressure_b_Pa * FlowShape(pressure_a_Pa / pressure_b_Pa, c));
}

}  // namespace pneumaid
