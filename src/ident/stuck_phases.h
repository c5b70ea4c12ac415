// One home of the rule "the rod is stuck here", read off a logged position:
// the friction fit cuts its replay segments at these phases
// (friction_segments.h) and multiple shooting restarts its windows there
// (refine_runs.h).
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

// The position noise the rule reads on `unit`'s logs: NoiseOf x (declared, or
// estimated from the logs), at least 0.1 um (a noise-free log still has its
// numbers' rounding).
double PositionNoise(const Unit& unit);

// A reading within this many sigma of where the rod rests is at rest.
constexpr double kRestSigmas = 3.0;

// The rule of `options` for a log with position noise `sigma_x_m` sampled
// every `period_s` (> 0): the band is stuck_band_m widened by 6 sigma, the
// shortest phase min_stuck_samples or min_stuck_s, whichever is longer; a
// reading is at rest within kRestSigmas sigma of the rest.
StuckRule StuckRuleOf(const FrictionFitOptions& options, double sigma_x_m, double period_s);

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

}  // namespace pneumaid::internal
