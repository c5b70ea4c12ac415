// Identification of the Stribeck friction (seed paper Eq. 12, per direction)
// from stroke logs, by output error on position: the rod's equation of motion
// with stick (rod_replay.h) is driven by the force of the measured chamber
// pressures, and Ceres fits Fs, Fd, b, vs of both directions so that the
// replayed positions match the logged ones.
//
// With the paper's friction the rod moves in stick-slip, so the logs are cut
// into segments at the rod's stuck phases: each segment starts stuck at the
// phase's measured position (v = 0 is then known exactly), covers breakaway,
// the slide and the next arrest (friction_segments.h). A segment starts at a
// stroke end only in a direction whose breakaways mid-stroke are too few or
// leave Fs undetermined, and then covers little more than its breakaway
// (end_slide_m: end-stop forces, fast pressures there). Smooth slides that no
// segment covers enter as force balance, friction(v) = F - M a
// (friction_slides.h). Breakaways and the force balance start the fit, and a
// screen of replayed candidates a second fit where it finds a better start; a
// weak prior per coefficient keeps what the logs do not determine near the
// prior.
//
// Uncertainty: the replay integrates the pressure sensors' noise twice, so the
// residuals inside a segment are correlated and (J'J)^-1 s^2 would understate
// the errors. The reported covariance is the cluster-robust sandwich
// (J'J)^-1 (sum over clusters J_k' r_k r_k' J_k) (J'J)^-1, the clusters being
// the segments and the smooth slides, the prior's information in both the
// bread and the meat; docs/identification.md derives it.
#pragma once

#include <string>
#include <vector>

#include "pneumaid/ident/fit_result.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid {

struct FrictionFitOptions {
  // The rod counts as stuck over a run of samples whose logged positions stay
  // within this band [m] (plus 6 x the position noise, declared or estimated,
  // grown by the inverse of a declared x lag, or 1.25 position quanta on a
  // log quantised more coarsely, whichever is wider); runs shorter
  // than min_stuck_samples are not stuck phases. (The one rule of "stuck":
  // multiple shooting, FitStage::windows, cuts its windows by it too, with
  // these defaults.)
  double stuck_band_m = 2.5e-5;
  int min_stuck_samples = 5;
  // ... and last at least min_stuck_s, and move like a rod at rest (least
  // squares over the run): slower than max_stuck_speed_m_per_s, with less
  // curvature than max_stuck_acceleration_m_per_s2 (or within 4 x what the
  // position noise gives). At a high sample rate a slow slide stays inside
  // the band for many samples, and the apex of a reversal that does not
  // stick looks still for a while: neither is stuck.
  double min_stuck_s = 0.004;
  double max_stuck_speed_m_per_s = 2e-3;
  double max_stuck_acceleration_m_per_s2 = 0.5;
  // Of a long stuck phase only its last samples before breakaway enter the
  // segment; a segment also keeps this many samples of the next stuck phase,
  // where the replay must have arrested the rod at the right place.
  int max_stuck_samples = 40;
  int arrest_samples = 10;
  // The force while stuck is replaced by a quadratic fitted to this many of
  // the stuck phase's last samples (its noise would trigger breakaway early).
  int stuck_force_samples = 20;
  // Within this distance of a stroke end [m] (plus 4 x the declared position
  // noise) the rod may touch the end stop, whose forces are not friction: a
  // slide is cut where it enters that zone, and a rod stuck there starts a
  // segment (in a direction that replays its stops: end_slide_m) once the
  // force points away from the stop.
  double end_margin_m = 3e-4;
  // Strokes that run from stop to stop stick nowhere else: a direction with
  // fewer than three slides that break away mid-stroke, or whose Fs those
  // slides do not determine (then fitted again), also replays the slides
  // that leave an end stop, from the stuck samples whose force points away
  // from the stop through the breakaway until the rod has
  // travelled this far [m] (at least two samples), which is what tells
  // its Fs. Not further: the chamber at the stop is near its dead volume, so
  // its pressure falls faster than a replay between samples follows once the
  // rod moves, and not in a direction with slides mid-stroke, whose
  // component fits it moved (docs/identification.md). 0: no segment starts
  // at a stop.
  double end_slide_m = 1e-4;
  // A slide replayed from its breakaway is cut after this long [s] (the
  // replay integrates any bias of the measured force twice); the rest of it
  // enters as force balance.
  double max_slide_s = 0.1;
  // Also fit the force balance of smoothly sliding samples (friction(v) =
  // F - M a, v and a by a local quadratic over smoothing_window_s).
  bool force_balance = true;
  double smoothing_window_s = 0.01;
  // Screen a grid of Fs, Fd, b and vs per direction (each candidate one
  // replay of every segment); where a candidate beats the starts read off the
  // logs, fit from both and keep the screened fit when its misfit is lower by
  // more than 1 %. Stick-slip replays have narrow basins.
  bool screen_starts = true;
  // Where a replay breaks away is uncertain by this x h^2 [s] (h the sample
  // interval): the rod escapes from the flat top of the Stribeck curve (its
  // slope is zero at v = 0) under a slowly rising force, so small errors of
  // that force move the escape, and between samples the force is
  // interpolated linearly, missing the kink where the chamber starts to
  // expand. A forward replay then carries the acceleration after breakaway
  // x that time as a velocity error, which its weights include. On
  // noise-free rig data a heavy rod's replays at the true coefficients are
  // off by the equivalent of ~60 /s; 125 /s is twice that (0.5 ms at
  // 500 Hz, 5 us at 5 kHz: the rig's smooth stick moves the escape too). On
  // the sweep's component fits 62 to 250 /s gave 202 to 207 coefficients
  // within tolerance of 320 (0: 184). 0: no such error.
  double breakaway_timing_per_s = 125.0;
  // RK4 steps while sliding near the Stribeck region: a sample interval is
  // split into ceil(h / replay_step_s) steps (on a clock that keeps no time
  // each logged interval by its own h), at most max_substeps (8 at
  // 500 Hz and below, 4 at 1 kHz, 2 at 2 kHz, 1 at 5 kHz). Above 4 vs a
  // quarter of them (rod_replay.h). A fixed 8 per interval made a 5 kHz
  // log's fit 5x slower for the same coefficients (within 0.3 %); 16 at
  // 250 Hz (the same step as 500 Hz) moved three of the sweep's five 250 Hz
  // units into other basins (docs/identification.md).
  double replay_step_s = 2.5e-4;
  int max_substeps = 8;
  // Ceres Levenberg-Marquardt iterations.
  int max_iterations = 50;
  // A segment whose mean squared residual exceeds this multiple of the median
  // segment's is treated as an outlier: the fit is repeated with a Huber loss
  // that bounds each segment's influence.
  double outlier_ratio = 25.0;
  // The stated prior uncertainty of each coefficient: a weak Gaussian prior
  // around the prior set's value (vs: on a log scale, a factor e^sigma)
  // keeps what the logs do not determine near the prior; against logs that
  // determine a coefficient it is negligible. Wide enough for Fs 2-20 N,
  // Fd 0.1-10 N, b 1-15 N s/m, vs 2-25 mm/s.
  double prior_static_sigma_N = 10.0;
  double prior_dynamic_sigma_N = 5.0;
  double prior_viscous_sigma_N_s_per_m = 7.0;
  double prior_stribeck_log_sigma = 1.1;  // ln 3
  // A coefficient whose standard error exceeds this fraction of its value
  // and its tolerance (0.1 N, 0.5 N s/m, 1 mm/s) is not determined by the
  // logs: it is reported as held, by name with why (determination.h).
  double identifiable_relative_error = 0.5;
  // A held coefficient takes the prior's value (true) or keeps the value the
  // regularised fit gave it (false).
  bool held_at_prior = false;

  bool IsValid(std::string* error) const;
};

// What one direction's slides were, and its coefficients as a branch.
struct DirectionFit {
  StribeckParams params;  // the values of this direction's coefficients
  int segments = 0;       // replayed segments whose slide goes this way
  int smooth_slides = 0;  // force-balance clusters (smooth slides) this way
};

// Coefficients "friction.<direction>.Fs", "Fd", "b", "vs" (positive first);
// each one the logs do not determine is held with the reason
// (FrictionFitOptions::held_at_prior says at which value). Not fitted: no
// slide in the stroke logs, or the solver failed; the prior is kept.
// The screen of starts (FrictionFitOptions::screen_starts): per direction
// (positive first) the misfit of the starts read off the logs and of the best
// candidate (grid points), sum over its segments and slides and the stuck
// segments of rows x ln(1 + mean square residual). When the screen moved a
// start, the fit runs from both and keeps the screened fit when its misfit is
// lower by more than 1 %.
struct FrictionStartScreen {
  int candidates = 0;  // 0: not screened
  double start_misfit[2] = {0, 0};
  double best_misfit[2] = {0, 0};
  bool used = false;  // the fit from the screened start was kept
};

struct FrictionFitResult : FitResult {
  DirectionFit positive, negative;
  FrictionStartScreen start_screen;
  int segments = 0, samples = 0, excluded_segments = 0, outlier_segments = 0;
  int smooth_samples = 0;     // force-balance samples
  double position_rms_m = 0;  // replay vs log over all fitted samples
  std::string BriefReport() const;
};

// Fits both directions; a direction without slides keeps `prior`'s values.
// `orientation` and the load mass come from the unit's manifest.
FrictionFitResult FitFriction(const Unit& unit, const FrictionParams& prior,
                              const FrictionFitOptions& options);

// The friction-velocity map of the seed paper's Figs. 8 and 9 read off the
// stroke logs: the force balance dir (F - M a) of every smoothly sliding
// sample (friction_slides.h), stick-slip slides included, per direction. What
// a plot of the fitted Stribeck curves is judged against.
struct FrictionMapSample {
  int direction = 0;  // +1 extending, -1 retracting
  double speed_m_per_s = 0;
  double friction_N = 0;
};
std::vector<FrictionMapSample> FrictionVelocityMap(const Unit& unit,
                                                   const FrictionFitOptions& options);

// Starts for fits through the simulator that free the friction (with the
// friction_pressure effect, effects.h, or without): Fd (and on request Fs)
// of both directions, and kp when asked, read off the force balance of the
// smooth slides of the runs `runs` (any kind that logs x, p1 and p2),
// friction = (1 + kp ((p1 + p2)/2 - p_atm)) S(|v|), the other coefficients
// held at `prior`'s (what the fits it starts do not free), by least squares
// with the friction fit's weak prior toward `prior`. Output error through
// the simulator has narrow basins in these coefficients where the rod sticks
// and slips (a start a factor 2 off in kp ends in another minimum); the force
// balance needs neither a simulation nor a start near the optimum.
struct SlideFrictionOptions {
  bool pressure_gain = true;     // fit kp (from kp_per_Pa); false: kp held at kp_per_Pa
  double kp_per_Pa = 0;          // the start, or the value held (0: the base model)
  bool static_friction = false;  // fit Fs too
  // A direction with fewer slide samples keeps the prior's coefficients.
  int min_samples = 50;
};
// Not ok, with why, when neither direction has min_samples or (fitting kp)
// the slides' mean chamber pressure does not vary.
struct SlideFrictionStart {
  bool ok = false;
  std::string why;
  FrictionParams friction;
  double kp_per_Pa = 0;
  int samples = 0;
};
SlideFrictionStart FrictionFromSlides(const Unit& unit, const std::vector<std::string>& runs,
                                      const FrictionParams& prior,
                                      const FrictionFitOptions& options,
                                      const SlideFrictionOptions& slide_options);

}  // namespace pneumaid
