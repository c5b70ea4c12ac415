#include "pneumaid/model/parameters.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "pneumaid/model/effects.h"
#include "pneumaid/model/parameter_table.h"

namespace pneumaid {
namespace {

bool HasProblemAt(const Parameters& p, const std::string& path) {
  for (const auto& problem : Validate(p)) {
    if (problem.path == path) return true;
  }
  return false;
}

TEST(ParametersTest, PaperDefaultsAreValid) { EXPECT_TRUE(Validate(Parameters{}).empty()); }

TEST(ParametersTest, NonPhysicalValuesAreNamedByPath) {
  Parameters p;
  p.cylinder.dead_volume_1_m3 = -1e-7;
  EXPECT_TRUE(HasProblemAt(p, "cylinder.dead_volume_1"));
  p = Parameters{};
  p.valve.increasing.u_sat_V = 1.2;
  EXPECT_TRUE(HasProblemAt(p, "valve.increasing.u_sat"));
  p.valve.increasing.u_sat_V = 0.0;
  EXPECT_TRUE(HasProblemAt(p, "valve.increasing.u_sat"));
  p = Parameters{};
  p.cylinder.area_2_m2 = p.cylinder.area_1_m2;
  EXPECT_TRUE(HasProblemAt(p, "cylinder.area_2"));
  p = Parameters{};
  p.supply.supply_pressure_Pa = 0.9e5;
  EXPECT_TRUE(HasProblemAt(p, "supply.supply_pressure"));
}

TEST(ParametersTest, EffectsAreCheckedAgainstTheCatalog) {
  Parameters p;
  p.effects["valve_lag"] = {{"tau", 0.01}};
  EXPECT_TRUE(Validate(p).empty());
  p.effects["valve_lag"] = {{"tau", -0.01}};
  EXPECT_TRUE(HasProblemAt(p, "effects.valve_lag.tau"));
  p.effects["valve_lag"] = {};
  EXPECT_TRUE(HasProblemAt(p, "effects.valve_lag.tau"));
  p.effects.clear();
  p.effects["warp_drive"] = {};
  EXPECT_TRUE(HasProblemAt(p, "effects.warp_drive"));
}

TEST(ParametersTest, CatalogHoldsTheSpecNames) {
  for (const char* name :
       {"valve_lag", "flow_sensor_lag", "pipeline_lag", "cross_leakage", "heat_transfer",
        "supply_droop", "friction_pressure", "valve_deadzone", "stick_creep"}) {
    EXPECT_NE(FindEffect(name), nullptr) << name;
  }
}

// SameValues: a set is the same as its copy, whatever its name, uncertainty
// and provenance; any one scalar of the table (every row, so a row added is
// tested too), effect value, mode or delta(L) entry changed sets it apart.
TEST(ParametersTest, SameValuesTellsEveryFieldApart) {
  Parameters base;
  base.effects["valve_lag"] = {{"tau", 0.005}};
  base.pipeline.delta_by_length = {{1.0, 8.0}};
  Parameters copy = base;
  copy.unit = "another";
  copy.uncertainty["friction.positive.Fs"] = 0.1;
  copy.provenance_yaml = "{tool: test}";
  EXPECT_TRUE(SameValues(base, copy));
  for (const auto& info : ScalarParameterTable()) {
    Parameters changed = base;
    double& value = info.ref(changed);
    value = value == 0 ? 1e-300 : std::nextafter(value, 2 * value);
    EXPECT_FALSE(SameValues(base, changed)) << info.path;
  }
  std::vector<Parameters> changed(6, base);
  changed[0].cylinder.orientation = Orientation::kHorizontal;
  changed[1].valve.branch = ValveBranchMode::kHysteresis;
  changed[2].pipeline.model = PipelineModel::kNone;
  changed[3].pipeline.delta_by_length[0].delta_per_s = 8.5;
  changed[4].pipeline.delta_by_length.push_back({2.0, 6.0});
  changed[5].effects["valve_lag"]["tau"] = 0.006;
  for (std::size_t k = 0; k < changed.size(); ++k) EXPECT_FALSE(SameValues(base, changed[k])) << k;
}

TEST(ParametersTest, PathsAddressScalarsAndEffects) {
  Parameters p;
  double value = 0;
  ASSERT_TRUE(GetParameter(p, "friction.negative.Fd", &value));
  EXPECT_EQ(value, 5.0);
  ASSERT_TRUE(SetParameter(&p, "friction.negative.Fd", 4.0));
  EXPECT_EQ(p.friction.negative.dynamic_force_N, 4.0);
  EXPECT_FALSE(GetParameter(p, "effects.valve_lag.tau", &value));
  p.effects["valve_lag"] = {{"tau", 0.01}};
  ASSERT_TRUE(SetParameter(&p, "effects.valve_lag.tau", 0.02));
  ASSERT_TRUE(GetParameter(p, "effects.valve_lag.tau", &value));
  EXPECT_EQ(value, 0.02);
  EXPECT_FALSE(GetParameter(p, "friction.sideways.Fs", &value));
  EXPECT_EQ(ScalarParameterTable().size(), 34u);
}

}  // namespace
}  // namespace pneumaid
