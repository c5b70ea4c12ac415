// The friction fit (friction_fit.h), its Ceres problem: the replay segments
// and force-balance slides as residual blocks over the two directions'
// coefficients, the solve, per-segment misfits, and the screen of starts
// that seeds the fit where the logs' own starts (breakaways, force balance)
// leave it outside the basin.
#pragma once

#include <ceres/ceres.h>

#include <vector>

#include "friction_segments.h"
#include "pneumaid/ident/friction_fit.h"

namespace pneumaid::friction_internal {

// The Ceres problem over the segments: friction blocks shared, one arrest
// time per two-sided segment.
struct SegmentProblem {
  ceres::Problem problem;
  std::vector<int> rows;  // residuals per segment, then per force-balance slide
  // Of `rows`, those with a weight (a replay's samples in or after a gap of
  // its log weigh nothing: friction_segments.h).
  std::vector<int> weighted_rows;
  // Per segment (unused when one-sided); kept from one pass to the next.
  std::vector<double>* stop_time_s = nullptr;
};

// Adds every segment and force-balance slide of `data` to `p` (with a Huber
// loss of scale huber_scale[k] on block k unless `huber_scale` is empty),
// both blocks bounded by kLowerBounds and kUpperBounds.
void BuildProblem(const StrokeData& data, double mass_kg, const FrictionFitOptions& options,
                  const std::vector<double>& huber_scale, Block* positive, Block* negative,
                  SegmentProblem* p);

// Levenberg-Marquardt with the arrest times eliminated per segment.
ceres::Solver::Summary Solve(const FrictionFitOptions& options, ceres::Problem* problem);

// Mean squared residual of each block (segments, then slides; residuals
// only: cheap) over its weighted rows, no loss applied; NaN for a block
// with none.
bool SegmentMeanSquares(SegmentProblem* p, std::vector<double>* out);

// The misfit of the blocks' current values: sum over blocks of rows x
// ln(1 + mean square residual), no loss applied, per direction of the slide
// (positive, negative) and, third, of the segments that stay stuck (the
// evidence against a low Fs). Residuals are in units of their expected
// noise, so a good fit's blocks add about rows x ln 2 each, and a few wild
// segments cannot dominate the sum. False when a replay failed.
bool DirectionMisfits(const StrokeData& data, SegmentProblem* p, double misfit[3]);

// The starts' screen. With stick-slip the replay's misfit has basins narrow
// in Fd, b and vs (a light rod whose slips overshoot: from the prior's
// Fd 0.5 N, b 5 N s/m the fit of a unit with Fd 0.7, b 12.5 ended at Fd 14.8
// with 60 x the truth's cost). Every candidate moves both directions to one
// grid point (Fs at 0.8, 1 and 1.25 x the direction's start, Fd a fraction of
// Fs, b and vs over the fleet's ranges) and is one replay of all segments (no
// Jacobian), scored per direction by DirectionMisfits (the stuck segments'
// part counted in both). Each direction takes its best candidate; the pair is
// then replayed together, and of the pair, each direction's best with the
// other's start, and the start the lowest total misfit is returned.
FrictionStartScreen ScreenStarts(const StrokeData& data, double mass_kg,
                                 const FrictionFitOptions& options, Block* positive,
                                 Block* negative);

}  // namespace pneumaid::friction_internal
