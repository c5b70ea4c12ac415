// Identification of the Stribeck friction (seed paper Eq. 12, per direction)
// from stroke logs, by output error on position: the rod's equation of motion
// with stick (rod_replay.h) is driven by the force of the measured chamber
// pressures, and Ceres fits Fs, Fd, b, vs of both directions so that the
// replayed positions match the logged ones.
//
// With the paper's friction the rod moves in stick-slip, so the logs are cut
// into segments at the rod's stuck phases: each segment starts stuck at the
// phase's measured position (v = 0 is then known exactly), covers breakaway,
// the slide and the next arrest. Segments touching the stroke ends (end-stop
// forces) are left out. Breakaway forces give the starting point of Fs.
//
// Uncertainty: the replay integrates the pressure sensors' noise twice, so the
// residuals inside a segment are correlated and (J'J)^-1 s^2 would understate
// the errors. The reported covariance is the cluster-robust sandwich
// (J'J)^-1 (sum over segments J_k' r_k r_k' J_k) (J'J)^-1, segments being
// independent; docs/identification.md derives it.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid {

struct FrictionFitOptions {
  // The rod counts as stuck over a run of samples whose logged positions stay
  // within this band [m] (plus 6 x the declared position noise); runs shorter
  // than min_stuck_samples are not stuck phases.
  double stuck_band_m = 2.5e-5;
  int min_stuck_samples = 5;
  // Of a long stuck phase only its last samples before breakaway enter the
  // segment; a segment also keeps this many samples of the next stuck phase,
  // where the replay must have arrested the rod at the right place.
  int max_stuck_samples = 40;
  int arrest_samples = 10;
  // The force while stuck is replaced by a quadratic fitted to this many of
  // the stuck phase's last samples (its noise would trigger breakaway early).
  int stuck_force_samples = 20;
  // Segments with a logged position closer than this to a stroke end [m] are
  // left out: end-stop forces are not part of the friction model.
  double end_margin_m = 1e-3;
  // RK4 substeps per sample interval while sliding.
  int substeps = 8;
  // Ceres Levenberg-Marquardt iterations.
  int max_iterations = 50;
  // A segment whose mean squared residual exceeds this multiple of the median
  // segment's is treated as an outlier: the fit is repeated with a Huber loss
  // that bounds each segment's influence.
  double outlier_ratio = 25.0;
  // A parameter whose standard error exceeds this fraction of its value is
  // reported as not identifiable from the data (the value is still written,
  // with its large standard error).
  double identifiable_relative_error = 0.5;

  bool IsValid(std::string* error) const;
};

// The fit of one direction's coefficients.
struct DirectionFit {
  bool fitted = false;  // false: no slide in this direction, the prior is kept
  StribeckParams params;
  std::map<std::string, double> standard_errors;  // "Fs", "Fd", "b", "vs"
  std::vector<std::string> warnings;              // parameters not identifiable, why
  int segments = 0;                               // segments whose slide goes this way
};

struct FrictionFitResult {
  bool fitted = false;
  std::string note;  // why not, or warnings
  DirectionFit positive, negative;
  std::map<std::string, double> correlations;  // "positive.Fs,negative.b" -> r
  int segments = 0, samples = 0, excluded_segments = 0, outlier_segments = 0;
  double initial_cost = 0, final_cost = 0;
  int iterations = 0;
  double position_rms_m = 0;  // replay vs log over all fitted samples
  std::string BriefReport() const;
};

// Fits both directions; a direction without slides keeps `prior`'s values.
// `orientation` and the load mass come from the unit's manifest.
FrictionFitResult FitFriction(const Unit& unit, const FrictionParams& prior,
                              const FrictionFitOptions& options);

}  // namespace pneumaid
