#include "pneumaid/model/actuator.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace pneumaid {
namespace {

using Jet = ceres::Jet<double, kMaxStates>;

Parameters WithAllSimulatedEffects() {
  Parameters p;
  p.effects["valve_lag"] = {{"tau", 0.005}};
  p.effects["flow_sensor_lag"] = {{"tau", 0.03}};
  p.effects["cross_leakage"] = {{"c", 1e-11}};
  p.effects["friction_pressure"] = {{"kp", 1e-6}};
  p.effects["valve_deadzone"] = {{"u0", 0.05}};
  p.effects["heat_transfer"] = {{"h", 0.3}};
  p.effects["supply_droop"] = {{"r", 3e7}};
  p.effects["stick_creep"] = {{"v", 2e-4}};
  return p;
}

TEST(ActuatorTest, LayoutCountsTheStatesOfEachOption) {
  Parameters p;
  // x, v, two chambers; a lag on the valves needs one state per valve pair.
  EXPECT_EQ(ActuatorLayout::For(p).size, 6);
  p.pipeline.model = PipelineModel::kFlowLag;
  EXPECT_EQ(ActuatorLayout::For(p).size, 6);
  p.pipeline.model = PipelineModel::kNone;
  EXPECT_EQ(ActuatorLayout::For(p).size, 4);
  p.effects["pipeline_lag"] = {{"delta", 8.0}};
  EXPECT_EQ(ActuatorLayout::For(p).size, 6);
  // valve_lag 2, the tube 2, flow_sensor_lag 2, heat_transfer 2 (two gas
  // temperatures); supply_droop and stick_creep have no state.
  EXPECT_EQ(ActuatorLayout::For(WithAllSimulatedEffects()).size, 12);
}

// stick_creep sets the friction saturation's width (the regularisation's
// otherwise): at half of it a rod's friction is 1.5 / 2 - 0.5 / 8 of Fs.
TEST(ActuatorTest, StickCreepSetsTheWidthOfTheFrictionSaturation) {
  Parameters p;
  const ModelRegularization reg;
  EXPECT_EQ(MakeActuatorCoefficients<double>(p, reg).stick_velocity_m_per_s,
            reg.stick_velocity_m_per_s);
  p.effects["stick_creep"] = {{"v", 2e-4}};
  const auto c = MakeActuatorCoefficients<double>(p, reg);
  EXPECT_EQ(c.stick_velocity_m_per_s, 2e-4);
  const double fs = p.friction.positive.static_force_N;
  EXPECT_NEAR(
      FrictionForce(1e-4, c.friction_positive, c.friction_negative, c.stick_velocity_m_per_s),
      fs * (0.75 - 0.0625), 1e-3 * fs);
}

// The Jacobian CVODE uses (forward-mode autodiff) against central differences
// of the double right-hand side, at random states away from kinks.
TEST(ActuatorTest, AutodiffJacobianMatchesCentralDifferences) {
  for (PipelineModel pipeline :
       {PipelineModel::kConductanceLag, PipelineModel::kFlowLag, PipelineModel::kNone}) {
    Parameters params = WithAllSimulatedEffects();
    params.pipeline.model = pipeline;
    const ModelRegularization reg;
    const ActuatorLayout layout = ActuatorLayout::For(params);
    const auto cd = MakeActuatorCoefficients<double>(params, reg);
    const auto cj = MakeActuatorCoefficients<Jet>(params, reg);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int trial = 0; trial < 20; ++trial) {
      ValveCommand command;
      command.opening = OpeningsForCommand(trial % 2 ? 0.5 : -0.3);
      std::vector<double> y(layout.size);
      y[kPosition] = -0.02 + 0.04 * unit(rng);
      y[kVelocity] = (unit(rng) - 0.5) * 0.4;  // well outside the stick band
      SetChamberPressures(cd, 1.2e5 + 3e5 * unit(rng), 1.2e5 + 3e5 * unit(rng), y.data());
      for (int i = 4; i < layout.size; ++i) y[i] = 3e-5 * unit(rng);
      for (int i = 0; i < 2; ++i) y[layout.temperature_begin + i] = 250.0 + 80.0 * unit(rng);
      if (layout.valve_lag) {
        for (int i = 0; i < kValvePairCount; ++i) {
          y[layout.opening_begin + i] = 0.2 + 0.6 * unit(rng);
        }
      }
      Jet yj[kMaxStates], fj[kMaxStates];
      for (int i = 0; i < layout.size; ++i) yj[i] = Jet(y[i], i);
      ActuatorDerivatives<Jet>(layout, cj, command, MotionMode::kRegularized, yj, fj, nullptr);
      for (int col = 0; col < layout.size; ++col) {
        const double h = 1e-6 * std::max(std::fabs(y[col]), 1e-6);
        auto plus = y, minus = y;
        plus[col] += h;
        minus[col] -= h;
        std::vector<double> fp(layout.size), fm(layout.size);
        ActuatorDerivatives<double>(layout, cd, command, MotionMode::kRegularized, plus.data(),
                                    fp.data(), nullptr);
        ActuatorDerivatives<double>(layout, cd, command, MotionMode::kRegularized, minus.data(),
                                    fm.data(), nullptr);
        for (int row = 0; row < layout.size; ++row) {
          const double fd = (fp[row] - fm[row]) / (2 * h);
          const double scale = std::fabs(fd) + std::fabs(fj[row].v[col]);
          EXPECT_NEAR(fj[row].v[col], fd, 1e-5 * scale + 1e-9)
              << ToString(pipeline) << " trial " << trial << " d f" << row << " / d y" << col;
        }
      }
    }
  }
}

TEST(ActuatorTest, AtRestWithBalancedForcesNothingChanges) {
  Parameters params;
  params.cylinder.orientation = Orientation::kHorizontal;
  params.pipeline.model = PipelineModel::kNone;
  const ActuatorLayout layout = ActuatorLayout::For(params);
  const auto c = MakeActuatorCoefficients<double>(params, ModelRegularization{});
  // p1 A1 = p2 A2 + p_atm A_h balances the rod exactly; valves closed.
  const double p2 = 3e5;
  const double p1 = (p2 * 1.73e-4 + 1e5 * (2.01e-4 - 1.73e-4)) / 2.01e-4;
  double y[4] = {0.0, 0.0}, f[4];
  SetChamberPressures(c, p1, p2, y);
  ActuatorDerivatives<double>(layout, c, ValveCommand{}, MotionMode::kRegularized, y, f, nullptr);
  for (double rate : f) EXPECT_NEAR(rate, 0.0, 1e-9);
}

TEST(ActuatorTest, EquilibriumLagStatesHaveZeroRates) {
  Parameters params = WithAllSimulatedEffects();
  const ActuatorLayout layout = ActuatorLayout::For(params);
  const auto c = MakeActuatorCoefficients<double>(params, ModelRegularization{});
  ValveCommand command;
  command.opening = OpeningsForCommand(0.6);
  std::vector<double> y(layout.size, 0.0), f(layout.size);
  SetChamberPressures(c, 2e5, 3e5, y.data());
  SetLagStatesToEquilibrium(layout, c, command, y.data());
  ActuatorDerivatives<double>(layout, c, command, MotionMode::kRegularized, y.data(), f.data(),
                              nullptr);
  for (int i = 4; i < layout.size; ++i) {
    if (i >= layout.temperature_begin && i < layout.temperature_begin + 2) continue;  // not a lag
    EXPECT_NEAR(f[i], 0.0, 1e-12) << "state " << i;
  }
}

}  // namespace
}  // namespace pneumaid
