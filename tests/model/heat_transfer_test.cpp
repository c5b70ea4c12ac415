// heat_transfer (actuator.h ChamberRatesWithHeat): each chamber's gas
// temperature as a state, wall exchange h (T_wall - T). Physical invariants
// of the right-hand side and closed forms of whole runs.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "../sim/sim_test_util.h"
#include "pneumaid/model/actuator.h"
#include "pneumaid/sim/command.h"
#include "pneumaid/sim/simulate.h"

namespace pneumaid {
namespace {

struct Rates {
  std::vector<double> y, f;
  double p1, p2, v1, v2;
};

// The rates at rod speed v with chamber pressures p1, p2, gas temperatures
// t1, t2, valves at `command_V` (0: all shut).
Rates At(const Parameters& params, double v, double p1, double p2, double t1, double t2,
         double command_V = 0.0) {
  const ActuatorLayout layout = ActuatorLayout::For(params);
  const auto c = MakeActuatorCoefficients<double>(params, ModelRegularization{});
  Rates r;
  r.y.assign(layout.size, 0.0);
  r.f.assign(layout.size, 0.0);
  r.y[kPosition] = 0.01;
  r.y[kVelocity] = v;
  SetChamberPressures(c, p1, p2, r.y.data());
  if (layout.heat_transfer) {
    r.y[layout.temperature_begin] = t1;
    r.y[layout.temperature_begin + 1] = t2;
  }
  ValveCommand command;
  command.opening = OpeningsForCommand(command_V);
  SetLagStatesToEquilibrium(layout, c, command, r.y.data());
  ActuatorDerivatives<double>(layout, c, command, MotionMode::kRegularized, r.y.data(), r.f.data(),
                              nullptr);
  const auto chambers = DecodeChambers(c, r.y.data());
  r.p1 = chambers.p1_Pa, r.p2 = chambers.p2_Pa;
  r.v1 = chambers.volume_1_m3, r.v2 = chambers.volume_2_m3;
  return r;
}

Parameters WithHeat(double h) {
  Parameters p;
  p.pipeline.model = PipelineModel::kNone;  // no tube lag: the valve flows act at once
  p.effects["heat_transfer"] = {{"h", h}};
  return p;
}

// Valves shut, no wall exchange, the rod moving: each chamber's gas is
// compressed isentropically, p V^k and T V^(k-1) constant.
TEST(HeatTransferTest, WithoutExchangeAShutChamberIsIsentropic) {
  const Parameters params = WithHeat(0.0);
  const ActuatorLayout layout = ActuatorLayout::For(params);
  const double k = params.gas.heat_capacity_ratio;
  const Rates r = At(params, 0.2, 3e5, 4e5, 310.0, 280.0);
  const double area[2] = {params.cylinder.area_1_m2, -params.cylinder.area_2_m2};
  const double volume[2] = {r.v1, r.v2}, temperature[2] = {310.0, 280.0};
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(r.f[kChamber1 + i], 0.0, 1e-12) << i;  // sigma = ln p + k ln V: constant
    const double volume_rate = area[i] * 0.2;
    // d ln T/dt = -(k - 1) d ln V/dt
    EXPECT_NEAR(r.f[layout.temperature_begin + i] / temperature[i],
                -(k - 1) * volume_rate / volume[i], 1e-9)
        << i;
  }
}

// Valves shut, rod still, gas hotter than the wall: the mass stays, the
// internal energy p V / (k - 1) falls at h (T_wall - T).
TEST(HeatTransferTest, AShutChamberLosesHeatToTheWallAtConstantMass) {
  const double h = 0.4;
  const Parameters params = WithHeat(h);
  const ActuatorLayout layout = ActuatorLayout::For(params);
  const double k = params.gas.heat_capacity_ratio, wall = params.gas.temperature_K;
  const Rates r = At(params, 0.0, 5e5, 2e5, 360.0, 250.0);
  const double pressure[2] = {r.p1, r.p2}, volume[2] = {r.v1, r.v2};
  const double temperature[2] = {360.0, 250.0};
  for (int i = 0; i < 2; ++i) {
    const double p_rate = r.f[kChamber1 + i] * pressure[i];  // V constant: dp/dt = p dsigma/dt
    const double t_rate = r.f[layout.temperature_begin + i];
    EXPECT_NEAR(volume[i] * p_rate / (k - 1), h * (wall - temperature[i]),
                1e-9 * std::fabs(h * (wall - temperature[i])))
        << i;
    // m = p V / (R T): dm/dt / m = dp/p - dT/T = 0.
    EXPECT_NEAR(p_rate / pressure[i] - t_rate / temperature[i], 0.0, 1e-12) << i;
    EXPECT_GT((wall - temperature[i]) * t_rate, 0.0) << "towards the wall";
  }
}

// Filling at the supply temperature, without exchange: the pressure rate is
// the base model's (Eq. 8) whatever the chamber's temperature.
TEST(HeatTransferTest, ChargingMatchesTheBaseModelsPressureRate) {
  Parameters base;
  base.pipeline.model = PipelineModel::kNone;
  const Rates with = At(WithHeat(0.0), 0.05, 2e5, 5e5, 330.0, 300.0, 0.8);
  const Rates without = At(base, 0.05, 2e5, 5e5, 0.0, 0.0, 0.8);
  EXPECT_GT(with.f[kChamber1], 0.0);  // chamber 1 fills at +0.8 V
  EXPECT_NEAR(with.f[kChamber1], without.f[kChamber1], 1e-12 * std::fabs(without.f[kChamber1]));
  // Chamber 2 exhausts gas at its own temperature (300 K vs the supply's
  // 293.15 K): its pressure falls faster in proportion.
  EXPECT_NEAR(with.f[kChamber2] / without.f[kChamber2], 300.0 / base.gas.temperature_K, 1e-9);
}

// Whole runs, rod held by friction: the gas heated by a fast charge relaxes
// to the wall's temperature once the valves shut, and the pressure with it.
// A rigid closed chamber's temperature obeys m c_v dT/dt = h (T_wall - T):
// an exponential with tau = m c_v / h, m = p_final V / (R T_wall); with
// h = 0 the pressure holds.
TEST(HeatTransferTest, PressureRelaxesAfterAChargeAtTheClosedFormRate) {
  const double h = 0.05;  // W/K: a 16 mm bore's wall, tau of a few tenths of a second
  Parameters params = WithHeat(h);
  params.cylinder.orientation = Orientation::kHorizontal;
  for (StribeckParams* side : {&params.friction.positive, &params.friction.negative}) {
    side->static_force_N = 500.0;  // the rod stays put: V constant
    side->dynamic_force_N = 400.0;
  }
  const auto run = [&params](double h_W_per_K) {
    Parameters p = params;
    p.effects["heat_transfer"]["h"] = h_W_per_K;
    InitialState initial;
    initial.p1_Pa = initial.p2_Pa = p.supply.atmospheric_pressure_Pa;
    // Charge chamber 1 for 50 ms, then shut.
    return testing::MustSimulate(p, StepCommand({{0.0, 1.0}, {0.05, 0.0}}), initial,
                                 UniformTimes(0, 3.0, 100));
  };
  const Trajectory adiabatic = run(0.0), exchanging = run(h);
  const std::size_t shut = 5, late = 300;  // t = 0.05 s and 3 s
  EXPECT_NEAR(adiabatic.p1_Pa[late], adiabatic.p1_Pa[shut], 1e-6 * adiabatic.p1_Pa[shut]);
  const double charged = exchanging.p1_Pa[shut], relaxed = exchanging.p1_Pa[late];
  EXPECT_LT(relaxed, 0.97 * charged);  // the hot charge cooled
  // The charge (from 1 bar, k = 1.4) is at most k T_wall: p falls by at most 1/k.
  EXPECT_GT(relaxed / charged, 1.0 / params.gas.heat_capacity_ratio);
  const double k = params.gas.heat_capacity_ratio, wall = params.gas.temperature_K;
  const double volume =
      params.cylinder.dead_volume_1_m3 + params.cylinder.area_1_m2 * 0.5 * params.cylinder.stroke_m;
  const double tau = relaxed * volume / ((k - 1) * wall * h);
  ASSERT_LT(tau, 1.0);
  const std::size_t one_tau = shut + static_cast<std::size_t>(std::lround(tau / 0.01));
  const double elapsed = 0.01 * static_cast<double>(one_tau - shut);
  const double expected = relaxed + (charged - relaxed) * std::exp(-elapsed / tau);
  EXPECT_NEAR(exchanging.p1_Pa[one_tau], expected, 0.01 * (charged - relaxed))
      << "tau " << tau << " s";
}

}  // namespace
}  // namespace pneumaid
