// WindowedMeasure (refine_verdict.h) for a search's many candidates, each
// one direction's friction away from the best so far. For one set, the base,
// each window's squares and what its simulation read of the friction
// (FrictionUse, simulate.h) are kept. A candidate that differs from the base
// in one direction's friction alone takes from it every window that
// direction cannot change (the base never slid that way there, and both the
// candidate's static force and the base's hold each breakaway test the
// base's run made): the same trajectory to the bit, so the same squares. It
// simulates the rest. An exact measure is WindowedMeasure's to the bit
// (summed in the windows' order); a lower bound is one too, above the bound
// asked for, though not WindowedMeasure's own: the windows taken count
// first, so a candidate that measures above the bound stops sooner. One
// instance per search: its calls are not for two threads (MeasureSeveral
// runs its candidates on threads of its own).
#pragma once

#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include "pneumaid/ident/refine.h"
#include "pneumaid/sim/simulate.h"

namespace pneumaid::refine_internal {

class WindowedMeasures {
 public:
  // `unit`, `spec` and `options` must outlive it.
  WindowedMeasures(const Unit& unit, const FitSpec& spec, const RefineOptions& options);

  // WindowedMeasure(params, unit, spec, options, above, exact).
  double Measure(const Parameters& params, double above = HUGE_VAL, bool* exact = nullptr);

  // Each of `candidates` measured as Measure measures it alone, on up to
  // `threads` threads, against the one bound `above`: a measure and whether
  // it is exact, per candidate.
  std::vector<std::pair<double, bool>> MeasureSeveral(const std::vector<Parameters>& candidates,
                                                      double above, int threads);

  // The base from now on: a set of the last call's measured exactly, when
  // one is `params` (a search's new best), else `params` measured whole (one
  // simulation of each window).
  void Rebase(const Parameters& params);

  long windows_simulated() const { return windows_simulated_; }
  long windows_taken() const { return windows_taken_; }  // from the base, not simulated

 private:
  struct Measured {
    Parameters params;
    double static_force_N[2] = {0, 0};  // each side's Fs as simulated
    std::vector<long> rows;             // each window's data rows
    std::vector<double> squares;        // each window's sum of squared data residuals
    std::vector<FrictionUse> use;       // each window's simulation's
  };

  // Measure's work, for any thread: into `m` (its params set when exact),
  // counting the windows simulated and taken.
  double MeasureInto(const Parameters& params, double above, bool* exact, Measured* m,
                     long* simulated_windows, long* taken_windows) const;

  // The side (0: positive, 1: negative) whose friction alone `params` may
  // differ in from the base (0 when it is the base's); -1 when it differs in
  // more, or there is no base.
  int SideApartFromBase(const Parameters& params) const;

  const Unit& unit_;
  const FitSpec& spec_;
  const RefineOptions& options_;
  std::optional<Measured> base_;
  std::vector<Measured> last_;  // the sets the last call measured exactly
  long windows_simulated_ = 0, windows_taken_ = 0;
};

}  // namespace pneumaid::refine_internal
