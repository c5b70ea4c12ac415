// Rod and load, seed paper Eq. 9, and the mechanical end stops.
//
//   M x'' = p1 A1 - p2 A2 - p_atm A_h - F_friction - M g + F_stop
// A_h = A1 - A2 is the rod section, exposed to the atmosphere; g only when the
// cylinder is vertical.
#pragma once

namespace pneumaid {

inline constexpr double kStandardGravity_m_per_s2 = 9.80665;

// Pneumatic force and weight on the rod [N], positive along +x.
template <typename T>
T PneumaticAndGravityForce(const T& p1_Pa, const T& p2_Pa, const T& atmospheric_pressure_Pa,
                           const T& area_1_m2, const T& area_2_m2, const T& weight_N) {
  return p1_Pa * area_1_m2 - p2_Pa * area_2_m2 - atmospheric_pressure_Pa * (area_1_m2 - area_2_m2) -
         weight_N;
}

template <typename T>
struct EndStopCoefficients {
  T half_stroke_m;
  T stiffness_N_per_m;   // contact spring
  T damping_N_s_per_m;   // contact damper at full engagement
  T engagement_depth_m;  // depth over which the damper engages (keeps the force continuous)
};

// One-sided contact of stiffness k and damping c: the force only pushes the rod
// back into the stroke, never pulls it, and is zero at the first touch.
template <typename T>
T ContactForce(const T& depth_m, const T& velocity_into_m_per_s, const EndStopCoefficients<T>& c) {
  if (depth_m <= T(0.0)) return T(0.0);
  const T engagement = depth_m < c.engagement_depth_m ? depth_m / c.engagement_depth_m : T(1.0);
  const T force =
      c.stiffness_N_per_m * depth_m + c.damping_N_s_per_m * engagement * velocity_into_m_per_s;
  return force > T(0.0) ? force : T(0.0);
}

// End-stop force [N] along +x at position x (from mid-stroke) and velocity v.
template <typename T>
T EndStopForce(const T& position_m, const T& velocity_m_per_s, const EndStopCoefficients<T>& c) {
  const T beyond_extended = position_m - c.half_stroke_m;
  const T beyond_retracted = -c.half_stroke_m - position_m;
  return ContactForce(beyond_retracted, -velocity_m_per_s, c) -
         ContactForce(beyond_extended, velocity_m_per_s, c);
}

}  // namespace pneumaid
