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

struct LagStart {
  bool read = false;        // the lag states read off the window (else as LoggedCommand gives them)
  CommandSignal command;    // when read: the run's command with the history before it
  InitialState initial;     // when read: the start, lag_history_from_s at the history's start
  double misfit_given = 0;  // the window's misfit from LoggedCommand's start (0: not judged)
  double misfit_read = 0;   // the same from the read history (0: not tried)
  std::string note;         // one line for a report when read, else empty
};

// Reads the lag states of a run that starts not settled (within the window's
// first kLagStartSettle_s the rod moves more than 0.1 mm or a pressure more
// than kStartPressureBand_Pa) under a command that changes within the window
// (beyond the logger's kCommandNoise_V), and that LoggedCommand did not
// already start at a step: the command before the run, held long enough for
// the lags to settle, whose simulated window (x, p1, p2 against `noise`)
// fits the logged one best (a grid over -1..1 V by 0.1 V, then golden
// section to 1 mV). Kept when the given start's misfit is over
// kLagStartMisfit and the read one under kLagStartKeepRatio of it. One
// scalar stands for the lag states: the valve pair it opens at its settled
// gain, the other closed.
constexpr double kLagStartSettle_s = 0.02;
LagStart ReadLagStart(const Parameters& params, const Trajectory& measured,
                      const CommandSignal& command, const InitialState& initial,
                      const std::map<std::string, double>& noise, const SimulationOptions& options);

}  // namespace pneumaid
