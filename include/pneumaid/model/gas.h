// Isentropic orifice constants of seed paper Eq. 2, computed from k and R.
#pragma once

#include <cmath>

namespace pneumaid {

struct OrificeConstants {
  double C1;              // choked flow constant [sqrt(kg K / J)], paper 0.0404
  double C2;              // subsonic flow constant [sqrt(kg K / J)], paper 0.1562
  double critical_ratio;  // p_cr = p_d / p_u where the flow chokes, paper 0.528
};

// k: heat capacity ratio, R: specific gas constant [J/(kg K)].
inline OrificeConstants ComputeOrificeConstants(double k, double gas_constant_J_per_kgK) {
  const double R = gas_constant_J_per_kgK;
  const double two_over_kp1 = 2.0 / (k + 1.0);
  OrificeConstants out;
  out.C1 = std::sqrt(k / R * std::pow(two_over_kp1, (k + 1.0) / (k - 1.0)));
  out.C2 = std::sqrt(2.0 * k / (R * (k - 1.0)));
  out.critical_ratio = std::pow(two_over_kp1, k / (k - 1.0));
  return out;
}

}  // namespace pneumaid
