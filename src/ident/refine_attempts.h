// Refinement (refine.h), its attempts: the fit through every stage from the
// given start, then, while the verdict says the runs are not explained, the
// later attempts in a fixed order, the Better fit kept at each step:
//   1. the friction screen (refine_friction_screen.h): a start whose
//      friction is read off the logs, and its next-best candidates (also
//      when the given fit is explained but leaves friction at a bound);
//      when still not explained, the same ranked by the windows, each of
//      its candidates whose fit is not explained fitted once more with the
//      last stage by multiple shooting first (with windowed_refit on);
//   2. a start one friction coefficient away from the given one
//      (refine_coordinate_start.h; also on an explained fit whose measure is
//      above RefineOptions::coordinate_start_above, which then gives way to
//      a clear gain only);
//   3. per direction, the given start with its Stribeck velocity divided
//      (refine_coordinate_start.h; on the same trigger);
//   4. a robust refit (each run through a Cauchy loss);
//   5. a windowed refit (the last stage by multiple shooting first);
//   6. rescue starts in a trust box around the given start (the last stage
//      only);
//   7. a windowed polish: the kept fit's last stage again from its own
//      result, by multiple shooting first.
// What the kept fit started from and each attempt's one-line report are the
// caller's to put into the result (refine.cpp).
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "pneumaid/ident/fit_spec.h"
#include "pneumaid/ident/refine.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"
#include "refine_friction_screen.h"

namespace pneumaid::refine_internal {

// One fit through every stage from a start, judged by the verdict.
struct StagedFit {
  RefineResult result;
  Parameters before_last;              // what the last stage started from
  std::vector<ExperimentCost> before;  // the first fitted stage's costs at its start
  double cost_before = 0;
  bool first_fit_windowed = false;  // `before` and `cost_before` are windows'
  // From a start a later attempt moved (the screen's, the coordinate or a
  // Stribeck velocity start's), else from the caller's.
  bool from_moved_start = false;
  // Its start was fitted with the last stage by multiple shooting first too
  // (ShootingFirst), the Better of the two kept; `by_windows_first`: that fit.
  bool shot_too = false, by_windows_first = false;
};

// The verdict on a fit's last stage: a windowed stage's runs are judged
// whole, from their logged starts, and its costs (fitted, final_cost) are
// those whole runs' (one simulation for both).
void JudgeLastStage(const FitStage& last, const Unit& unit, const FitSpec& spec,
                    const RefineOptions& options, RefineResult* r);

// Whether fit `a` is better than `b`: explained first, then any with values
// by the lower median (NaN, no run simulated, counts as infinite), nothing
// usable last.
bool Better(const RefineResult& a, const RefineResult& b);

// What `later`, a fit from another start than the caller's (a later round,
// the creep fit), says of the caller's start is `first`'s: the whole runs'
// costs there (by run id), the coefficients' start values (by path) and the
// held-out runs before.
void FromCallersStart(const RefineResult& first, RefineResult* later);

// Why Better(candidate, kept) is false, as a report's words.
std::string WhyNotKept(const RefineResult& candidate, const RefineResult& kept);

// A fit's median reduced chi-square as a report's words ("4.22"), or "no
// values" for a fit that has none.
std::string MeasureText(const RefineResult& fit);

// The wall time since `since` [s]; a time as "; 12.3 s", closing an
// attempt's report line (where a refinement's time goes:
// docs/refinement.md); and Took(since), the two together.
double SecondsSince(std::chrono::steady_clock::time_point since);
std::string SecondsText(double seconds);
std::string Took(std::chrono::steady_clock::time_point since);

class Attempts {
 public:
  // Fits from `start` through `stages`: the given attempt. Every argument
  // must outlive the object.
  Attempts(const Parameters& start, const Unit& unit, const FitSpec& spec,
           const std::vector<FitStage>& stages, const RefineOptions& options);

  // The later attempts, in order; each does nothing once the kept fit is
  // explained (the coordinate and velocity starts: explained at or below
  // coordinate_start_above), or when its option is off. The caller runs none
  // after a stop (StopRequested); within one, the screens stop between
  // candidates.
  void ScreenFriction();
  void CoordinateStart();
  void VelocityStarts();
  void RobustRefit();
  void WindowedRefit();
  void Rescue();
  void WindowedPolish();

  // The fit kept.
  StagedFit& best() { return best_; }
  // One line per later attempt (empty: not tried), and how many friction
  // starts the screen simulated.
  // The whole runs' screen's line, then the windows' screen's (if it ran).
  std::string screen_report() const;
  const std::string& coordinate_report() const { return coordinate_report_; }
  const std::string& velocity_report() const { return velocity_report_; }
  const std::string& robust_report() const { return robust_report_; }
  const std::string& windowed_report() const { return windowed_report_; }
  const std::string& polish_report() const { return polish_report_; }
  int screened_candidates() const { return screened_candidates_; }

 private:
  bool Explained() const { return best_.result.explained(); }
  // Explained at or below RefineOptions::coordinate_start_above: the
  // coordinate and velocity starts are not tried (or no more of them).
  bool ExplainedNearNoise() const;
  // Whether a fit from a moved start (the coordinate or a velocity start)
  // may replace the kept one: always while that is not explained, else only
  // at most coordinate_start_keep_ratio of its measure (a clear gain).
  bool ClearGain(const RefineResult& candidate) const;
  // One friction screen ranked by `measure`, the fits from its start and
  // next-best candidates offered; its one-line report into `report`.
  void ScreenWith(ScreenMeasure measure, bool even_if_explained, std::string* report);
  // Keeps `candidate` when it is Better, `report` then naming the attempt
  // that found it; the iterations add up either way. True when kept.
  bool Offer(StagedFit&& candidate, std::string* report);
  // A fit from the moved start (moved_start_) through `stages`, offered; its
  // one-line report.
  void Refit(const char* what, const std::vector<FitStage>& stages, bool robust_runs,
             std::string* report);

  const Parameters& start_;
  const Unit& unit_;
  const FitSpec& spec_;
  const std::vector<FitStage>& stages_;
  const RefineOptions& options_;
  StagedFit best_;
  // The given attempt's: whether it had values, and where its last stage
  // started (the rescue starts from there).
  bool given_has_values_ = false;
  Parameters given_before_last_;
  Parameters moved_start_;
  bool moved_ = false;  // moved_start_ differs from start_
  // moved_start_ was fitted by windows first already (a candidate of the
  // windows' screen): the windowed refit from it would repeat that fit.
  bool moved_start_shot_ = false;
  std::string screen_report_, windows_screen_report_, coordinate_report_, velocity_report_,
      robust_report_, windowed_report_, polish_report_;
  int screened_candidates_ = 0;
  std::string* kept_report_ = nullptr;  // the report of the later attempt kept, if any
};

}  // namespace pneumaid::refine_internal
