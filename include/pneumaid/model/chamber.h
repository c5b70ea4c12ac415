// Cylinder chambers, seed paper Eq. 8: adiabatic mass balance with dead volumes.
//
//   dp/dt = k / V (R T q - p dV/dt)
// x = 0 at mid-stroke; chamber 1 (cap side) grows with x, chamber 2 shrinks.
//
// The simulator integrates each chamber as sigma = ln(p / p_ref) + k ln(V / V_ref)
// instead of p. Eq. 8 then reads d sigma/dt = k R T q / (p V): with closed
// valves sigma is constant, so the isentropic invariant p V^k is kept exactly
// by construction (not just to the integrator's tolerance), and p = p_ref
// exp(...) can never reach zero.
#pragma once

#include <cmath>

namespace pneumaid {

template <typename T>
struct ChamberGeometry {
  T area_m2;              // piston area facing this chamber
  T dead_volume_m3;       // volume left at the end of the stroke that empties it
  T half_stroke_m;        // L/2
  T direction;            // +1 for chamber 1 (grows with x), -1 for chamber 2
  T minimum_volume_m3;    // guard: the volume never falls below this
  T reference_volume_m3;  // V_ref of the chamber state: its full volume
};

// V = V0 + A (L/2 +- x), floored at minimum_volume (reached only if an end stop
// is overrun by more than V0/A, which the end-stop force prevents).
template <typename T>
T ChamberVolume(const T& position_m, const ChamberGeometry<T>& g) {
  const T volume = g.dead_volume_m3 + g.area_m2 * (g.half_stroke_m + g.direction * position_m);
  return volume > g.minimum_volume_m3 ? volume : g.minimum_volume_m3;
}

// dp/dt [Pa/s] for net mass inflow q [kg/s] while the rod moves at v [m/s].
// k_RT = k R T [J/kg].
template <typename T>
T ChamberPressureRate(const T& pressure_Pa, const T& volume_m3, const T& mass_inflow_kg_per_s,
                      const T& velocity_m_per_s, const T& heat_capacity_ratio, const T& k_RT,
                      const ChamberGeometry<T>& g) {
  const T volume_rate = g.direction * g.area_m2 * velocity_m_per_s;
  return (k_RT * mass_inflow_kg_per_s - heat_capacity_ratio * pressure_Pa * volume_rate) /
         volume_m3;
}

// sigma = ln(p / p_ref) + k ln(V / V_ref).
template <typename T>
T ChamberStateFromPressure(const T& pressure_Pa, const T& volume_m3, const T& heat_capacity_ratio,
                           const T& reference_pressure_Pa, const ChamberGeometry<T>& g) {
  using std::log;
  return log(pressure_Pa / reference_pressure_Pa) +
         heat_capacity_ratio * log(volume_m3 / g.reference_volume_m3);
}

// p = p_ref exp(sigma - k ln(V / V_ref)).
template <typename T>
T PressureFromChamberState(const T& state, const T& volume_m3, const T& heat_capacity_ratio,
                           const T& reference_pressure_Pa, const ChamberGeometry<T>& g) {
  using std::exp;
  using std::log;
  return reference_pressure_Pa *
         exp(state - heat_capacity_ratio * log(volume_m3 / g.reference_volume_m3));
}

// d sigma/dt [1/s] for net mass inflow q [kg/s]; Eq. 8 divided by p.
template <typename T>
T ChamberStateRate(const T& pressure_Pa, const T& volume_m3, const T& mass_inflow_kg_per_s,
                   const T& k_RT) {
  return k_RT * mass_inflow_kg_per_s / (pressure_Pa * volume_m3);
}

}  // namespace pneumaid
