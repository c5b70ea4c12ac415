// Validation on synthetic units with a known truth.
#include "pneumaid/validate/validate.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"

namespace pneumaid {
namespace {

const std::string kUnit = std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig";

TEST(ValidateTest, TheTruthValidatesOnItsOwnSyntheticUnit) {
  const Unit unit = ReadUnit(kUnit);
  const Parameters truth = LoadParams(kUnit + "/truth.yaml");
  const ValidationReport report = ValidateUnit(truth, unit, ValidationOptions{});
  ASSERT_EQ(report.experiments.size(), 2u);  // step-1 and profile-1
  EXPECT_FALSE(report.numerical_failure());
  EXPECT_TRUE(report.thresholds_met()) << report.BriefReport();
  for (const auto& e : report.experiments) {
    EXPECT_GT(*e.channels.at("x").nrmse_fit_percent, 99.0) << e.id;
    EXPECT_LT(e.channels.at("p1").rmse, 1000.0) << e.id;  // ~3x the 300 Pa sensor noise
    EXPECT_EQ(e.simulated.size(), e.measured.size());
  }
  // Flows are compared through the declared 30 ms meter lag: without it the
  // fit would be visibly worse.
  EXPECT_GT(*report.experiments[0].channels.at("q1").nrmse_fit_percent, 98.0);
}

TEST(ValidateTest, AWrongParameterSetMissesTheThresholds) {
  const Unit unit = ReadUnit(kUnit);
  Parameters wrong = LoadParams(kUnit + "/truth.yaml");
  wrong.valve.increasing.q_max_kg_per_s *= 0.5;
  wrong.valve.decreasing.q_max_kg_per_s *= 0.5;
  const ValidationReport report = ValidateUnit(wrong, unit, ValidationOptions{});
  EXPECT_FALSE(report.thresholds_met()) << report.BriefReport();
  EXPECT_FALSE(report.experiments[0].missed.empty());
}

// A run too short to evaluate (its first samples only: the rod has not moved
// yet) misses the fit threshold it cannot evaluate; it passed vacuously.
TEST(ValidateTest, AFitThatCannotBeEvaluatedIsNotMet) {
  Unit unit = ReadUnit(kUnit);
  const Parameters truth = LoadParams(kUnit + "/truth.yaml");
  for (Experiment& e : unit.experiments) {
    for (auto& [name, column] : e.columns) column.resize(std::min<std::size_t>(column.size(), 3));
  }
  const ValidationReport report = ValidateUnit(truth, unit, ValidationOptions{});
  EXPECT_FALSE(report.thresholds_met()) << report.BriefReport();
  ASSERT_FALSE(report.experiments.empty());
  ASSERT_FALSE(report.experiments[0].missed.empty());
  EXPECT_NE(report.experiments[0].missed[0].find("x fit n/a"), std::string::npos)
      << report.experiments[0].missed[0];
}

TEST(ValidateTest, ConditionsComeFromTheManifestAndGeometryMustAgree) {
  Unit unit = ReadUnit(kUnit);
  Parameters params;  // the paper's
  unit.manifest.rig.supply_pressure_Pa = 6e5;
  unit.manifest.rig.orientation = Orientation::kHorizontal;
  const Parameters conditioned = WithRigConditions(params, unit);
  EXPECT_EQ(conditioned.supply.supply_pressure_Pa, 6e5);
  EXPECT_EQ(conditioned.cylinder.orientation, Orientation::kHorizontal);
  EXPECT_EQ(conditioned.cylinder.area_1_m2, params.cylinder.area_1_m2);  // geometry: the set's
  unit.manifest.rig.stroke_m = 0.06;
  EXPECT_THROW(WithRigConditions(params, unit), InputError);
  unit.manifest.defaults_used.push_back("rig.cylinder.stroke");  // not stated: not checked
  EXPECT_NO_THROW(WithRigConditions(params, unit));
}

TEST(ValidateTest, UnknownExperimentAndReportFormats) {
  const Unit unit = ReadUnit(kUnit);
  ValidationOptions options;
  options.experiment_ids = {"nope"};
  EXPECT_THROW(ValidateUnit(Parameters{}, unit, options), InputError);
  options.experiment_ids = {"step-1"};
  const ValidationReport report = ValidateUnit(Parameters{}, unit, options);
  ASSERT_EQ(report.experiments.size(), 1u);
  const std::string json = ReportToJson(report);
  EXPECT_NE(json.find("\"format\": \"pneumaid-report/1\""), std::string::npos);
  EXPECT_NE(json.find("\"nrmse_fit_percent\""), std::string::npos);
  const std::string csv = ComparisonToCsv(report.experiments[0]);
  EXPECT_EQ(csv.find("t,u,x,x_sim,p1,p1_sim,p2,p2_sim,q1 [kg/s],q1_sim [kg/s]"),
            csv.find('\n') + 1);
}

}  // namespace
}  // namespace pneumaid
