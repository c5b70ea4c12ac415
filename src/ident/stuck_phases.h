// One home of the rule "the rod is stuck here", read off a logged position:
// the friction fit cuts its replay segments at these phases
// (friction_segments.h) and multiple shooting restarts its windows there
// (refine_runs.h). And the force the rod holds while stuck, smoothed.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/io/rig_data.h"

namespace pneumaid::internal {

// A run [begin, end) of samples, and runs.
using Run = std::pair<std::size_t, std::size_t>;
using Runs = std::vector<Run>;

// What counts as stuck in a log sampled every `period_s` (FrictionFitOptions
// holds the tunable part, with its documentation).
struct StuckRule {
  double band_m = 0;                       // the spread of a stuck rod's logged positions
  int min_samples = 0;                     // the shortest stuck phase
  double max_slope_m_per_sample = 0;       // the fastest a stuck rod moves
  double max_curvature_m_per_sample2 = 0;  // its largest acceleration
  double sigma_x_m = 0;                    // the position noise
  double rest_tolerance_m = 0;             // a reading this close to the rest is at rest
};

// The step of a quantised position log `x`: its smallest non-zero change from
// one sample to the next (0 when it never changes). A log that is not
// quantised changes by far less than its noise somewhere, so this is then
// far below it; so does a quantised log read off its steps (resampled onto a
// uniform clock across lost rows, or with a declared lag undone), which
// then keeps the 3 sigma rule.
double PositionQuantum(const std::vector<double>& x);

// The position noise the rule reads on `unit`'s logs: NoiseOf x (declared, or
// estimated from the logs), at least 0.1 um (a noise-free log still has its
// numbers' rounding).
double PositionNoise(const Unit& unit);

// A reading within this many sigma, or this many position quanta, of where
// the rod rests is at rest: a quantised log at rest flickers by one quantum,
// which can exceed 3 sigma (a 20 um step with a 5 um noise), and a
// breakaway read at such a flicker falls samples before the slide starts.
constexpr double kRestSigmas = 3.0;
constexpr double kRestQuanta = 1.25;

// The rule of `options` for a log with position noise `sigma_x_m` and
// quantum `quantum_m` (PositionQuantum; 0: not quantised) sampled every
// `period_s` (> 0): the band is stuck_band_m widened by 6 sigma or
// kRestQuanta quanta, whichever is wider (a rest that flickers between two
// levels of a 0.1 mm ADC spans 0.1 mm, more than 25 um + 6 x 2 um), the
// shortest phase min_stuck_samples or min_stuck_s, whichever is longer; a
// reading is at rest within kRestSigmas sigma or kRestQuanta quanta of the
// rest, whichever is wider.
StuckRule StuckRuleOf(const FrictionFitOptions& options, double sigma_x_m, double quantum_m,
                      double period_s);

// Runs of at least `rule.min_samples` samples whose values stay within
// `rule.band_m` of each other, and whose motion over the run's first four
// fifths (the last samples may already be the slide) is that of a rod at
// rest: slope and curvature below the rule's, or within
// 4 x what the position noise gives. At a high sample rate a slow slide stays
// inside the band for many samples, and the apex of a reversal without stick
// looks still for a while: neither is stuck.
Runs StuckRuns(const std::vector<double>& x, const StuckRule& rule);

// Where the rod rested over the stuck run `run` (not empty) of `x`: its median.
double RestPosition(const std::vector<double>& x, const Run& run);

// The rod's arrival at rest in the stuck run `run`: its first sample within
// `rule.rest_tolerance_m` of where the rod rested (the band's edge is crossed
// earlier, while the rod still slows down).
std::size_t ArrivalSample(const std::vector<double>& x, const Run& run, const StuckRule& rule);

// The breakaway from the stuck run `run`: its last sample still within
// `rule.rest_tolerance_m` of where the rod rested (the band's edge is crossed
// later, at a higher force; a long slide is far past it after a quarter of
// its travel).
std::size_t BreakawaySample(const std::vector<double>& x, const Run& run, const StuckRule& rule);

// While the rod sticks the chamber volumes are constant and the force varies
// smoothly (the valve filling a closed chamber), so its noise is averaged out
// by a quadratic fit over the last `window` samples of each stuck run. That
// matters at breakaway: the first crossing of Fs by the raw noisy force comes
// early, and a replay driven by it would bias Fs. A run whose force the
// quadratic does not follow, a mean square misfit over kSmoothStuckMisfit
// times the noise variance sigma_N^2 (a chamber near its dead volume filled
// within a few samples, at a stop or on a fast valve), keeps its samples as
// logged: the fit would cut the rise short, and the replay break away at a
// fraction of the force the rod held (a 0.11 kg rod at 250 Hz: Fs 0.97 N for
// 15.6).
constexpr double kSmoothStuckMisfit = 25.0;

// Smooths `force` over each of `runs` that way; `t`, when not empty, holds
// the sample times of a log sampled at irregular intervals: the quadratic is
// then in time.
void SmoothStuckForce(const Runs& runs, std::size_t window, double sigma_N,
                      const std::vector<double>& t, std::vector<double>* force);

}  // namespace pneumaid::internal
