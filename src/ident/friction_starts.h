// Starting points of the friction fit read off the stroke logs: Fs from the
// breakaways, Fd, b and vs from the force balance of the smooth slides.
#pragma once
#include <array>
#include <vector>

#include "friction_segments.h"
#include "friction_slides.h"

namespace pneumaid::friction_internal {

// What the stroke logs tell of one direction's coefficients before any fit:
// the friction fit's start, and the readings its errors are checked against
// (friction_covariance.h, WidenByDisagreement).
struct LogsReading {
  Block value{};                                  // Fs, Fd, b, vs; the fallback's where not read
  std::array<bool, kDirectionParameters> read{};  // read off the logs
  Block error{};  // standard error (Fs: the breakaways' median's); 0: none known
};

// Fs: the median force at breakaway of the slides of `direction` (the stroke
// ends' breakaways with fewer than three), its error from their robust spread
// (1.2533 x 1.4826 MAD / sqrt n); then Fd, b and vs from the force balance of
// the smooth slides at that Fs (ForceBalanceStart); `fallback` where the logs
// give nothing. A value read is the reading as the logs give it, also where it
// lies outside the fit's bounds (the fit clamps its start) and also where it
// equals the fallback. The force balance gives no error: its samples are
// correlated within a slide, and its vs can rest on the Stribeck term's tail
// alone (2 % of the drop at 2 vs). Taking vs as not read where no slide
// reaches below 2 vs put identify's coefficients within 3 errors of the truth
// at 87 % instead of 91 % on the sweep and moved three refinements into worse
// basins (docs/identification.md).
LogsReading ReadOffLogs(const StrokeData& data, int direction, const Block& fallback);

// (Fd, b) of one direction from its force-balance samples with Fs and vs
// given (Fd in [0, Fs], b >= 0); the weighted squared misfit, HUGE_VAL (and
// fd, b untouched) with fewer than kMinSlideSamples samples.
double FitSliding(const std::vector<internal::SlideCluster>& clusters, int direction, double fs,
                  double vs, double* fd, double* b);

// Fd, b, vs of one direction from its force-balance samples with Fs given
// (the breakaways): the best point of a vs grid, (Fd, b) solved exactly at each.
// Leaves `block` as it is, and returns false, with fewer than
// kMinSlideSamples samples.
bool ForceBalanceStart(const StrokeData& data, int direction, Block* block);

}  // namespace pneumaid::friction_internal
