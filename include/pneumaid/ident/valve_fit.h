// Identification of the valve gain K_vp(u) (seed paper Eq. 3) from valve
// logs: what each log measures of K_vp (the steady plateaus of a staircase, or
// K_vp on a grid of openings for a ramp or any command that is not held),
// through Eq. 4 at the measured pressures and the meter's declared lag, then
// one Ceres least-squares problem per branch (increasing / decreasing, as the
// command's direction latches it), with covariance.
#pragma once

#include <string>
#include <vector>

#include "pneumaid/ident/fit_result.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid {

struct ValveFitOptions {
  // Each held level's flow is read through the flow meter's declared lag
  // (modelled, not waited out: short holds work), from the samples after the
  // first settle_fraction of the level (a valve's own opening dynamics are
  // not modelled).
  double settle_fraction = 0.2;
  // A valve log is read as a staircase when at least held_fraction of its
  // samples lie in held levels (a level whose command trends by less than
  // half of level_change_V) and it has at most max_levels levels. Any other
  // log (a ramp, a sampled signal) is a continuous command: K_vp of each
  // branch is solved for on nodes every node_spacing_V, linear in between.
  double held_fraction = 0.8;
  int max_levels = 200;
  double node_spacing_V = 0.02;
  // Plateaus with fewer samples used are not used.
  int min_plateau_samples = 10;
  // Half-width of the reported K_vp band in standard deviations.
  double band_sigmas = 2.0;
  // Ceres Levenberg-Marquardt iterations.
  int max_iterations = 200;
  // Fit u_sat (the default; identify --fix-u-sat keeps the prior's). u_sat
  // only decides which plateaus are saturated, so the cost is piecewise
  // constant in it: every split of the plateau openings that leaves at least
  // min_saturated_openings above it is fitted and the cheapest kept; inside
  // its gap u_sat is where the fitted polynomial reaches 1 (K_vp continuous at
  // saturation), or the gap's middle; its standard error is the gap /
  // sqrt(12). A split counts only when the plateaus above it are flat: each
  // within saturation_flatness (relative) of their mean. Where one counts,
  // the split with the top opening alone above it competes too and is kept
  // when it fits better by 9 in chi-square (a decreasing branch starts one
  // step below the staircase's top). A staircase that shows no saturation
  // keeps the prior's u_sat.
  bool fit_u_sat = true;
  int min_saturated_openings = 2;
  double saturation_flatness = 0.005;
  // A change of the logged command larger than this starts a new plateau;
  // smaller changes are the logger's noise.
  double level_change_V = 0.01;

  bool IsValid(std::string* error) const;
};

// One steady plateau of a valve log, or one node of a continuous command's
// K_vp grid.
struct ValvePlateau {
  std::string experiment;
  double u_V = 0;
  bool decreasing = false;  // reached by a step down
  double kvp_kg_per_s = 0;  // measured K_vp
  double kvp_sigma = 0;     // its standard error
  int samples = 0;
  // The flow meter's lag it was read through [s]: the manifest's, or, where
  // that declares none, a staircase's read off its steps (meter_lag_read; 0
  // when they show none) and a continuous command's 0.
  double meter_lag_s = 0;
  bool meter_lag_read = false;
  // A node of a continuous command: its K_vp is that of the hat from
  // u_V - support_half_width_V to u_V + support_half_width_V (one side of it
  // at a break, KvpBreaks); 0 for a plateau.
  double support_half_width_V = 0;
};

// K_vp of one branch on a grid of u, with its band.
struct KvpBand {
  std::vector<double> u_V, kvp, lower, upper;
};

// One branch's fit: coefficients "valve.<branch>.q_max", "a", "b", "c", "d"
// and "u_sat" (held at the prior's unless ValveFitOptions::fit_u_sat and the
// staircase shows saturation). Not fitted: too few plateaus, the prior is kept.
struct BranchFit : FitResult {
  KvpBranchParams params;     // the coefficients as a branch (the prior's when not fitted)
  bool u_sat_fitted = false;  // u_sat was read off the staircase
  // The interval u_sat lies in: the openings either side (a ramp's: one node
  // spacing centred on where the scan of breaks put it).
  double u_sat_gap_low_V = 0, u_sat_gap_high_V = 0;
  int plateaus = 0;
  KvpBand band;
};

// Both branches as one result (their coefficients in turn), and each alone.
struct ValveFitResult : FitResult {
  BranchFit increasing, decreasing;
  std::vector<ValvePlateau> plateaus;
  std::string BriefReport() const;
};

// Where K_vp of a continuous command may jump (u_sat), per branch; 0: no
// jump is placed, each node spans node_spacing_V either side.
struct KvpBreaks {
  double increasing_V = 0;
  double decreasing_V = 0;
};

// The plateaus of every valve experiment of `unit` (and the nodes of those
// whose command is not held, with K_vp free to jump at `breaks`).
// `normalization` is N of Eq. 4. `earlier`, when given, is an earlier call's
// result for the same unit: the plateaus of the held commands, which do not
// depend on `breaks`, are taken from it, not read again (a lag read off the
// steps costs some 65 solves per log).
std::vector<ValvePlateau> ExtractValvePlateaus(const Unit& unit, double normalization,
                                               const ValveFitOptions& options,
                                               const KvpBreaks& breaks = {},
                                               const std::vector<ValvePlateau>* earlier = nullptr);

// Fits both branches; a branch without enough plateaus keeps `prior`'s values.
ValveFitResult FitValve(const Unit& unit, const ValveParams& prior, const ValveFitOptions& options);

}  // namespace pneumaid
