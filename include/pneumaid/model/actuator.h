// The whole actuator as one ODE: valves, tube, chambers, rod, friction, end
// stops and the simulated effects of the catalog.
//
// Model/data split: `ActuatorLayout` (which states exist) and
// `ActuatorCoefficients<T>` (every number the equations use) are built once
// from a parameter set and never change; the state and the valve command are
// passed in. Everything is templated on the scalar so that ceres::Jet gives
// exact Jacobians (and, later, parameter sensitivities).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <type_traits>

#include "pneumaid/model/chamber.h"
#include "pneumaid/model/friction.h"
#include "pneumaid/model/kvp.h"
#include "pneumaid/model/load.h"
#include "pneumaid/model/orifice.h"
#include "pneumaid/model/parameters.h"
#include "pneumaid/model/valve_bank.h"

namespace pneumaid {

// Numerical treatments that are not physical parameters of the unit. Each one
// replaces a non-smooth feature of the paper's model by a stiff but smooth
// one; docs/model.md explains the choices.
struct ModelRegularization {
  // Half-width of the friction saturation around v = 0. A rod whose net
  // force is below Fs creeps at less than this speed. A parameter set with
  // the stick_creep effect sets its own (and is simulated without stick
  // events).
  double stick_velocity_m_per_s = 1.0e-5;
  // Contact spring of the end stops. 1e7 N/m lets the full supply force on the
  // cap side (100 N) push the rod 10 um past the stop.
  double end_stop_stiffness_N_per_m = 1.0e7;
  // Damping ratio of the rod mass on the contact spring (1 = critical).
  double end_stop_damping_ratio = 1.0;
  // Depth over which the contact damper engages, so the force has no jump.
  double end_stop_engagement_depth_m = 1.0e-5;
  // Pressure ratio above which valve flow is linear in the pressure difference.
  double linear_flow_ratio = kDefaultLinearFlowRatio;
  // pipeline.model: flow_lag only: below this absolute chamber pressure the
  // lagged outflow is faded out so that no pressure reaches zero.
  double flow_lag_pressure_floor_Pa = 1.0e3;
  // A chamber volume never falls below this fraction of its dead volume.
  double minimum_volume_fraction = 0.1;

  bool IsValid(std::string* error) const;
};

// Fixed state indices; optional states follow from index 4 in the order of
// the layout's fields. The chamber states are sigma of chamber.h, not p: use
// ChamberPressures() / SetChamberPressures() to read and write pressures.
enum StateIndex : int { kPosition = 0, kVelocity = 1, kChamber1 = 2, kChamber2 = 3 };

// 4 + 2 per optional group: valve_lag, the pipeline's lag (conductance_lag or
// flow_lag, never both), flow_sensor_lag, heat_transfer.
inline constexpr int kMaxStates = 12;

struct ActuatorLayout {
  bool valve_lag = false;        // 2 states: lagged opening of each valve pair [V]
  bool conductance_lag = false;  // 2 states: lagged K_vp of each valve pair [kg/s]
  bool flow_lag = false;         // 2 states: lagged mass flows into chambers [kg/s]
  bool flow_sensor_lag = false;  // 2 states: flows as the meters read them [kg/s]
  bool heat_transfer = false;    // 2 states: each chamber's gas temperature [K]
  bool supply_droop = false;     // no state: the supply pressure is solved per call
  int opening_begin = -1, conductance_begin = -1, flow_begin = -1, sensor_begin = -1;
  int temperature_begin = -1;
  int size = 4;

  // Which states the parameter set needs. Requires a validated parameter set.
  static ActuatorLayout For(const Parameters& params);
};

template <typename T>
struct ActuatorCoefficients {
  OrificeCoefficients<T> orifice;
  KvpCoefficients<T> increasing, decreasing;
  T heat_capacity_ratio, k_RT;
  T gas_constant_J_per_kgK, supply_temperature_K;  // the wall's and the inflow's temperature
  T supply_pressure_Pa, atmospheric_pressure_Pa;
  ChamberGeometry<T> chamber_1, chamber_2;
  T area_1_m2, area_2_m2, load_mass_kg, weight_N;
  StribeckCoefficients<T> friction_positive, friction_negative;
  T stick_velocity_m_per_s;
  EndStopCoefficients<T> end_stop;
  T pipeline_delta_per_s;
  T flow_lag_pressure_floor_Pa;
  // Effects; zero when the effect is absent (and then unused).
  T valve_lag_tau_s, flow_sensor_tau_s, leak_conductance_kg_per_s_Pa;
  T friction_pressure_per_Pa, deadzone_V;
  T heat_transfer_W_per_K, supply_resistance_Pa_s_per_kg;
};

// The coefficients seen as a flat array of scalars: every member of
// ActuatorCoefficients<T> is a T (checked where this is used), so parameter
// sensitivities can be carried coefficient by coefficient.
template <typename T>
inline constexpr int kCoefficientCount = static_cast<int>(sizeof(ActuatorCoefficients<T>) /
                                                          sizeof(T));

template <typename T>
T* CoefficientArray(ActuatorCoefficients<T>* c) {
  static_assert(std::is_standard_layout_v<ActuatorCoefficients<T>>);
  static_assert(sizeof(ActuatorCoefficients<T>) % sizeof(T) == 0);
  static_assert(kCoefficientCount<T> == kCoefficientCount<double>);
  return reinterpret_cast<T*>(c);
}

template <typename T>
const T* CoefficientArray(const ActuatorCoefficients<T>& c) {
  return CoefficientArray(const_cast<ActuatorCoefficients<T>*>(&c));
}

// The valve inputs held constant over one input segment.
struct ValveCommand {
  ValveOpenings opening{0, 0, 0, 0};
  std::array<bool, kValveCount> decreasing_branch{false, false, false, false};
};

// What the sensors of a rig would see, besides the state itself.
template <typename T>
struct ActuatorOutputs {
  T p1_Pa, p2_Pa;              // absolute chamber pressures
  T q1_kg_per_s, q2_kg_per_s;  // mass flows into the chambers at the valve side
};

// stick_creep: the rod creeps below its breakaway force (friction saturates
// within |v| < the effect's v), so it has no stuck mode; its width replaces
// ModelRegularization::stick_velocity_m_per_s.
inline bool Creeps(const Parameters& p) { return p.effects.count("stick_creep") > 0; }

namespace internal {
inline double EffectValue(const Parameters& p, const char* name, const char* key) {
  const auto effect = p.effects.find(name);
  return effect == p.effects.end() ? 0.0 : effect->second.at(key);
}
}  // namespace internal

template <typename T>
ActuatorCoefficients<T> MakeActuatorCoefficients(const Parameters& p,
                                                 const ModelRegularization& reg) {
  ActuatorCoefficients<T> c;
  const double k = p.gas.heat_capacity_ratio;
  c.orifice = MakeOrificeCoefficients<T>(k, p.gas.gas_constant_J_per_kgK, p.gas.temperature_K,
                                         p.valve.normalization, reg.linear_flow_ratio);
  c.increasing = MakeKvpCoefficients<T>(p.valve.increasing);
  c.decreasing = MakeKvpCoefficients<T>(p.valve.decreasing);
  c.heat_capacity_ratio = T(k);
  c.k_RT = T(k * p.gas.gas_constant_J_per_kgK * p.gas.temperature_K);
  c.gas_constant_J_per_kgK = T(p.gas.gas_constant_J_per_kgK);
  c.supply_temperature_K = T(p.gas.temperature_K);
  c.supply_pressure_Pa = T(p.supply.supply_pressure_Pa);
  c.atmospheric_pressure_Pa = T(p.supply.atmospheric_pressure_Pa);
  const auto& cyl = p.cylinder;
  const double half_stroke = 0.5 * cyl.stroke_m;
  c.chamber_1 = {T(cyl.area_1_m2),
                 T(cyl.dead_volume_1_m3),
                 T(half_stroke),
                 T(1.0),
                 T(reg.minimum_volume_fraction * cyl.dead_volume_1_m3),
                 T(cyl.dead_volume_1_m3 + cyl.area_1_m2 * cyl.stroke_m)};
  c.chamber_2 = {T(cyl.area_2_m2),
                 T(cyl.dead_volume_2_m3),
                 T(half_stroke),
                 T(-1.0),
                 T(reg.minimum_volume_fraction * cyl.dead_volume_2_m3),
                 T(cyl.dead_volume_2_m3 + cyl.area_2_m2 * cyl.stroke_m)};
  c.area_1_m2 = T(cyl.area_1_m2);
  c.area_2_m2 = T(cyl.area_2_m2);
  c.load_mass_kg = T(cyl.load_mass_kg);
  c.weight_N =
      T(cyl.orientation == Orientation::kVertical ? cyl.load_mass_kg * kStandardGravity_m_per_s2
                                                  : 0.0);
  c.friction_positive = MakeStribeckCoefficients<T>(p.friction.positive);
  c.friction_negative = MakeStribeckCoefficients<T>(p.friction.negative);
  c.stick_velocity_m_per_s =
      T(Creeps(p) ? internal::EffectValue(p, "stick_creep", "v") : reg.stick_velocity_m_per_s);
  const double stiffness = reg.end_stop_stiffness_N_per_m;
  c.end_stop = {T(half_stroke), T(stiffness),
                T(2.0 * reg.end_stop_damping_ratio * std::sqrt(stiffness * cyl.load_mass_kg)),
                T(reg.end_stop_engagement_depth_m)};
  const bool lag_from_effect = p.pipeline.model == PipelineModel::kNone;
  c.pipeline_delta_per_s = T(lag_from_effect ? internal::EffectValue(p, "pipeline_lag", "delta")
                                             : p.pipeline.delta_per_s);
  c.flow_lag_pressure_floor_Pa = T(reg.flow_lag_pressure_floor_Pa);
  c.valve_lag_tau_s = T(internal::EffectValue(p, "valve_lag", "tau"));
  c.flow_sensor_tau_s = T(internal::EffectValue(p, "flow_sensor_lag", "tau"));
  c.leak_conductance_kg_per_s_Pa = T(internal::EffectValue(p, "cross_leakage", "c"));
  c.friction_pressure_per_Pa = T(internal::EffectValue(p, "friction_pressure", "kp"));
  c.deadzone_V = T(internal::EffectValue(p, "valve_deadzone", "u0"));
  c.heat_transfer_W_per_K = T(internal::EffectValue(p, "heat_transfer", "h"));
  c.supply_resistance_Pa_s_per_kg = T(internal::EffectValue(p, "supply_droop", "r"));
  return c;
}

// valve_deadzone: no flow below u0, the remaining range rescaled to [0, 1].
template <typename T>
T EffectiveOpening(const T& opening_V, const T& deadzone_V) {
  if (opening_V <= deadzone_V) return T(0.0);
  return (opening_V - deadzone_V) / (T(1.0) - deadzone_V);
}

// Valve openings the orifices see: the command, or its lagged state.
template <typename T>
std::array<T, kValveCount> ValveOpeningsInUse(const ActuatorLayout& layout,
                                              const ValveCommand& command, const T* y) {
  std::array<T, kValveCount> opening;
  for (int i = 0; i < kValveCount; ++i) opening[i] = T(command.opening[i]);
  if (layout.valve_lag) {
    for (int pair = 0; pair < kValvePairCount; ++pair) {
      const T& lagged = y[layout.opening_begin + pair];
      opening[kValvePairs[pair].lead] = opening[kValvePairs[pair].partner] = lagged;
    }
  }
  return opening;
}

// Commanded K_vp [kg/s] of each valve (before any tube lag).
template <typename T>
std::array<T, kValveCount> ValveGains(const ActuatorCoefficients<T>& c, const ValveCommand& command,
                                      const std::array<T, kValveCount>& opening) {
  std::array<T, kValveCount> gain;
  for (int i = 0; i < kValveCount; ++i) {
    const auto& branch = command.decreasing_branch[i] ? c.decreasing : c.increasing;
    gain[i] = Kvp(EffectiveOpening(opening[i], c.deadzone_V), branch);
  }
  return gain;
}

// Mass flow [kg/s] through one valve for its gain; a closed valve passes
// nothing (skipping it saves the costly powers).
template <typename T>
T ValveFlow(const ActuatorCoefficients<T>& c, const std::array<T, kValveCount>& gain, int valve,
            const T& from_Pa, const T& to_Pa) {
  return gain[valve] > T(0.0) ? OrificeMassFlow(gain[valve], from_Pa, to_Pa, c.orifice) : T(0.0);
}

// supply_droop: the supply pressure p_s at the valves solves
// p_s = p_supply - r q_s(p_s), q_s the mass flow drawn through both supply
// valves. f(p_s) = p_s - p_supply + r q_s(p_s) rises with p_s (q_s does), so
// the root is unique; it is bracketed in [p_atm / 2, max(p_supply, p1, p2)] and found in
// doubles by safeguarded Newton steps, then one Newton step in T from that
// root gives the implicit derivatives -f_theta / f' exactly (f = 0 there).
template <typename T>
T DroopedSupplyPressure(const ActuatorCoefficients<T>& c, const std::array<T, kValveCount>& gain,
                        const T& p1, const T& p2) {
  const auto residual = [&](const auto& supply, const auto& g, const auto& q1, const auto& q2,
                            const auto& cc) {
    using S = std::decay_t<decltype(supply)>;
    const S drawn = ValveFlow(cc, g, kSupplyToChamber1, supply, q1) +
                    ValveFlow(cc, g, kSupplyToChamber2, supply, q2);
    return supply - cc.supply_pressure_Pa + cc.supply_resistance_Pa_s_per_kg * drawn;
  };
  const auto value = [](const T& x) {
    if constexpr (std::is_same_v<T, double>) {
      return x;
    } else {
      return x.a;
    }
  };
  ActuatorCoefficients<double> plain;
  const T* from = CoefficientArray(c);
  double* to = CoefficientArray(&plain);
  for (int k = 0; k < kCoefficientCount<double>; ++k) to[k] = value(from[k]);
  std::array<double, kValveCount> g;
  for (int i = 0; i < kValveCount; ++i) g[i] = value(gain[i]);
  const double q1 = value(p1), q2 = value(p2);
  const auto f = [&](double supply) { return residual(supply, g, q1, q2, plain); };
  // f >= 0 at the highest of p_supply and the chambers' pressures (no flow
  // can be drawn there): a chamber above the supply pushes the root above it.
  double low = 0.5 * plain.atmospheric_pressure_Pa;
  double high = std::max({plain.supply_pressure_Pa, q1, q2});
  double root = high, slope = 1.0;
  const double tolerance = 1e-13 * plain.supply_pressure_Pa;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double step = 1e-7 * plain.supply_pressure_Pa;
    const double at = f(root);
    slope = (f(root + step) - f(root - step)) / (2 * step);
    const double newton = root - at / slope;
    if (std::fabs(newton - root) <= tolerance) break;  // converged (before any bracket test)
    (at > 0 ? high : low) = root;
    root = newton > low && newton < high ? newton : 0.5 * (low + high);  // else bisect
  }
  return T(root) - residual(T(root), gain, p1, p2, c) / slope;
}

// Mass flows [kg/s] into chambers 1 and 2 through the valves, for given gains
// and the supply pressure at the valves.
template <typename T>
std::array<T, 2> ValveFlows(const ActuatorCoefficients<T>& c,
                            const std::array<T, kValveCount>& gain, const T& p1, const T& p2,
                            const T& supply_Pa) {
  return {ValveFlow(c, gain, kSupplyToChamber1, supply_Pa, p1) -
              ValveFlow(c, gain, kChamber1ToExhaust, p1, c.atmospheric_pressure_Pa),
          ValveFlow(c, gain, kSupplyToChamber2, supply_Pa, p2) -
              ValveFlow(c, gain, kChamber2ToExhaust, p2, c.atmospheric_pressure_Pa)};
}

// Mass flows [kg/s] into chambers 1 and 2 through the valves, with the
// supply pressure p_supply or, with supply_droop, the drooped one.
template <typename T>
std::array<T, 2> ChamberInflows(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                                const std::array<T, kValveCount>& gain, const T& p1, const T& p2) {
  if (!layout.supply_droop) return ValveFlows(c, gain, p1, p2, c.supply_pressure_Pa);
  return ValveFlows(c, gain, p1, p2, DroopedSupplyPressure(c, gain, p1, p2));
}

// flow_lag guard: fades an outflow out between floor and 2 x floor.
template <typename T>
T GuardedOutflow(const T& flow, const T& pressure_Pa, const T& floor_Pa) {
  if (flow >= T(0.0)) return flow;
  T fraction = (pressure_Pa - floor_Pa) / floor_Pa;
  if (fraction < T(0.0)) fraction = T(0.0);
  if (fraction > T(1.0)) fraction = T(1.0);
  return flow * fraction;
}

// How the rod's friction is treated (see friction.h and docs/model.md).
enum class MotionMode {
  kRegularized,      // one smooth law for all v: stick is a stiff viscous band
  kStuck,            // static friction holds the rod: x and v frozen
  kSlidingPositive,  // v >= 0, Eq. 12 with the positive coefficients
  kSlidingNegative,  // v <= 0, Eq. 12 with the negative coefficients
};

// Chamber pressures and volumes at a state.
template <typename T>
struct ChamberPressures {
  T p1_Pa, p2_Pa, volume_1_m3, volume_2_m3;
};

template <typename T>
ChamberPressures<T> DecodeChambers(const ActuatorCoefficients<T>& c, const T* y) {
  ChamberPressures<T> out;
  out.volume_1_m3 = ChamberVolume(y[kPosition], c.chamber_1);
  out.volume_2_m3 = ChamberVolume(y[kPosition], c.chamber_2);
  out.p1_Pa = PressureFromChamberState(y[kChamber1], out.volume_1_m3, c.heat_capacity_ratio,
                                       c.atmospheric_pressure_Pa, c.chamber_1);
  out.p2_Pa = PressureFromChamberState(y[kChamber2], out.volume_2_m3, c.heat_capacity_ratio,
                                       c.atmospheric_pressure_Pa, c.chamber_2);
  return out;
}

// Writes the chamber states of `y` for pressures p1, p2 at position y[kPosition].
template <typename T>
void SetChamberPressures(const ActuatorCoefficients<T>& c, const T& p1_Pa, const T& p2_Pa, T* y) {
  y[kChamber1] =
      ChamberStateFromPressure(p1_Pa, ChamberVolume(y[kPosition], c.chamber_1),
                               c.heat_capacity_ratio, c.atmospheric_pressure_Pa, c.chamber_1);
  y[kChamber2] =
      ChamberStateFromPressure(p2_Pa, ChamberVolume(y[kPosition], c.chamber_2),
                               c.heat_capacity_ratio, c.atmospheric_pressure_Pa, c.chamber_2);
}

// Everything that pushes the rod except friction [N], along +x.
template <typename T>
T DrivingForce(const ActuatorCoefficients<T>& c, const T* y, const ChamberPressures<T>& p) {
  const T drive = PneumaticAndGravityForce(p.p1_Pa, p.p2_Pa, c.atmospheric_pressure_Pa, c.area_1_m2,
                                           c.area_2_m2, c.weight_N);
  return drive + EndStopForce(y[kPosition], y[kVelocity], c.end_stop);
}

// friction_pressure: friction scales by 1 + kp ((p1 + p2)/2 - p_atm).
template <typename T>
T FrictionScale(const ActuatorCoefficients<T>& c, const ChamberPressures<T>& p) {
  return T(1.0) +
         c.friction_pressure_per_Pa * (T(0.5) * (p.p1_Pa + p.p2_Pa) - c.atmospheric_pressure_Pa);
}

// Breakaway force [N] of the rod in the direction of `sign` (+1 or -1).
template <typename T>
T BreakawayForce(const ActuatorCoefficients<T>& c, const ChamberPressures<T>& p, double sign) {
  const auto& side = sign > 0 ? c.friction_positive : c.friction_negative;
  return FrictionScale(c, p) * side.static_force_N;
}

// Rod acceleration [m/s^2], Eq. 9 with Eq. 12 under the given motion mode.
template <typename T>
T RodAcceleration(const ActuatorCoefficients<T>& c, MotionMode motion, const T* y,
                  const ChamberPressures<T>& p) {
  const T& v = y[kVelocity];
  T friction;
  switch (motion) {
    case MotionMode::kStuck:
      return T(0.0);
    case MotionMode::kSlidingPositive:
      friction = StribeckMagnitude(v > T(0.0) ? v : T(0.0), c.friction_positive);
      break;
    case MotionMode::kSlidingNegative:
      friction = -StribeckMagnitude(v < T(0.0) ? T(-v) : T(0.0), c.friction_negative);
      break;
    case MotionMode::kRegularized:
    default:
      friction =
          FrictionForce(v, c.friction_positive, c.friction_negative, c.stick_velocity_m_per_s);
      break;
  }
  return (DrivingForce(c, y, p) - FrictionScale(c, p) * friction) / c.load_mass_kg;
}

// heat_transfer: the chambers' states and gas temperatures T_i. Energy of
// each chamber's gas: inflow enters at the supply temperature, outflow (and
// the seal leak) leaves at its source chamber's temperature, the wall (at the
// supply temperature) exchanges h (T_wall - T_i):
//   dp/dt = (k R (T_in q_in - T_i q_out) + (k - 1) h (T_wall - T_i) - k p dV/dt) / V
//   dT/dt = T_i (dp/dt / p + dV/dt / V - R T_i q_net / (p V))   (m = p V / (R T_i))
// in the chamber state sigma of chamber.h: d sigma/dt = dp/dt / p + k dV/dt / V.
template <typename T>
void ChamberRatesWithHeat(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                          MotionMode motion, const T* y, const ChamberPressures<T>& chambers,
                          const std::array<T, 2>& flow, const T& leak, T* dydt) {
  const T* temperature = y + layout.temperature_begin;
  const T leak_temperature = leak > T(0.0) ? temperature[0] : temperature[1];
  const T k = c.heat_capacity_ratio, R = c.gas_constant_J_per_kgK;
  const T speed = motion == MotionMode::kStuck ? T(0.0) : y[kVelocity];
  const T pressure[2] = {chambers.p1_Pa, chambers.p2_Pa};
  const T volume[2] = {chambers.volume_1_m3, chambers.volume_2_m3};
  const T volume_rate[2] = {c.chamber_1.direction * c.area_1_m2 * speed,
                            c.chamber_2.direction * c.area_2_m2 * speed};
  const T leak_in[2] = {-leak, leak};
  for (int i = 0; i < 2; ++i) {
    const T& gas = temperature[i];
    const T carried = (flow[i] > T(0.0) ? c.supply_temperature_K : gas) * flow[i] +
                      leak_temperature * leak_in[i];  // [K kg/s]
    const T heat = c.heat_transfer_W_per_K * (c.supply_temperature_K - gas);
    const T pV = pressure[i] * volume[i];
    const T sigma_rate = (k * R * carried + (k - T(1.0)) * heat) / pV;
    dydt[kChamber1 + i] = sigma_rate;
    dydt[layout.temperature_begin + i] =
        gas * (sigma_rate - (k - T(1.0)) * volume_rate[i] / volume[i] -
               R * gas * (flow[i] + leak_in[i]) / pV);
  }
}

namespace internal {

// ActuatorDerivatives for a model with (kThermal) or without heat_transfer
// and supply_droop: two instantiations, so that the base model's right-hand
// side has no trace of the effects it lacks (a run-time branch around them
// cost 0.5 % of the paper step's instructions in spilled registers).
template <typename T, bool kThermal>
void Derivatives(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                 const ValveCommand& command, MotionMode motion, const T* y, T* dydt,
                 ActuatorOutputs<T>* outputs) {
  const ChamberPressures<T> chambers = DecodeChambers(c, y);
  const T& p1 = chambers.p1_Pa;
  const T& p2 = chambers.p2_Pa;

  const auto opening = ValveOpeningsInUse(layout, command, y);
  if (layout.valve_lag) {
    for (int pair = 0; pair < kValvePairCount; ++pair) {
      const int lead = kValvePairs[pair].lead;
      dydt[layout.opening_begin + pair] =
          (T(command.opening[lead]) - opening[lead]) / c.valve_lag_tau_s;
    }
  }
  auto gain = ValveGains(c, command, opening);
  if (layout.conductance_lag) {
    for (int pair = 0; pair < kValvePairCount; ++pair) {
      const T& lagged = y[layout.conductance_begin + pair];
      const ValvePair valves = kValvePairs[pair];
      dydt[layout.conductance_begin + pair] = c.pipeline_delta_per_s * (gain[valves.lead] - lagged);
      gain[valves.lead] = gain[valves.partner] = lagged;
    }
  }
  auto flow = kThermal ? ChamberInflows(layout, c, gain, p1, p2)
                       : ValveFlows(c, gain, p1, p2, c.supply_pressure_Pa);
  if (layout.flow_lag) {
    const T* lagged = y + layout.flow_begin;
    dydt[layout.flow_begin] = c.pipeline_delta_per_s * (flow[0] - lagged[0]);
    dydt[layout.flow_begin + 1] = c.pipeline_delta_per_s * (flow[1] - lagged[1]);
    flow = {GuardedOutflow(lagged[0], p1, c.flow_lag_pressure_floor_Pa),
            GuardedOutflow(lagged[1], p2, c.flow_lag_pressure_floor_Pa)};
  }
  if (layout.flow_sensor_lag) {
    for (int i = 0; i < 2; ++i) {
      dydt[layout.sensor_begin + i] = (flow[i] - y[layout.sensor_begin + i]) / c.flow_sensor_tau_s;
    }
  }
  if (outputs != nullptr) {
    outputs->p1_Pa = p1;
    outputs->p2_Pa = p2;
    outputs->q1_kg_per_s = layout.flow_sensor_lag ? y[layout.sensor_begin] : flow[0];
    outputs->q2_kg_per_s = layout.flow_sensor_lag ? y[layout.sensor_begin + 1] : flow[1];
  }

  const T leak = c.leak_conductance_kg_per_s_Pa * (p1 - p2);  // cross_leakage, 1 -> 2
  if (kThermal && layout.heat_transfer) {
    ChamberRatesWithHeat(layout, c, motion, y, chambers, flow, leak, dydt);
  } else {
    dydt[kChamber1] = ChamberStateRate(p1, chambers.volume_1_m3, flow[0] - leak, c.k_RT);
    dydt[kChamber2] = ChamberStateRate(p2, chambers.volume_2_m3, flow[1] + leak, c.k_RT);
  }

  dydt[kPosition] = motion == MotionMode::kStuck ? T(0.0) : y[kVelocity];
  dydt[kVelocity] = RodAcceleration(c, motion, y, chambers);
}

}  // namespace internal

// The right-hand side dy/dt = f(y, command, motion). `outputs` may be null.
template <typename T>
void ActuatorDerivatives(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                         const ValveCommand& command, MotionMode motion, const T* y, T* dydt,
                         ActuatorOutputs<T>* outputs) {
  if (layout.heat_transfer || layout.supply_droop) {
    internal::Derivatives<T, true>(layout, c, command, motion, y, dydt, outputs);
  } else {
    internal::Derivatives<T, false>(layout, c, command, motion, y, dydt, outputs);
  }
}

// Sets the lag states of `y` to their steady values for `command` at the
// pressures already in `y`, as if the command had been held for a long time.
template <typename T>
void SetLagStatesToEquilibrium(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                               const ValveCommand& command, T* y) {
  for (int pair = 0; pair < kValvePairCount && layout.valve_lag; ++pair) {
    y[layout.opening_begin + pair] = T(command.opening[kValvePairs[pair].lead]);
  }
  const auto opening = ValveOpeningsInUse(layout, command, y);
  const auto gain = ValveGains(c, command, opening);
  for (int pair = 0; pair < kValvePairCount && layout.conductance_lag; ++pair) {
    y[layout.conductance_begin + pair] = gain[kValvePairs[pair].lead];
  }
  const ChamberPressures<T> chambers = DecodeChambers(c, y);
  const auto flow = ChamberInflows(layout, c, gain, chambers.p1_Pa, chambers.p2_Pa);
  for (int i = 0; i < 2; ++i) {
    if (layout.flow_lag) y[layout.flow_begin + i] = flow[i];
    if (layout.flow_sensor_lag) y[layout.sensor_begin + i] = flow[i];
  }
}

}  // namespace pneumaid
