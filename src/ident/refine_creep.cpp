#include "refine_creep.h"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pneumaid/model/actuator.h"
#include "pneumaid/model/effects.h"
#include "refine_attempts.h"
#include "refine_solve.h"

namespace pneumaid::refine_internal {
namespace {

constexpr const char* kEffect = "stick_creep";
constexpr const char* kPath = "effects.stick_creep.v";

// Why the creep fit does not apply to this refinement (empty: it does).
std::string NotApplicable(const RefineResult& paper, const Parameters& start, const FitSpec& spec,
                          const RefineOptions& options) {
  if (StopRequested(options)) return "stopped";
  if (!paper.has_values()) return "the paper model's fit has no values";
  if (Creeps(start)) return "the start has stick_creep already";
  if (spec.FindParameter(kPath) != nullptr) return "the spec frees it itself";
  for (const FitStage& stage : spec.stages) {
    if (stage.friction_replay) return "the spec replays the friction fit, an event-stick model";
  }
  // What the last stage frees: the creep fit refits that stage alone.
  const std::vector<std::string> named =
      spec.stages.empty() ? std::vector<std::string>{} : spec.stages.back().parameters;
  for (const FreeParameter& p : spec.parameters) {
    const bool in_last =
        named.empty() || std::find(named.begin(), named.end(), p.path) != named.end();
    if (in_last && p.path.rfind("friction.", 0) == 0) return "";
  }
  return "the spec's last stage frees no friction coefficient";
}

// The creep fit's line where it is not run, for `why`.
std::string NotRunLine(const std::string& why) {
  return "creep fit (" + std::string(kPath) + "): not run, " + why;
}

// The spec's last stage alone, without held-out runs (Refine validates the
// creep fit it keeps, once).
FitSpec LastStageOnly(const FitSpec& spec) {
  FitSpec last = spec;
  if (!last.stages.empty()) last.stages = {last.stages.back()};
  last.multistart = 0;
  last.hold_out.clear();
  return last;
}

// `held` with v freed too (in its last stage when that names its parameters).
FitSpec WithCreepFreed(const FitSpec& held) {
  FitSpec freed = held;
  const EffectParameterInfo& v = *FindEffectParameter(kPath);
  freed.parameters.push_back({kPath, v.plausible_min, v.plausible_max, ParameterScale::kLog});
  if (!freed.stages.empty() && !freed.stages.back().parameters.empty())
    freed.stages.back().parameters.push_back(kPath);
  return freed;
}

// `creep` told in the frame of the paper fit it replaces: the given start's
// costs, held-out runs and coefficient values, the paper fit's reports.
void InPaperFrame(const RefineResult& paper, RefineResult* creep) {
  FromCallersStart(paper, creep);
  creep->rescue_starts_tried = paper.rescue_starts_tried;
  creep->screen_report = paper.screen_report;
  creep->screened_candidates = paper.screened_candidates;
  creep->coordinate_report = paper.coordinate_report;
  creep->velocity_report = paper.velocity_report;
  creep->robust_report = paper.robust_report;
  creep->windowed_report = paper.windowed_report;
  creep->polish_report = paper.polish_report;
  creep->rounds_report = paper.rounds_report;
  creep->stages = paper.stages;
}

// The profile over the creep speed: each of options.stick_creep_profile held
// while `held` (the spec's last stage) is fitted with the `inner` options.
struct Profile {
  std::optional<RefineResult> best;  // the Better of the fits with values
  std::string report;                // " v m/s measure," per point
  int iterations = 0;                // of every fit
};

Profile FitProfile(const RefineResult& paper, const Unit& unit, const FitSpec& held,
                   const RefineOptions& inner, const RefineOptions& options) {
  Profile out;
  for (const double v : options.stick_creep_profile) {
    if (StopRequested(options)) break;
    Parameters from = paper.params;
    from.effects[kEffect]["v"] = v;
    RefineResult r = Refine(from, unit, held, inner);
    out.iterations += r.iterations;
    char item[64];
    std::snprintf(item, sizeof(item), " %.2g m/s %s,", v, MeasureText(r).c_str());
    out.report += item;
    if (r.has_values() && (!out.best || Better(r, *out.best))) out.best = std::move(r);
  }
  return out;
}

}  // namespace

RefineOptions InnerOptions(const RefineOptions& options) {
  RefineOptions inner = options;
  inner.fit_stick_creep = false;
  inner.screen_friction_starts = false;
  inner.screen_friction_windows = false;
  inner.coordinate_rounds = 0;
  inner.stribeck_velocity_divisor = 0;
  inner.robust_refit = false;
  inner.windowed_refit = false;
  inner.rescue_starts = 0;
  inner.windowed_polish = false;
  inner.rounds = 1;
  inner.write_start_unless_explained = false;  // its fits are compared as refined
  return inner;
}

std::string CreepNotRunReport(const RefineResult& paper, const Parameters& start,
                              const FitSpec& spec, const RefineOptions& options,
                              const std::string& because) {
  const std::string why = NotApplicable(paper, start, spec, options);
  return NotRunLine(why.empty() ? because : why);
}

RefineResult WithStickCreep(RefineResult paper, const Parameters& start, const Unit& unit,
                            const FitSpec& spec, const RefineOptions& options) {
  const std::string name = "creep fit (" + std::string(kPath) + ")";
  if (const std::string why = NotApplicable(paper, start, spec, options); !why.empty()) {
    paper.creep_report = NotRunLine(why);
    return paper;
  }
  const auto clock = std::chrono::steady_clock::now();
  RefineOptions inner = InnerOptions(options);
  // The prior of the paper fit's refinement (toward the component fits), not
  // one toward the paper fit: that fit is of the same runs, and its errors
  // are conditional on the stick the creep fit replaces.
  if (!inner.start_prior_centre)
    inner.start_prior_centre = std::make_shared<const Parameters>(start);
  const FitSpec held = LastStageOnly(spec);
  Profile profile = FitProfile(paper, unit, held, inner, options);
  std::string report = name + ", median reduced chi-square: v held at" + profile.report;
  std::optional<RefineResult>& best = profile.best;
  int iterations = profile.iterations;  // of the inner fits
  if (!best || StopRequested(options)) {
    paper.creep_report =
        report + (best ? " stopped" : " none with values") + "; the paper model's fit kept";
    paper.iterations += iterations;
    paper.creep_wall_time_s = SecondsSince(clock);
    return paper;
  }
  RefineResult free = Refine(best->params, unit, WithCreepFreed(held), inner);
  iterations += free.iterations;
  // Kept where it is Better (never a fit out of iterations over an explained
  // one) and explains the runs clearly better, or explains them where the
  // paper model does not.
  const auto keeps = [&](const RefineResult& c) {
    return Better(c, paper) &&
           (c.reduced_chi_square <= options.stick_creep_keep_ratio * paper.reduced_chi_square ||
            (c.explained() && !paper.explained()));
  };
  // The freed fit when Better, or within stick_creep_freed_ratio of the
  // profile's best with as good a status (a v of its own, with its standard
  // error, is worth that) unless that costs the creep fit its keep.
  const bool close =
      free.has_values() && free.status <= best->status &&
      free.reduced_chi_square <= options.stick_creep_freed_ratio * best->reduced_chi_square &&
      (keeps(free) || !keeps(*best));
  RefineResult& creep = close || Better(free, *best) ? free : *best;
  double fitted_v = 0;
  GetParameter(creep.params, kPath, &fitted_v);
  const bool better = Better(creep, paper);
  const bool keep = keeps(creep);
  char tail[256];
  std::snprintf(tail, sizeof(tail),
                " freed %s; v %.3g m/s (%s) at %s against the paper model's %s: %s",
                MeasureText(free).c_str(), fitted_v, &creep == &free ? "fitted" : "held",
                MeasureText(creep).c_str(), MeasureText(paper).c_str(),
                keep     ? "kept"
                : better ? "not kept (above the keep ratio)"
                         : "not kept (not better)");
  report += tail;
  if (!keep) {
    paper.creep_report = report;
    paper.iterations += iterations;
    paper.creep_wall_time_s = SecondsSince(clock);
    return paper;
  }
  if (&creep != &free) {
    ListHeldCreepSpeed(fitted_v,
                       "held at a point of the creep fit's profile (freed, the fit ended at " +
                           MeasureText(free) + " against " + MeasureText(creep) +
                           "); the other coefficients' errors are conditional on it",
                       &creep);
  }
  InPaperFrame(paper, &creep);
  creep.iterations = paper.iterations + iterations;
  creep.creep_report = report;
  creep.creep_wall_time_s = SecondsSince(clock);
  return std::move(creep);
}

void ListHeldCreepSpeed(double v_m_per_s, const std::string& why, RefineResult* creep) {
  FitResult held;
  held.status = FitStatus::kNotFitted;  // adds nothing to the status
  FittedCoefficient v;
  v.path = kPath;
  v.start = v.value = v_m_per_s;
  v.held = why;
  held.coefficients.push_back(v);
  const bool with_covariance =
      creep->covariance.rows() == static_cast<Eigen::Index>(creep->coefficients.size());
  AppendFit(held, "creep fit", creep);
  if (!with_covariance) creep->covariance.resize(0, 0);  // none stays none
}

}  // namespace pneumaid::refine_internal
