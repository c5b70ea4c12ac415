// ReadPositionZero and LoggedTrajectory (pneumaid/validate/logged_run.h): a
// position transducer zeroed 0.2 mm off shows in the rests at the end stops,
// and the runs are compared (validation, the refinement's fitted runs) with
// the rod where it was. The bundled unit
// (pneumaid synth, datasets/paper-rig) with its x shifted in memory.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "../synth/synth_test_util.h"
#include "pneumaid/ident/fit_spec.h"
#include "pneumaid/ident/refine.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/validate/logged_run.h"
#include "pneumaid/validate/validate.h"

namespace pneumaid {
namespace {

const std::string kUnit = std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig";

double ValidationXRmse(const Parameters& params, const Unit& unit) {
  double worst = 0;
  for (const auto& e : ValidateUnit(params, unit, ValidationOptions{}).experiments)
    worst = std::max(worst, e.channels.at("x").rmse);
  return worst;
}

TEST(PositionZeroTest, ALogAsZeroedIsReadAsLogged) {
  const PositionZero zero = ReadPositionZero(ReadUnit(kUnit));
  EXPECT_GE(zero.rests[0], 3);
  EXPECT_GE(zero.rests[1], 3);
  EXPECT_EQ(zero.offset_m, 0.0);
  for (const double from_stop : zero.from_stop_m) EXPECT_LT(std::fabs(from_stop), 2e-5);
  EXPECT_NE(zero.note.find("x read as logged"), std::string::npos) << zero.note;
}

TEST(PositionZeroTest, TheRestsAtTheStopsShowATransducersZero) {
  const Unit unit = ReadUnit(kUnit);
  const Unit shifted = testing::WithPositionOffset(unit, 2e-4);
  const PositionZero zero = ReadPositionZero(shifted);
  EXPECT_NEAR(zero.offset_m, 2e-4, 2e-5);
  EXPECT_NE(zero.note.find(": x read 0.2"), std::string::npos) << zero.note;
  EXPECT_NE(zero.note.find(" lower (a transducer's zero)"), std::string::npos) << zero.note;
  // The trajectories compared with simulations are the rod where it was.
  for (std::size_t k = 0; k < unit.experiments.size(); ++k) {
    const Trajectory as_zeroed = LoggedTrajectory(shifted.experiments[k], zero);
    const std::vector<double>& x = unit.experiments[k].column("x");
    for (std::size_t i = 0; i < x.size(); ++i)
      ASSERT_NEAR(as_zeroed.x_m[i], x[i] + 2e-4 - zero.offset_m, 1e-12);
  }
  // Validation at the truth as on the unit as zeroed (the rod pressed
  // against a stop 0.2 mm off the model's would cost 0.2 mm there).
  const Parameters truth = LoadParams(kUnit + "/truth.yaml");
  EXPECT_NEAR(ValidationXRmse(truth, shifted), ValidationXRmse(truth, unit), 2e-5);
  // The refinement's fitted runs too: the truth's verdict measure as on the
  // unit as zeroed (read as logged, the rod pressed 0.2 mm off the model's
  // stop would cost hundreds per residual).
  const FitSpec spec = LoadFitSpec(std::string(PNEUMAID_SOURCE_DIR) + "/configs/fit-default.yaml");
  const double as_zeroed = EvaluateFit(truth, unit, spec, RefineOptions{}).reduced_chi_square;
  EXPECT_NEAR(EvaluateFit(truth, shifted, spec, RefineOptions{}).reduced_chi_square, as_zeroed,
              0.1 * as_zeroed);
  // The other way, and below what the rests resolve: as logged.
  EXPECT_NEAR(ReadPositionZero(testing::WithPositionOffset(unit, -3e-4)).offset_m, -3e-4, 2e-5);
  EXPECT_EQ(ReadPositionZero(testing::WithPositionOffset(unit, 3e-5)).offset_m, 0.0);
}

}  // namespace
}  // namespace pneumaid
