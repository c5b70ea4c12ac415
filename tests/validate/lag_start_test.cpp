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

// The x RMSE [mm] of profile-1 simulated from the start LoggedCommand and
// LoggedInitialState give, without a read lag start.
double GivenXRmseMm(const Unit& unit, const Parameters& params) {
  const Trajectory m = Profile(unit).AsTrajectory();
  const InitialState initial = LoggedInitialState(m, 0.5 * params.cylinder.stroke_m);
  Trajectory given;
  const SimulationSummary summary =
      Simulate(WithRigConditions(params, unit), LoggedCommand(m, unit.manifest.rig), initial, m.t_s,
               SimulationOptions{}, &given);
  EXPECT_TRUE(summary.ok()) << summary.message;
  return CompareChannel(m.x_m, given.x_m, std::nullopt).rmse * 1e3;
}

std::map<std::string, double> Noise() { return {{"x", 5e-6}, {"p1", 300.0}, {"p2", 300.0}}; }

// The profile logged from `from_s` on, validated at the truth: a lag start
// is read (its note), and the truth follows the cut log as it follows the
// whole one, at least 3 times closer than from the start LoggedCommand
// gives (settled for the first command).
void ExpectTheCutValidatesAtTheTruth(double from_s) {
  const Parameters truth = LoadParams(kUnit + "/truth.yaml");
  const double whole_mm = ValidateProfile(ReadUnit(kUnit), truth).channels.at("x").rmse * 1e3;
  const Unit cut = CutProfile(from_s);
  const ExperimentValidation run = ValidateProfile(cut, truth);
  ASSERT_TRUE(run.simulation.ok()) << run.simulation.message;
  EXPECT_EQ(run.notes.size(), 1u);
  for (const std::string& note : run.notes)
    EXPECT_NE(note.find("read off its first 100 ms"), std::string::npos) << note;
  const double cut_mm = run.channels.at("x").rmse * 1e3;
  EXPECT_LT(cut_mm, 2 * whole_mm + 0.005) << "whole " << whole_mm << " mm";
  EXPECT_GT(GivenXRmseMm(cut, truth), 3 * cut_mm) << "the cut log's lag state does not matter";
}

// Cut inside the profile's ramp (the command rising through 0.09 V, chamber
// 1 filling 2 kPa/ms): x RMSE 1.03 mm settled, 0.015 mm read.
TEST(LagStartTest, AProfileCutInItsRampValidatesAtTheTruth) {
  ExpectTheCutValidatesAtTheTruth(3.3);
}

// Cut inside the -0.3 V the profile holds from 0.75 s (the rod sliding, the
// command stepped 0.25 s before): 0.25 mm settled, 0.014 mm read as after a
// step.
TEST(LagStartTest, AProfileCutInsideAHeldCommandValidatesAtTheTruth) {
  ExpectTheCutValidatesAtTheTruth(1.0);
}

// A log that starts settled (at rest, the command 0), one whose command
// steps at its second sample (it starts at its step: LoggedCommand's rule),
// or one without a position noise to judge by: nothing is read.
TEST(LagStartTest, SettledStartsAndStepStartsAreLeftAsLogged) {
  const Parameters truth = LoadParams(kUnit + "/truth.yaml");
  const SimulationOptions options;
  const Unit unit = ReadUnit(kUnit);
  const Trajectory whole = Profile(unit).AsTrajectory();
  const auto first = std::find_if(whole.u_V.begin(), whole.u_V.end(),
                                  [](double u) { return std::fabs(u) > kCommandNoise_V; });
  ASSERT_NE(first, whole.u_V.end());
  const std::size_t step = static_cast<std::size_t>(first - whole.u_V.begin());
  ASSERT_GT(step, 1u);
  const Trajectory at_step = Slice(whole, step - 1, whole.size());  // one sample before it
  for (const Trajectory* m : {&whole, &at_step}) {
    const CommandSignal command = LoggedCommand(*m, unit.manifest.rig);
    const LagStart lag =
        ReadLagStart(WithRigConditions(truth, unit), *m, command,
                     LoggedInitialState(*m, 0.5 * truth.cylinder.stroke_m), Noise(), options);
    EXPECT_FALSE(lag.read) << m->size();
    EXPECT_EQ(lag.misfit_given, 0.0) << m->size() << ": judged";
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

// The JSON report carries the read note with its run (`notes`); a run
// whose log starts settled has none.
TEST(LagStartTest, TheJsonReportCarriesTheNote) {
  const Parameters truth = LoadParams(kUnit + "/truth.yaml");
  ValidationOptions options;
  options.experiment_ids = {"profile-1"};
  const std::string cut = ReportToJson(ValidateUnit(truth, CutProfile(1.0), options));
  EXPECT_NE(cut.find("\"notes\": [\""), std::string::npos) << cut;
  EXPECT_NE(cut.find("read off its first 100 ms"), std::string::npos) << cut;
  const std::string whole = ReportToJson(ValidateUnit(truth, ReadUnit(kUnit), options));
  EXPECT_EQ(whole.find("\"notes\""), std::string::npos) << whole;
}

}  // namespace
}  // namespace pneumaid
