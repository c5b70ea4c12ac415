// The command-driven state of a run (internal to src/sim/): valve commands
// with their hysteresis latches, and the lag states (valve openings, tube
// conductances) at the start of a run, settled or replayed from the log.
#pragma once

#include <array>
#include <cmath>

#include "pneumaid/model/actuator.h"
#include "pneumaid/model/valve_bank.h"
#include "pneumaid/sim/command.h"
#include "pneumaid/sim/simulate.h"

namespace pneumaid::internal {

// Turns command values into valve commands, keeping each valve's hysteresis
// latch across segments.
class ValveCommandTracker {
 public:
  ValveCommandTracker(ValveBranchMode mode, double threshold_V)
      : mode_(mode),
        latches_{BranchLatch(threshold_V), BranchLatch(threshold_V), BranchLatch(threshold_V),
                 BranchLatch(threshold_V)} {}

  ValveCommand Next(double command_V) {
    ValveCommand command;
    command.opening = OpeningsForCommand(command_V);
    for (int i = 0; i < kValveCount; ++i) {
      latches_[i].Update(command.opening[i]);
      command.decreasing_branch[i] = mode_ == ValveBranchMode::kHysteresis
                                         ? latches_[i].decreasing()
                                         : mode_ == ValveBranchMode::kDecreasing;
    }
    return command;
  }

 private:
  ValveBranchMode mode_;
  std::array<BranchLatch, kValveCount> latches_;
};

// Relaxes the lags driven by the command alone over dt seconds of a held
// command: exact exponentials.
template <typename T>
void RelaxCommandLags(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                      const ValveCommand& command, double dt, T* y) {
  using std::exp;
  if (!(dt > 0)) return;
  if (layout.valve_lag) {
    const T keep = exp(T(-dt) / c.valve_lag_tau_s);
    for (int pair = 0; pair < kValvePairCount; ++pair) {
      T& opening = y[layout.opening_begin + pair];
      const T target(command.opening[kValvePairs[pair].lead]);
      opening = target + (opening - target) * keep;
    }
  }
  if (layout.conductance_lag) {
    const auto gain = ValveGains(c, command, ValveOpeningsInUse(layout, command, y));
    const T keep = exp(T(-dt) * c.pipeline_delta_per_s);
    for (int pair = 0; pair < kValvePairCount; ++pair) {
      T& lagged = y[layout.conductance_begin + pair];
      const T& target = gain[kValvePairs[pair].lead];
      lagged = target + (lagged - target) * keep;
    }
  }
}

// The lag states at t0 (InitialState::lag_history_from_s): settled for the
// command before `from` (a knot at `from` is a step the lags then follow, as
// Run() applies the knots at t0: a log that starts at its step), then relaxed
// through every knot up to t0. `tracker` is
// fresh; it is advanced as the run's own tracker would be.
template <typename T>
void ReplayLagHistory(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                      const CommandSignal& command, ValveCommandTracker tracker, double from,
                      double t0, T* y) {
  ValveCommand current = tracker.Next(command.initial_V);
  size_t knot = 0;
  for (; knot < command.time_s.size() && command.time_s[knot] < from; ++knot) {
    current = tracker.Next(command.value_V[knot]);
  }
  SetLagStatesToEquilibrium(layout, c, current, y);
  double t = from;
  for (; knot < command.time_s.size() && command.time_s[knot] <= t0; ++knot) {
    RelaxCommandLags(layout, c, current, command.time_s[knot] - t, y);
    current = tracker.Next(command.value_V[knot]);
    t = command.time_s[knot];
  }
  RelaxCommandLags(layout, c, current, t0 - t, y);
}

// The lag states of y at t0: settled for the initial command, or replayed.
template <typename T>
void InitialLagStates(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                      const CommandSignal& command, const ValveCommandTracker& fresh,
                      const ValveCommand& initial_command, const InitialState& initial, double t0,
                      T* y) {
  // heat_transfer: the gas starts at the wall's temperature.
  for (int i = 0; i < 2 && layout.heat_transfer; ++i)
    y[layout.temperature_begin + i] = c.supply_temperature_K;
  if (std::isnan(initial.lag_history_from_s)) {
    SetLagStatesToEquilibrium(layout, c, initial_command, y);
  } else {
    ReplayLagHistory(layout, c, command, fresh, initial.lag_history_from_s, t0, y);
  }
}

}  // namespace pneumaid::internal
