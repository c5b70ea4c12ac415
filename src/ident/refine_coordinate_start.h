// Refinement (refine.h), a start one friction coefficient away: where the
// component fits leave every friction coefficient near the truth but one
// (a 0.5 kg rod at 1 kHz whose positive Stribeck velocity was 17 % low: the
// runs' median reduced chi-square 3.7e3, 2.7 at the truth, 4.2 with only
// that coefficient at its truth), the whole-run cost is so steep and rough
// along it that the fit from the start stalls, and the screen
// (refine_friction_screen.h), which solves Fd and b from the slides, moves
// the coefficients that were right. Each round scans every free friction
// coefficient on its own over a geometric grid around the current value,
// the others held, every candidate simulated once and judged by the
// verdict's measure, and takes the one best move.
#pragma once

#include <string>
#include <vector>

#include "pneumaid/ident/refine.h"

namespace pneumaid::refine_internal {

struct CoordinateSearch {
  Parameters start;              // `start` with the moves taken
  double chi_square_before = 0;  // the verdict's measure at `start`
  double chi_square_after = 0;   // and at the moved start
  int candidates = 0;            // simulated
  bool moved = false;            // some move lowered the measure
  std::string report;            // one line: the moves taken, or that none lowered the measure
};

// Up to RefineOptions::coordinate_rounds moves of the free friction
// coefficients (Fs, Fd, b, vs of each direction) of `spec` from `start`,
// each within a factor RefineOptions::coordinate_span of the value before
// it (of a floor where the value is near 0: Fd 5 % of Fs, b 0.5 N s/m,
// vs 1 mm/s, Fs 0.1 N), inside the spec's bounds (a grid point clamped to
// the one before it is not simulated again), Fd at most Fs; a round that
// gains nothing ends the search. A moved coefficient loses its
// standard error in `start.uncertainty` (as the screen's).
CoordinateSearch SearchFrictionCoordinates(const Parameters& start, const Unit& unit,
                                           const FitSpec& spec, const RefineOptions& options);

// RefineOptions::stribeck_velocity_divisor: one start per direction whose
// Stribeck velocity is free in `spec`, `from` with that vs divided by the
// divisor (clamped to its bounds; a start equal to `from` is left out), the
// other values as they are, and the moved vs without a standard error.
struct VelocityStart {
  std::string direction;  // "positive" or "negative"
  Parameters start;
};
std::vector<VelocityStart> StribeckVelocityStarts(const Parameters& from, const FitSpec& spec,
                                                  double divisor);

}  // namespace pneumaid::refine_internal
