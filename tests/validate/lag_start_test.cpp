// The valves' lag states of a log cut mid-run (lag_start.h), on the bundled
// unit's validation profile (pneumaid synth, seed 1) at its truth.
#include "pneumaid/validate/lag_start.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "pneumaid/eval/metrics.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/validate/logged_run.h"
#include "pneumaid/validate/validate.h"

namespace pneumaid {
namespace {

const std::string kUnit = std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig";

// The bundled unit with profile-1 logged from `from_s` on (t from 0 there).
Unit CutProfile(double from_s) {
  Unit unit = ReadUnit(kUnit);
  for (Experiment& e : unit.experiments) {
    if (e.entry.id != "profile-1") continue;
    const std::vector<double>& t = e.columns.at("t");
    const auto first = std::lower_bound(t.begin(), t.end(), from_s) - t.begin();
    for (auto& [name, column] : e.columns) column.erase(column.begin(), column.begin() + first);
    const double t0 = e.columns.at("t").front();
    for (double& ti : e.columns.at("t")) ti -= t0;
  }
  return unit;
}

const Experiment& Profile(const Unit& unit) {
  for (const Experiment& e : unit.experiments) {
    if (e.entry.id == "profile-1") return e;
  }
  throw std::runtime_error("no profile-1");
}

ExperimentValidation ValidateProfile(const Unit& unit, const Parameters& params) {
  ValidationOptions options;
  options.experiment_ids = {"profile-1"};
  const ValidationReport report = ValidateUnit(params, unit, options);
  EXPECT_EQ(report.experiments.size(), 1u);
  return report.experiments.at(0);
}

std::map<std::string, double> Noise() { return {{"x", 5e-6}, {"p1", 300.0}, {"p2", 300.0}}; }

// Cut inside the profile's ramp (the command rising through -0.3 V, the rod
// retracting at 40 mm/s): the truth follows the cut log as it follows the
// whole one. Started settled for the first command, as before, it does not.
TEST(LagStartTest, AProfileCutInItsRampValidatesAtTheTruth) {
  const Parameters truth = LoadParams(kUnit + "/truth.yaml");
  const double whole_mm = ValidateProfile(ReadUnit(kUnit), truth).channels.at("x").rmse * 1e3;
  const Unit cut = CutProfile(3.3);
  const ExperimentValidation run = ValidateProfile(cut, truth);
  ASSERT_TRUE(run.simulation.ok()) << run.simulation.message;
  EXPECT_EQ(run.notes.size(), 1u);
  for (const std::string& note : run.notes)
    EXPECT_NE(note.find("read off its first 100 ms"), std::string::npos) << note;
  const double cut_mm = run.channels.at("x").rmse * 1e3;
  EXPECT_LT(cut_mm, 2 * whole_mm + 0.005) << "whole " << whole_mm << " mm";

  // The start as LoggedCommand gives it, simulated directly.
  const Trajectory m = Profile(cut).AsTrajectory();
  const InitialState initial = LoggedInitialState(m, 0.5 * truth.cylinder.stroke_m);
  const Parameters conditioned = WithRigConditions(truth, cut);
  Trajectory given;
  ASSERT_TRUE(Simulate(conditioned, LoggedCommand(m, cut.manifest.rig), initial, m.t_s,
                       SimulationOptions{}, &given)
                  .ok());
  const double given_mm = CompareChannel(m.x_m, given.x_m, std::nullopt).rmse * 1e3;
  EXPECT_GT(given_mm, 3 * cut_mm) << "the cut log's lag state does not matter here";
}

// A log that starts settled (at rest, the command 0), or under a held
// command, or without a position noise to judge by: nothing is read.
TEST(LagStartTest, SettledStartsAndHeldCommandsAreLeftAsLogged) {
  const Parameters truth = LoadParams(kUnit + "/truth.yaml");
  const SimulationOptions options;
  for (double from_s : {0.0, 1.0}) {  // the log's start; inside the -0.3 V held from 0.75 s
    const Unit unit = CutProfile(from_s);
    const Trajectory m = Profile(unit).AsTrajectory();
    const CommandSignal command = LoggedCommand(m, unit.manifest.rig);
    const LagStart lag =
        ReadLagStart(WithRigConditions(truth, unit), m, command,
                     LoggedInitialState(m, 0.5 * truth.cylinder.stroke_m), Noise(), options);
    EXPECT_FALSE(lag.read) << from_s;
    EXPECT_EQ(lag.misfit_given, 0.0) << from_s << ": judged";
    EXPECT_TRUE(lag.note.empty());
  }
  const Unit cut = CutProfile(3.3);
  const Trajectory m = Profile(cut).AsTrajectory();
  const InitialState initial = LoggedInitialState(m, 0.5 * truth.cylinder.stroke_m);
  const CommandSignal command = LoggedCommand(m, cut.manifest.rig);
  const Parameters conditioned = WithRigConditions(truth, cut);
  const LagStart read = ReadLagStart(conditioned, m, command, initial, Noise(), options);
  EXPECT_TRUE(read.read);
  EXPECT_LT(read.misfit_read, kLagStartKeepRatio * read.misfit_given);
  std::map<std::string, double> no_x = Noise();
  no_x.erase("x");
  EXPECT_FALSE(ReadLagStart(conditioned, m, command, initial, no_x, options).read);
}

}  // namespace
}  // namespace pneumaid
