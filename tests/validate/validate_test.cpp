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

// A log written from the retracted stop, under a manifest whose stroke the
// set's differs from (within the 1 % allowed): its x is placed from the
// set's retracted stop. Where the rod rests at both stops, the position zero
// read off them made up for it already (the comparison is the same with and
// without); where it rests at one, the zero cannot, and x was half the
// difference off.
TEST(ValidateTest, ALogFromTheRetractedStopIsComparedOnTheSetsStroke) {
  const Unit unit = ReadUnit(kUnit);
  ASSERT_EQ(unit.manifest.rig.position_origin, PositionOrigin::kRetracted);
  const Parameters truth = LoadParams(kUnit + "/truth.yaml");
  const double rmse = ValidateUnit(truth, unit, {}).experiments[0].channels.at("x").rmse;
  EXPECT_FALSE(OnTheSetsStroke(unit, truth).has_value());  // the strokes agree
  Unit longer = unit;  // as read with the manifest's stroke 0.45 mm longer
  longer.manifest.rig.stroke_m = truth.cylinder.stroke_m + 0.45e-3;
  for (Experiment& e : longer.experiments) {
    for (auto& [name, values] : e.columns) {
      if (name != "x") continue;
      for (double& x : values) x -= 0.225e-3;
    }
  }
  EXPECT_NEAR(ReadPositionZero(longer).offset_m, -0.225e-3, 1e-6);  // the rests show it
  const std::optional<Unit> moved = OnTheSetsStroke(longer, truth);
  ASSERT_TRUE(moved.has_value());
  EXPECT_EQ(moved->manifest.rig.stroke_m, truth.cylinder.stroke_m);
  const PositionZero zero = ReadPositionZero(*moved);  // the rests are on the set's stops
  EXPECT_EQ(zero.offset_m, 0.0) << zero.note;
  EXPECT_NEAR(zero.from_stop_m[0], 0.0, 20e-6) << zero.note;
  EXPECT_NEAR(zero.from_stop_m[1], 0.0, 20e-6) << zero.note;
  const double compared = ValidateUnit(truth, longer, {}).experiments[0].channels.at("x").rmse;
  EXPECT_NEAR(compared, rmse, 1e-6) << rmse;
  EXPECT_LT(rmse, 0.05e-3);
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

// Every id is looked up before any chosen run's kind is judged: a tube test
// named first and an unknown id after it says the id is unknown; a tube
// test alone, that it cannot be simulated.
TEST(ValidateTest, AnUnknownIdIsNamedBeforeAnotherRunsKind) {
  const Unit unit = ReadUnit(kUnit);
  ValidationOptions options;
  const auto message = [&]() -> std::string {
    try {
      ValidateUnit(Parameters{}, unit, options);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  options.experiment_ids = {"pipe-038", "nope"};
  EXPECT_NE(message().find("no experiment 'nope'"), std::string::npos) << message();
  options.experiment_ids = {"pipe-038"};
  EXPECT_NE(message().find("'pipe-038' is a pipeline log"), std::string::npos) << message();
}

}  // namespace
}  // namespace pneumaid
