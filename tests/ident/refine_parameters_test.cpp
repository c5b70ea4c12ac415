// Refinement's weak prior (src/ident/refine_parameters.h, MakeStartPrior):
// centred on the start with its standard errors, or on another centre
// (RefineOptions::start_prior_centre) with that centre's errors; a free
// parameter the centre lacks falls back to the start, as one without an
// error. Closed forms. The bounds map keeps every value inside its bounds.
#include "../../src/ident/refine_parameters.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

namespace pneumaid::refine_internal {
namespace {

ParameterMap Map() {
  FitSpec spec;
  spec.parameters = {{"friction.positive.Fs", 0, 200, ParameterScale::kLinear},
                     {"friction.positive.vs", 1e-4, 1, ParameterScale::kLog},
                     {"effects.stick_creep.v", 1e-6, 1e-3, ParameterScale::kLog}};
  Parameters start;
  start.effects["stick_creep"]["v"] = 1e-4;
  return MakeParameterMap(start, spec);
}

// A set with the positive Fs [N] and vs [m/s], the creep speed v [m/s]
// when positive, and standard errors by path.
Parameters Set(double fs_N, double vs_m_per_s, double v_m_per_s,
               const std::map<std::string, double>& errors) {
  Parameters p;
  p.friction.positive.static_force_N = fs_N;
  p.friction.positive.stribeck_velocity_m_per_s = vs_m_per_s;
  if (v_m_per_s > 0) p.effects["stick_creep"]["v"] = v_m_per_s;
  for (const auto& [path, error] : errors) p.uncertainty[path] = error;
  return p;
}

TEST(StartPriorTest, CentredOnTheStartWithItsErrors) {
  const Parameters start =
      Set(10, 5e-3, 1e-4, {{"friction.positive.Fs", 0.5}, {"friction.positive.vs", 1e-3}});
  const StartPrior prior = MakeStartPrior(Map(), start, start, 3.0, 0.02);
  ASSERT_EQ(prior.w.size(), 3u);
  EXPECT_DOUBLE_EQ(prior.w[0], 10.0);
  EXPECT_DOUBLE_EQ(prior.sigma[0], 1.5);  // 3 standard errors
  EXPECT_DOUBLE_EQ(prior.w[1], std::log(5e-3));
  EXPECT_DOUBLE_EQ(prior.sigma[1], std::log1p(3 * 1e-3 / 5e-3));
  EXPECT_DOUBLE_EQ(prior.w[2], std::log(1e-4));
  EXPECT_DOUBLE_EQ(prior.sigma[2], std::log(3.0));  // no standard error
}

TEST(StartPriorTest, AnotherCentreGivesItsValuesAndErrorsAndTheStartWhatItLacks) {
  // The creep fit's refits: started from the paper fit (tight errors, the
  // creep speed), centred on the component fits (no creep speed).
  const Parameters paper_fit =
      Set(12, 8e-3, 3e-4, {{"friction.positive.Fs", 0.01}, {"effects.stick_creep.v", 1e-5}});
  const Parameters components = Set(10, 5e-3, 0, {{"friction.positive.Fs", 0.5}});
  const StartPrior prior = MakeStartPrior(Map(), components, paper_fit, 3.0, 0.02);
  EXPECT_DOUBLE_EQ(prior.w[0], 10.0);
  EXPECT_DOUBLE_EQ(prior.sigma[0], 1.5);
  // vs: the centre's value, which has no error there: a factor 3.
  EXPECT_DOUBLE_EQ(prior.w[1], std::log(5e-3));
  EXPECT_DOUBLE_EQ(prior.sigma[1], std::log(3.0));
  // v: the centre has none, so the start's value, as one without an error
  // (the start's own error is not the centre's).
  EXPECT_DOUBLE_EQ(prior.w[2], std::log(3e-4));
  EXPECT_DOUBLE_EQ(prior.sigma[2], std::log(3.0));
}

// A coordinate far out maps onto the bound itself, never past it: exp(ln
// 1e-3) is 1.0000000000000002e-3, and a set written at that value would be
// refused as the next refinement's start ("lies outside its bounds").
TEST(ParameterMapTest, ValuesStayWithinTheirBounds) {
  const ParameterMap map = Map();
  for (int j = 0; j < map.size(); ++j) {
    for (const double theta : {-60.0, -40.0, 0.0, 40.0, 60.0}) {
      const double value = map.ToValue(j, theta);
      EXPECT_GE(value, map.free[j].lower) << map.free[j].path << " at " << theta;
      EXPECT_LE(value, map.free[j].upper) << map.free[j].path << " at " << theta;
    }
  }
  EXPECT_EQ(map.ToValue(2, 60.0), 1e-3);
}

}  // namespace
}  // namespace pneumaid::refine_internal
