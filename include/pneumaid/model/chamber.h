// Cylinder chambers, seed paper Eq. 8: adiabatic mass balance with dead volumes.
//
//   dp/dt = k / V (R T q - p dV/dt)
// x = 0 at mid-stroke; chamber 1 (cap side) grows with x, chamber 2 shrinks.
#pragma once

namespace pneumaid {

template <typename T>
struct ChamberGeometry {
  T area_m2;           // piston area facing this chamber
  T dead_volume_m3;    // volume left at the end of the stroke that empties it
  T half_stroke_m;     // L/2
  T direction;         // +1 for chamber 1 (grows with x), -1 for chamber 2
  T minimum_volume_m3; // guard: the volume never falls below this
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

}  // namespace pneumaid
