// How a logged run is set up for simulation (logged_run.h): the command the
// valves saw before the log, and the state the run starts from.
#include "pneumaid/validate/logged_run.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "pneumaid/io/params_yaml.h"
#include "pneumaid/validate/validate.h"

namespace pneumaid {
namespace {

const std::string kUnit = std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig";

// The x RMSE [mm] of the bundled unit's truth on `unit`'s stroke-060, and
// its simulation's length against the log's.
double TruthsXRmseMm(const Unit& unit) {
  ValidationOptions options;
  options.experiment_ids = {"stroke-060"};
  const ValidationReport report = ValidateUnit(LoadParams(kUnit + "/truth.yaml"), unit, options);
  EXPECT_EQ(report.experiments.size(), 1u);
  if (report.experiments.size() != 1) return NAN;
  const ExperimentValidation& run = report.experiments[0];
  EXPECT_TRUE(run.simulation.ok()) << run.simulation.message;
  EXPECT_EQ(run.simulated.size(), run.measured.size());
  return run.channels.count("x") ? run.channels.at("x").rmse * 1e3 : NAN;
}

// 1 kHz, 0.1 s of a command u0 from the first sample; the rod at the
// retracted stop, chamber 1 at p1 and 2 at p2 throughout, or moving at
// `speed_m_per_s`.
Trajectory Log(double u0, double p1_Pa, double p2_Pa, double speed_m_per_s = 0) {
  Trajectory m;
  for (int i = 0; i < 100; ++i) {
    m.t_s.push_back(1e-3 * i);
    m.u_V.push_back(u0);
    m.x_m.push_back(-0.025 + speed_m_per_s * 1e-3 * i);
    m.p1_Pa.push_back(p1_Pa);
    m.p2_Pa.push_back(p2_Pa);
  }
  return m;
}

// A rig that starts logging as it gives the command: the rod rests and the
// chamber the command charges is still at the atmosphere. The valves were
// closed before (both chambers at the atmosphere) or drove the rod the
// other way (the other chamber at the supply); from the first sample on the
// command is the log's.
TEST(LoggedCommandTest, ALogThatStartsAtItsStepHadTheValvesElsewhereBefore) {
  const RigConstants rig;  // 5 bar supply, 1 bar atmosphere
  const CommandSignal closed = LoggedCommand(Log(0.4, 1e5, 1e5), rig);
  EXPECT_EQ(closed.initial_V, 0.0);
  ASSERT_FALSE(closed.time_s.empty());
  EXPECT_EQ(closed.time_s.front(), 0.0);
  EXPECT_EQ(closed.ValueAt(0.0), 0.4);
  EXPECT_EQ(closed.ValueAt(0.05), 0.4);

  const CommandSignal other_way = LoggedCommand(Log(0.4, 1e5, 5e5), rig);
  EXPECT_EQ(other_way.initial_V, -0.4);
  EXPECT_EQ(other_way.ValueAt(0.0), 0.4);
  // A negative command charges chamber 2.
  EXPECT_EQ(LoggedCommand(Log(-0.6, 5e5, 1e5), rig).initial_V, 0.6);
}

// The valves settled for the first command: a command held long (its
// chamber at the supply), a rod already moving, a closed valve, a log
// without pressures.
TEST(LoggedCommandTest, OtherwiseTheValvesAreSettledForTheFirstCommand) {
  const RigConstants rig;
  for (const Trajectory& m : {Log(0.4, 4.9e5, 1e5), Log(0.4, 2e5, 1.5e5, 0.05), Log(0.0, 1e5, 1e5),
                              Log(0.005, 1e5, 1e5)}) {
    const CommandSignal command = LoggedCommand(m, rig);
    EXPECT_EQ(command.initial_V, m.u_V.front());
    EXPECT_TRUE(command.time_s.empty());
  }
  Trajectory no_pressures = Log(0.4, 1e5, 1e5);
  no_pressures.p1_Pa.clear();
  no_pressures.p2_Pa.clear();
  EXPECT_EQ(LoggedCommand(no_pressures, rig).initial_V, 0.4);
  // A rig whose supply is lower: 3 bar abs reached is the supply.
  RigConstants low;
  low.supply_pressure_Pa = 3e5;
  EXPECT_EQ(LoggedCommand(Log(0.4, 2.95e5, 1e5), low).initial_V, 0.4);
}

// A log that starts at its step averages no filling chamber into its start.
TEST(LoggedInitialStateTest, AFillingChamberIsNotAveragedIntoTheStart) {
  Trajectory m = Log(0.4, 1e5, 1e5);
  for (std::size_t i = 0; i < m.size(); ++i) m.p1_Pa[i] = 1e5 + 2e6 * m.t_s[i];  // 2 kPa/ms
  int averaged = 0;
  const InitialState start = LoggedInitialState(m, 0.025, &averaged);
  EXPECT_LE(averaged, 3);
  EXPECT_LT(start.p1_Pa, 1.03e5);
  // At rest and still, up to 50 samples.
  LoggedInitialState(Log(0.0, 1e5, 1e5), 0.025, &averaged);
  EXPECT_EQ(averaged, 50);
}

// A chamber emptying 1 kPa/ms (a log cut while the valves vent it) and one
// filling by t^2 (a log that starts at its step, the valve's lag opening it)
// under 300 Pa of seeded noise: the start is read at the first sample, not
// half the averaged span late (the mean was 2 kPa off the emptying one).
TEST(LoggedInitialStateTest, ADriftingPressureIsReadAtTheFirstSample) {
  std::mt19937_64 rng(46);
  std::normal_distribution<double> noise(0.0, 300.0);
  double worst_emptying = 0, worst_filling = 0;
  for (int trial = 0; trial < 20; ++trial) {
    Trajectory m = Log(-0.4, 4.36e5, 4.99e5);
    Trajectory f = Log(0.4, 1e5, 1e5);
    for (std::size_t i = 0; i < m.size(); ++i) {
      m.p1_Pa[i] = 4.36e5 - 1e6 * m.t_s[i] + noise(rng);
      m.p2_Pa[i] += noise(rng);
      f.p1_Pa[i] = 1e5 + 2e8 * m.t_s[i] * m.t_s[i] + noise(rng);
      f.p2_Pa[i] += noise(rng);
    }
    int averaged = 0;
    const InitialState emptying = LoggedInitialState(m, 0.025, &averaged);
    EXPECT_GE(averaged, 1);
    EXPECT_LE(averaged, 6);  // the line's value at the first of six samples: about n / 4
    worst_emptying = std::max(worst_emptying, std::fabs(emptying.p1_Pa - 4.36e5));
    worst_filling = std::max(worst_filling, std::fabs(LoggedInitialState(f, 0.025).p1_Pa - 1e5));
  }
  EXPECT_LT(worst_emptying, 1000.0);
  EXPECT_LT(worst_filling, 1000.0);
}

// A spike on the first sample (8 kPa on p1) neither stops the averaging nor
// sets the start: the band is measured from the second sample.
TEST(LoggedInitialStateTest, ASpikeOnTheFirstSampleIsLeftOut) {
  Trajectory m = Log(0.0, 3e5, 2e5);
  m.p1_Pa[0] += 8e3;
  int averaged = 0;
  const InitialState start = LoggedInitialState(m, 0.025, &averaged);
  EXPECT_EQ(averaged, 50);
  EXPECT_DOUBLE_EQ(start.p1_Pa, 3e5);
  EXPECT_DOUBLE_EQ(start.p2_Pa, 2e5);
  // A chamber filling from the first sample by 5.5 kPa, then 4.9 kPa a
  // sample is no spike: its first sample is the start.
  Trajectory filling = Log(0.4, 1e5, 1e5);
  for (std::size_t i = 1; i < filling.size(); ++i)
    filling.p1_Pa[i] = filling.p1_Pa[i - 1] + (i == 1 ? 5.5e3 : 4.9e3);
  EXPECT_EQ(LoggedInitialState(filling, 0.025).p1_Pa, 1e5);
}

// The bundled unit's stroke log cut at its first step (the rows at u = 0
// before it dropped, as a rig that logs from the command writes it) is
// simulated by the truth as the whole log is: before, the valves started
// settled for the step's command, fully open.
TEST(LoggedCommandTest, AStrokeLogCutAtItsFirstStepValidatesAtTheTruth) {
  Unit unit = ReadUnit(kUnit);
  const double whole_mm = TruthsXRmseMm(unit);
  for (Experiment& e : unit.experiments) {
    if (e.entry.id != "stroke-060") continue;
    const std::vector<double>& u = e.columns.at("u");
    const auto first = static_cast<long>(
        std::find_if(u.begin(), u.end(), [](double v) { return v != 0.0; }) - u.begin());
    ASSERT_GT(first, 0) << "the log starts at its step already";
    ASSERT_LT(first, static_cast<long>(u.size()));
    for (auto& [name, column] : e.columns) column.erase(column.begin(), column.begin() + first);
    const double t0 = e.columns.at("t").front();
    for (double& t : e.columns.at("t")) t -= t0;
  }
  const double cut_mm = TruthsXRmseMm(unit);  // 4.95 mm before
  EXPECT_LT(cut_mm, 1.5 * whole_mm + 0.005) << "whole " << whole_mm << " mm";
}

// A run is cut after a logger's pause (an interval of 0.1 s or more) and
// where the command changed within a gap; not where a row or two dropped
// with the command the same on both sides.
TEST(PieceStartsTest, ARunIsCutWhereTheLoggerPausedOrTheCommandChangedInAGap) {
  Trajectory m = Log(0.4, 1e5, 1e5);
  EXPECT_EQ(PieceStarts(m), std::vector<std::size_t>{0});
  const auto drop = [&m](std::size_t from, std::size_t to) {  // rows [from, to)
    for (std::vector<double>* column : {&m.t_s, &m.u_V, &m.x_m, &m.p1_Pa, &m.p2_Pa})
      column->erase(column->begin() + static_cast<long>(from),
                    column->begin() + static_cast<long>(to));
  };
  drop(10, 15);  // five rows, a 6 ms gap with the command held: not a cut
  EXPECT_EQ(PieceStarts(m), std::vector<std::size_t>{0});
  Trajectory ramp = m;  // a command that is not held, across the same gap: not a cut
  for (std::size_t i = 0; i < ramp.size(); ++i) ramp.u_V[i] = 0.4 + 0.5 * ramp.t_s[i];
  EXPECT_EQ(PieceStarts(ramp), std::vector<std::size_t>{0});
  for (std::size_t i = 30; i < m.size(); ++i) m.u_V[i] = -0.4;
  drop(28, 32);  // 5 ms with the held command stepped inside: a cut
  EXPECT_EQ(PieceStarts(m), (std::vector<std::size_t>{0, 28}));
  for (std::size_t i = 40; i < m.size(); ++i) m.t_s[i] += 0.2;  // a pause, the command held
  EXPECT_EQ(PieceStarts(m), (std::vector<std::size_t>{0, 28, 40}));
  // The piece after the pause: the command before it the same, the valves
  // were settled for it (a rod at rest, the charged chamber below the
  // supply, would otherwise read as a log starting at its step).
  const RigConstants rig;
  const Trajectory after = Slice(m, 40, m.size());
  EXPECT_EQ(LoggedCommand(after, rig, m.u_V[39]).initial_V, -0.4);
  EXPECT_EQ(LoggedCommand(after, rig).initial_V, 0.0);
}

// The bundled unit's stroke log with 1.2 s of rows missing while the rod
// reversed (a logger paused): simulated piece by piece from the logged start
// after the pause, the truth follows it as it follows the whole log. Before,
// the command before the pause held across it drove the rod elsewhere.
TEST(PieceStartsTest, AStrokeLogWithALoggersPauseValidatesAtTheTruth) {
  Unit unit = ReadUnit(kUnit);
  const double whole_mm = TruthsXRmseMm(unit);
  for (Experiment& e : unit.experiments) {
    if (e.entry.id != "stroke-060") continue;
    const std::vector<double> t = e.columns.at("t");
    const auto from = std::lower_bound(t.begin(), t.end(), 1.8) - t.begin();
    const auto to = std::lower_bound(t.begin(), t.end(), 3.0) - t.begin();
    for (auto& [name, column] : e.columns) column.erase(column.begin() + from, column.begin() + to);
  }
  const double paused_mm = TruthsXRmseMm(unit);  // 16.7 mm before
  EXPECT_LT(paused_mm, 3 * whole_mm + 0.01) << "whole " << whole_mm << " mm";
}

}  // namespace
}  // namespace pneumaid
