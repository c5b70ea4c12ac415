// Starting points of the friction fit read off the stroke logs: Fs from the
// breakaways, Fd, b and vs from the force balance of the smooth slides.
#pragma once
#include <vector>

#include "friction_segments.h"
#include "friction_slides.h"

namespace pneumaid::friction_internal {

// A starting point for Fs: the median force at breakaway of the slides of
// `direction` (the stroke ends' breakaways with fewer than three).
double BreakawayMedian(const StrokeData& data, int direction, double fallback);

// The standard error of that median from the breakaways' robust spread (0
// where there is none: the fallback).
double BreakawayMedianError(const StrokeData& data, int direction);

// (Fd, b) of one direction from its force-balance samples with Fs and vs
// given (Fd in [0, Fs], b >= 0); the weighted squared misfit, HUGE_VAL (and
// fd, b untouched) with fewer than kMinSlideSamples samples.
double FitSliding(const std::vector<internal::SlideCluster>& clusters, int direction, double fs,
                  double vs, double* fd, double* b);

// Fd, b, vs of one direction from its force-balance samples, Fs given (the
// breakaways): the best point of a vs grid, (Fd, b) solved exactly at each.
// Leaves `block` as it is with fewer than kMinSlideSamples samples.
void ForceBalanceStart(const StrokeData& data, int direction, Block* block);

}  // namespace pneumaid::friction_internal
