// The valves' lag states at the start of a log cut mid-run. The conductance
// lag (pipeline.delta), valve_lag and the flow lags carry the command of the
// last 1/delta seconds, which such a log does not hold; LoggedCommand takes
// them as settled for the log's first command. Under a command that changes
// (a sine, a chirp) that is wrong by the lag itself: a 0.5 V, 0.5 Hz sine
// logged from 1.3 s on, at the truth, missed validation with x RMSE 1.45 mm
// (5 um from its start) and p2 RMSE 0.29 bar.
#pragma once

#include <map>
#include <string>

#include "pneumaid/model/parameters.h"
#include "pneumaid/sim/command.h"
#include "pneumaid/sim/simulate.h"
#include "pneumaid/trajectory.h"

namespace pneumaid {

// The leading span of a run the lag state is read from.
constexpr double kLagStartWindow_s = 0.1;
// The span a read start must fit better than the given one too.
constexpr double kLagStartConfirm_s = 0.3;
// The given start's window misfit (mean squared residual per noise sigma)
// above which a read start is tried, and the share of it a read start must
// stay under to be kept.
constexpr double kLagStartMisfit = 4.0;
constexpr double kLagStartKeepRatio = 0.5;

// The history a read start replays: a line of commands over the last
// kLagHistory_s before the log (in kLagHistorySteps held steps, within
// +-kLagHistoryCommand_V), the lags settled for its first value before.
constexpr double kLagHistory_s = 0.5;
constexpr int kLagHistorySteps = 50;
constexpr double kLagHistoryCommand_V = 1.0;
constexpr int kLagStartRounds = 3;  // of the search's coordinate descent
// What reads a start as unsettled: its samples before the command changes,
// at most kLagStartSettle_s of them, and a pressure slope over
// kLagStartDriftSigmas standard errors.
constexpr double kLagStartSettle_s = 0.02;
constexpr double kLagStartDriftSigmas = 5.0;
// A moving start's speed is refined within this (or its own size) either side.
constexpr double kLagStartSpeedSpan_m_per_s = 0.02;

struct LagStart {
  bool read = false;        // the lag states read off the window (else as LoggedCommand gives them)
  CommandSignal command;    // when read: the run's command with the history before it
  InitialState initial;     // when read: the start, lag_history_from_s at the history's start
  double misfit_given = 0;  // the window's misfit from LoggedCommand's start (0: not judged)
  double misfit_read = 0;   // the same from the read history (0: not tried)
  std::string note;         // one line for a report when read, else empty
};

// Reads the lag states of a run that starts unsettled: over its samples
// before the command changes (beyond the logger's kCommandNoise_V; at most
// kLagStartSettle_s, and at least two: a command that changes at once is a
// log that starts at its step, LoggedCommand's rule) the rod moves more than
// 0.1 mm, a pressure leaves the start's kStartPressureBand_Pa, or a pressure
// drifts by more than kLagStartDriftSigmas standard errors of its slope. The
// history before the run whose simulated window (x, p1, p2 against `noise`)
// fits the logged one best is read from two families: a line of commands
// through the log's start (a level on a 0.1 V grid with slope 0, and the
// logged command's own line; then level and slope in turn by golden section,
// kLagStartRounds rounds) and a step to the log's first command (from a
// level on a 0.1 V grid, 5 to 320 ms before the log; then each in turn).
// A moving start's speed is refined first with the logged command, then
// with the history. Kept when the given start's misfit is over
// kLagStartMisfit, the read one under kLagStartKeepRatio of the given
// start's with its speed refined, and the read start fits the first
// kLagStartConfirm_s better than the given one; else the speed alone when it
// halves the misfit and holds so. The lags replay the history exactly
// (InitialState::lag_history_from_s); the flow lags start settled.
// Whether a logged run starts unsettled by the rule above (before its
// command changes: the rod moves, a pressure leaves the band or drifts).
// `check` notes such a log; ReadLagStart reads only such runs.
bool StartsUnsettled(const Trajectory& measured);

LagStart ReadLagStart(const Parameters& params, const Trajectory& measured,
                      const CommandSignal& command, const InitialState& initial,
                      const std::map<std::string, double>& noise, const SimulationOptions& options);

}  // namespace pneumaid
