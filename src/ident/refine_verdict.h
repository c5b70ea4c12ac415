// Refinement (refine.h), its stopping verdict: how far each fitted run's
// channels are from what the declared sensor noise explains, where the worst
// stretch of each lies, and whether the set explains the runs.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

#include "pneumaid/ident/refine.h"
#include "refine_residual.h"
#include "refine_runs.h"

namespace pneumaid::refine_internal {

// The misfit of each channel of run `e` from its weighted residuals (channel
// after channel, as the residual block writes them; start priors ignored).
std::vector<ChannelMisfit> RunMisfits(const FitExperiment& e, const Eigen::VectorXd& residuals,
                                      double window_s);

// The misfits of each channel of each run.
std::vector<ChannelMisfit> MisfitsOf(const std::vector<RunResiduals>& runs, double window_s);

// MisfitsOf every whole fitted run at `params`, simulated from its logged
// start.
std::vector<ChannelMisfit> WholeRunMisfits(const Parameters& params, const Unit& unit,
                                           const FitSpec& spec, const RefineOptions& options);

// The median over runs of each run's reduced chi-square over its channels
// and the pieces a logger's pause cut it in, weighted by their rows.
double MedianRunChiSquare(const std::vector<ChannelMisfit>& misfits);

// The verdict's rule, in one place: a median run reduced chi-square (of a
// fit, or of a start simulated with no fit) that explains the runs (NaN:
// not).
inline bool Explains(double median_run_chi_square, const RefineOptions& options) {
  return median_run_chi_square <= options.acceptable_reduced_chi_square;
}

// The verdict's measure of `params` with no fit: MedianRunChiSquare of the
// WholeRunMisfits, HUGE_VAL where a run cannot be simulated. What the starts'
// searches (the friction screen, the coordinate start) rank candidates by.
double VerdictMeasure(const Parameters& params, const Unit& unit, const FitSpec& spec,
                      const RefineOptions& options);

// The windows' measure of `params` with no fit: the mean square of the
// weighted data residuals over the fitted runs cut into the windows of
// multiple shooting (each from its logged state, v = 0), HUGE_VAL where a
// measured window cannot be simulated. A window holds one slide, so an error
// of one direction's friction does not carry into the slides after it: what
// the windowed friction screen ranks candidates by. It measures at most
// RefineOptions::screen_windows_max windows (SubsetByHash; 0: all), so a
// window outside them that cannot be simulated does not count.
//
// With `above` finite, the windows stop once those simulated put the mean
// square above it: the squares only add up, so the value returned is then a
// lower bound of the measure, above `above` (finite even where a later
// window could not be simulated), and *exact (if given) false. A search that
// only asks whether a candidate measures below `above` gets the same answer
// for a fraction of the simulations.
double WindowedMeasure(const Parameters& params, const Unit& unit, const FitSpec& spec,
                       const RefineOptions& options, double above = HUGE_VAL,
                       bool* exact = nullptr);

// The verdict on `r` (its misfits, the pieces of a paused run joined into
// one per run and channel): status, threshold, and when it fails a message
// naming the worst runs, channels and windows.
void Judge(const RefineOptions& options, RefineResult* r);

}  // namespace pneumaid::refine_internal
