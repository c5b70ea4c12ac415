// Refinement (refine.h), its friction starts from the data: whole-run output
// error has narrow basins in the friction when the rod sticks and slips (a
// start a factor 2 off in Fs or vs stalls two orders of magnitude above the
// noise), and the component fit misses Fs and vs where the slides are short
// or the load heavy. When the fit from the given start is not explained (or
// leaves friction at a bound), that start is screened against friction read
// off the logs: per direction, a grid in Fs and vs, each point's Fd and b
// solved from the force balance of the smooth slides (friction_segments.h),
// then a pattern search in Fs and vs; every candidate is simulated once and
// judged by the verdict's measure, 90 to 120 simulations. Ranked by the
// windows instead (WindowedMeasure: each slide from its logged state, so an
// error of one direction does not carry into the other's slides), two
// searches from the start, each ending in a pattern search in Fs, vs, Fd
// and b: a pair of coefficients at a time (a full grid in Fs and vs with the
// start's Fd and b, then a grid in Fd and b) and jointly (a grid in all four
// per direction); the better ranked is the start, the other's best the first
// alternative. With alternatives asked for, a third search, profiled (a grid
// in vs, Fd and b with each point at its best Fs within 15 % of the start's),
// gives one more alternative. About 2 800 candidates, 3 800 with the third
// search; a candidate's windows stop once it measures above the best so far
// (WindowedMeasure's `above`), so most are simulated in part. No Jacobian,
// no fit.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "pneumaid/ident/refine.h"

namespace pneumaid::refine_internal {

// What a screen ranks its candidates by.
enum class ScreenMeasure {
  kWholeRuns,  // VerdictMeasure, the verdict's own
  kWindows,    // WindowedMeasure
};

struct FrictionScreen {
  Parameters start;  // the best candidate (`start` itself when none is better)
  double chi_square_before = 0, chi_square_after = 0;  // the verdict's measure
  double ranked_before = 0, ranked_after = 0;          // the measure it ranks by (0: not screened)
  int candidates = 0;  // simulated, in part or whole (one simulated twice counts twice)
  bool moved = false;  // a candidate ranks before the start
  std::string report;  // one line, empty when nothing moved
  // Up to `alternatives` next-best candidates, each differing from `start`
  // and from one another in some direction's Fs by a factor kDistinctStatic
  // or its vs by kDistinctStribeck, lowest ranked first; ranked by windows,
  // up to `alternatives` + 1 after a profiled search: the first `runner_ups`
  // (0 to 2) are the other search's best and the profiled search's best
  // (which may rank before `start`: a lower measure there is not a better
  // start, docs/refinement.md), then the rest lowest ranked first.
  std::vector<Parameters> alternatives;
  int runner_ups = 0;
  // Ranked by windows with alternatives asked for: the profiled search's
  // best (the given start when nothing ranked before it), and its index in
  // `alternatives` (-1 when it is not one: not distinct from the start, the
  // screen's best or the other search's). A profiled search adds one slot
  // to `alternatives` either way: its best, else the next by rank.
  std::optional<Parameters> profiled;
  int profiled_alternative = -1;
};

inline constexpr double kDistinctStatic = 1.15, kDistinctStribeck = 1.3;

// The screened start for the free friction coefficients of `spec`
// (directions whose Fs and vs are both free); a coefficient it moves loses
// its standard error in `start.uncertainty` (the component fit's no longer
// applies: the start prior treats it as undetermined).
// A start whose runs' median already passes the verdict is returned as it
// is (one simulation) unless `even_if_explained`.
FrictionScreen ScreenFrictionStarts(const Parameters& start, const Unit& unit, const FitSpec& spec,
                                    const RefineOptions& options, bool even_if_explained = false,
                                    int alternatives = 0,
                                    ScreenMeasure measure = ScreenMeasure::kWholeRuns);

}  // namespace pneumaid::refine_internal
