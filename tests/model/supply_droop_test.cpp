// supply_droop (actuator.h DroopedSupplyPressure): the supply pressure at the
// valves solves p_s = p_supply - r q_s(p_s), with implicit derivatives.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "../sim/sim_test_util.h"
#include "pneumaid/model/actuator.h"
#include "pneumaid/sim/command.h"
#include "pneumaid/sim/simulate.h"

namespace pneumaid {
namespace {

using Jet = ceres::Jet<double, 3>;  // d/d p1, d/d p2, d/d r

Parameters WithDroop(double r) {
  Parameters p;
  p.effects["supply_droop"] = {{"r", r}};
  return p;
}

std::array<double, kValveCount> Gains(const ActuatorCoefficients<double>& c, double command_V) {
  ValveCommand command;
  command.opening = OpeningsForCommand(command_V);
  ActuatorLayout layout;
  return ValveGains(c, command, ValveOpeningsInUse(layout, command, static_cast<double*>(nullptr)));
}

double Drawn(const ActuatorCoefficients<double>& c, const std::array<double, kValveCount>& gain,
             double supply, double p1, double p2) {
  return ValveFlow(c, gain, kSupplyToChamber1, supply, p1) +
         ValveFlow(c, gain, kSupplyToChamber2, supply, p2);
}

TEST(SupplyDroopTest, TheSupplyPressureSolvesItsEquation) {
  const double r = 3e8;  // Pa s/kg: 0.3 bar at 1 g/s
  const auto c = MakeActuatorCoefficients<double>(WithDroop(r), ModelRegularization{});
  for (double command_V : {0.3, 0.7, 1.0, -0.8}) {
    const auto gain = Gains(c, command_V);
    const double p1 = 1.5e5, p2 = 4e5;
    const double supply = DroopedSupplyPressure(c, gain, p1, p2);
    const double drawn = Drawn(c, gain, supply, p1, p2);
    EXPECT_GT(drawn, 0.0) << command_V;
    EXPECT_LT(supply, c.supply_pressure_Pa) << command_V;
    EXPECT_NEAR(supply, c.supply_pressure_Pa - r * drawn, 1e-9 * c.supply_pressure_Pa) << command_V;
  }
  // Across the choking ratio and every chamber pressure, 500 Pa apart: the
  // root is found everywhere (a solver that bisects away from a converged
  // root missed it by up to 7 Pa here).
  const auto gain = Gains(c, 0.4);
  for (double p1 = 1.2e5; p1 < 4.5e5; p1 += 500) {
    const double supply = DroopedSupplyPressure(c, gain, p1, 1.6e5);
    EXPECT_NEAR(supply, c.supply_pressure_Pa - r * Drawn(c, gain, supply, p1, 1.6e5),
                1e-9 * c.supply_pressure_Pa)
        << p1;
  }
  // A chamber above the supply (gas pushed back into the line): the root
  // lies above p_supply, and is found there too.
  const double above = 1.4 * c.supply_pressure_Pa;
  const double back = DroopedSupplyPressure(c, Gains(c, 0.7), above, 1.6e5);
  EXPECT_GT(back, c.supply_pressure_Pa);
  EXPECT_NEAR(back, c.supply_pressure_Pa - r * Drawn(c, Gains(c, 0.7), back, above, 1.6e5),
              1e-9 * c.supply_pressure_Pa);
  // Valves shut: nothing drawn, no droop.
  EXPECT_DOUBLE_EQ(DroopedSupplyPressure(c, Gains(c, 0.0), 1.5e5, 4e5), c.supply_pressure_Pa);
}

// The implicit derivatives -f_theta / f' (one Newton step in Jets from the
// root) against central differences of the solved pressure.
TEST(SupplyDroopTest, ImplicitDerivativesMatchCentralDifferences) {
  const double r = 3e8, p1 = 1.5e5, p2 = 4e5;
  const auto solve = [](double r_value, double p1_value, double p2_value) {
    const auto c = MakeActuatorCoefficients<double>(WithDroop(r_value), ModelRegularization{});
    return DroopedSupplyPressure(c, Gains(c, 0.7), p1_value, p2_value);
  };
  auto cj = MakeActuatorCoefficients<Jet>(WithDroop(r), ModelRegularization{});
  cj.supply_resistance_Pa_s_per_kg = Jet(r, 2);
  const auto cd = MakeActuatorCoefficients<double>(WithDroop(r), ModelRegularization{});
  const auto gain_d = Gains(cd, 0.7);
  std::array<Jet, kValveCount> gain;
  for (int i = 0; i < kValveCount; ++i) gain[i] = Jet(gain_d[i]);
  const Jet supply = DroopedSupplyPressure(cj, gain, Jet(p1, 0), Jet(p2, 1));
  EXPECT_NEAR(supply.a, solve(r, p1, p2), 1e-6);
  const double dp1 = (solve(r, p1 + 10, p2) - solve(r, p1 - 10, p2)) / 20;
  const double dp2 = (solve(r, p1, p2 + 10) - solve(r, p1, p2 - 10)) / 20;
  const double dr = (solve(r * 1.001, p1, p2) - solve(r * 0.999, p1, p2)) / (0.002 * r);
  EXPECT_NEAR(supply.v[0], dp1, 1e-5 * std::fabs(dp1) + 1e-9);
  EXPECT_NEAR(supply.v[1], dp2, 1e-5 * std::fabs(dp2) + 1e-9);
  EXPECT_NEAR(supply.v[2], dr, 1e-5 * std::fabs(dr));
  EXPECT_LT(dr, 0.0);  // more resistance, more droop
}

// A full-stroke step: the droop slows the charge while flow is drawn, and
// vanishes once the chamber is full (p1 -> p_supply at rest).
TEST(SupplyDroopTest, AStepChargesSlowerButReachesTheSupply) {
  const auto run = [](double r) {
    const Parameters p = WithDroop(r);
    InitialState initial;
    initial.position_m = -0.5 * p.cylinder.stroke_m;
    initial.p1_Pa = initial.p2_Pa = p.supply.atmospheric_pressure_Pa;
    return testing::MustSimulate(p, StepCommand({{0.0, 1.0}}), initial, UniformTimes(0, 2.0, 100));
  };
  const Trajectory stiff = run(0.0), drooping = run(3e8);
  const Parameters p;
  double lead = 0;  // how far ahead the stiff supply's rod is, summed over the stroke
  for (std::size_t i = 0; i < 100; ++i) lead += stiff.x_m[i] - drooping.x_m[i];
  EXPECT_GT(lead, 0.01);  // 0.1 mm on average over the first second
  EXPECT_NEAR(drooping.p1_Pa.back(), p.supply.supply_pressure_Pa,
              1e-3 * p.supply.supply_pressure_Pa);
}

}  // namespace
}  // namespace pneumaid
