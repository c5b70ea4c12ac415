#include "refine_attempts.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>

#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/validate/logged_run.h"
#include "refine_coordinate_start.h"
#include "refine_friction_screen.h"
#include "refine_parameters.h"
#include "refine_solve.h"
#include "refine_verdict.h"

namespace pneumaid::refine_internal {
namespace {

// FitStage::friction_replay: the identification's friction fit on the
// stroke logs, from the current friction; directions without slides keep it.
void ReplayFriction(const Unit& unit, Parameters* params, std::string* report) {
  const FrictionFitResult fit = FitFriction(unit, params->friction, FrictionFitOptions{});
  *report += fit.BriefReport();
  if (!fit.has_values()) return;
  const Parameters before = *params;
  fit.ApplyTo(params);  // a direction without slides holds the current values
  // The next stage's prior is centred on these values: with the replay's
  // errors, not those of the values they replace.
  for (const FittedCoefficient& c : fit.coefficients) {
    double was = c.value;
    GetParameter(before, c.path, &was);
    if (c.determined() && c.standard_error > 0)
      params->uncertainty[c.path] = c.standard_error;
    else if (c.value != was)
      params->uncertainty.erase(c.path);
  }
}

// The spec of one stage: its parameters only, in the order of `parameters`.
FitSpec StageSpec(const FitSpec& spec, const FitStage& stage) {
  FitSpec one = spec;
  one.stages.clear();
  if (stage.parameters.empty()) return one;  // all
  one.parameters.clear();
  for (const FreeParameter& p : spec.parameters) {
    if (std::count(stage.parameters.begin(), stage.parameters.end(), p.path)) {
      one.parameters.push_back(p);
    }
  }
  return one;
}

StagedFit FitStages(const Parameters& from, const Unit& unit, const FitSpec& spec,
                    const std::vector<FitStage>& stages, const RefineOptions& options,
                    bool robust_runs = false) {
  StagedFit out;
  RefineResult& r = out.result;
  Parameters current = from;
  out.before_last = from;
  int iterations = 0;
  bool first_fit = true;
  for (size_t k = 0; k < stages.size(); ++k) {
    if (stages[k].friction_replay) {
      ReplayFriction(unit, &current, &r.replay_report);
      continue;
    }
    const std::string replay_report = r.replay_report;
    out.before_last = current;
    r = RefineStage(current, unit, StageSpec(spec, stages[k]), stages[k].windows,
                    k + 1 == stages.size(), options, robust_runs);
    r.replay_report = replay_report;
    iterations += r.iterations;
    if (first_fit) {
      out.before = r.fitted;
      out.cost_before = r.initial_cost;
      out.first_fit_windowed = stages[k].windows;
      first_fit = false;
    }
    if (!r.has_values()) {
      r.reason = "stage " + std::to_string(k + 1) + ": " + r.reason;
      break;
    }
    current = r.params;
    if (StopRequested(options) && k + 1 < stages.size()) {
      // The later stages could not simulate: this stage's values, not converged.
      r.status = FitStatus::kNotConverged;
      r.reason = "stopped after stage " + std::to_string(k + 1);
      break;
    }
  }
  r.iterations = iterations;
  JudgeLastStage(stages.back(), unit, spec, options, &r);
  return out;
}

// `stages` with their last stage first by multiple shooting (windows),
// then as it is: restarted at every stuck phase, a slip at another instant
// cannot carry into the rest of a run, so a chaotic stick-slip no longer
// makes the cost rugged around the optimum. Nothing when the last stage is
// windowed already.
std::optional<std::vector<FitStage>> ShootingFirst(const std::vector<FitStage>& stages) {
  if (stages.back().windows) return std::nullopt;
  std::vector<FitStage> windowed = stages;
  FitStage shooting = stages.back();
  shooting.windows = true;
  windowed.insert(windowed.end() - 1, shooting);
  return windowed;
}

// A fit from a screened candidate: through `stages`, and, when
// `shooting_too` and that fit is not explained, through ShootingFirst(stages)
// as well, the Better of the two kept. Candidates ranked by windows (sweep,
// N = 40, seed 12): from the profiled search's best on sweep-01 the whole
// runs stall at 821 and the windows first reach 1.47, the truth's basin;
// from a next-best candidate on sweep-36 the whole runs reach 1.74 and the
// windows first stall above 250.
StagedFit FitCandidate(const Parameters& from, const Unit& unit, const FitSpec& spec,
                       const std::vector<FitStage>& stages, const RefineOptions& options,
                       bool shooting_too) {
  StagedFit fit = FitStages(from, unit, spec, stages, options);
  fit.from_moved_start = true;
  const std::optional<std::vector<FitStage>> windowed = ShootingFirst(stages);
  if (!shooting_too || fit.result.explained() || !windowed) return fit;
  StagedFit shooting = FitStages(from, unit, spec, *windowed, options);
  shooting.from_moved_start = true;
  shooting.shot_too = fit.shot_too = true;
  shooting.result.iterations += fit.result.iterations;
  if (Better(shooting.result, fit.result)) {
    shooting.by_windows_first = true;
    return shooting;
  }
  fit.result.iterations = shooting.result.iterations;
  return fit;
}

}  // namespace

void JudgeLastStage(const FitStage& last, const Unit& unit, const FitSpec& spec,
                    const RefineOptions& options, RefineResult* r) {
  if (last.windows && r->has_values()) {  // windows' costs and misfits: report whole runs
    const std::vector<RunResiduals> runs = WholeRunResiduals(r->params, unit, spec, options);
    r->misfits = MisfitsOf(runs, options.misfit_window_s);
    r->fitted = CostsOf(runs);
    r->final_cost = 0;
    for (const ExperimentCost& e : r->fitted) r->final_cost += e.after;
  }
  Judge(options, r);
}

bool Better(const RefineResult& a, const RefineResult& b) {
  if (!a.has_values()) return false;
  if (!b.has_values()) return true;
  if (a.explained() != b.explained()) return a.explained();
  const auto finite_or_huge = [](const RefineResult& r) {
    return std::isnan(r.reduced_chi_square) ? HUGE_VAL : r.reduced_chi_square;
  };
  return finite_or_huge(a) < finite_or_huge(b);
}

double SecondsSince(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

std::string MeasureText(const RefineResult& fit) {
  if (!fit.has_values()) return "no values";
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", fit.reduced_chi_square);
  return text;
}

std::string SecondsText(double seconds) {
  char line[40];
  std::snprintf(line, sizeof(line), "; %.1f s", seconds);
  return line;
}

std::string Took(std::chrono::steady_clock::time_point since) {
  return SecondsText(SecondsSince(since));
}

void FromCallersStart(const RefineResult& first, RefineResult* later) {
  later->initial_cost = first.initial_cost;
  for (ExperimentCost& e : later->fitted) {
    for (const ExperimentCost& f : first.fitted)
      if (f.id == e.id) e.before = f.before;
  }
  for (FittedCoefficient& c : later->coefficients) {
    for (const FittedCoefficient& f : first.coefficients)
      if (f.path == c.path) c.start = f.start;
  }
  later->held_out_before = first.held_out_before;
}

std::string WhyNotKept(const RefineResult& candidate, const RefineResult& kept) {
  if (!candidate.has_values()) return "its fit has no values";
  if (kept.explained() && !candidate.explained()) return "the fit kept before is explained";
  return "the fit kept before ends lower";
}

Attempts::Attempts(const Parameters& start, const Unit& unit, const FitSpec& spec,
                   const std::vector<FitStage>& stages, const RefineOptions& options)
    : start_(start),
      unit_(unit),
      spec_(spec),
      stages_(stages),
      options_(options),
      best_(FitStages(start, unit, spec, stages, options)),
      given_has_values_(best_.result.has_values()),
      given_before_last_(best_.before_last),
      moved_start_(start) {}

bool Attempts::Offer(StagedFit&& candidate, std::string* report) {
  const int iterations = best_.result.iterations + candidate.result.iterations;
  const bool better = Better(candidate.result, best_.result);
  if (better) {
    best_ = std::move(candidate);
    kept_report_ = report;
  }
  best_.result.iterations = iterations;
  return better;
}

void Attempts::ScreenFriction() {
  // A friction coefficient at a bound of its range (Fd and b at 0, vs at
  // 1 m/s: Coulomb friction passed off as Stribeck) is a basin the runs
  // tolerate but do not determine: screened like a stall, even when the
  // given start itself passes the verdict.
  const RefineResult& given = best_.result;
  const bool friction_at_bound =
      given.has_values() && std::any_of(given.coefficients.begin(), given.coefficients.end(),
                                        [](const FittedCoefficient& c) {
                                          return c.at_bound && c.path.rfind("friction.", 0) == 0;
                                        });
  if ((Explained() && !friction_at_bound) || !options_.screen_friction_starts) return;
  // The fit from the given start stalled (not explained, out of iterations
  // or nothing usable) or left friction at a bound: a start whose friction
  // is read off the logs may lie in the basin that explains the runs.
  ScreenWith(ScreenMeasure::kWholeRuns, friction_at_bound, &screen_report_);
  // Still not explained: the candidates ranked by the windows, where an error
  // of one direction's friction does not carry into the other's slides (with
  // both directions off, the whole runs hide the basin of each).
  if (!Explained() && options_.screen_friction_windows && !StopRequested(options_)) {
    ScreenWith(ScreenMeasure::kWindows, false, &windows_screen_report_);
  }
}

std::string Attempts::screen_report() const {
  if (screen_report_.empty() || windows_screen_report_.empty())
    return screen_report_ + windows_screen_report_;
  return screen_report_ + "\n  " + windows_screen_report_;
}

void Attempts::ScreenWith(ScreenMeasure measure, bool even_if_explained, std::string* report) {
  const auto clock = std::chrono::steady_clock::now();
  FrictionScreen screen = ScreenFrictionStarts(start_, unit_, spec_, options_, even_if_explained,
                                               options_.screened_alternatives, measure);
  screened_candidates_ += screen.candidates;
  *report = screen.report;
  if (!screen.moved) {
    *report += Took(clock);
    return;
  }
  *report += "; screened in" + Took(clock).substr(1);  // the fits from its candidates follow
  const Parameters previous_start = moved_start_;
  const bool previous_shot = moved_start_shot_;
  moved_start_ = std::move(screen.start);
  // Candidates ranked by windows are fitted by windows first too (with
  // windowed_refit on) where the whole runs do not explain the logs.
  const bool shooting_too = measure == ScreenMeasure::kWindows && options_.windowed_refit;
  // Offers the fit from a candidate; true when kept.
  bool by_windows_first = false;
  std::string why_not;  // the last candidate not kept
  const auto offer = [&](const Parameters& from) {
    StagedFit fit = FitCandidate(from, unit_, spec_, stages_, options_, shooting_too);
    const bool shot = fit.shot_too, first = fit.by_windows_first;
    why_not = WhyNotKept(fit.result, best_.result);
    if (!Offer(std::move(fit), report)) return false;
    moved_start_shot_ = shot;
    by_windows_first = first;
    return true;
  };
  bool kept = offer(moved_start_);
  if (!kept) *report += "; not kept: " + why_not;
  // Not explained from the best candidate either: the next-best ones.
  int tried = 0, kept_alternative = 0;
  for (Parameters& alternative : screen.alternatives) {
    if (Explained() || StopRequested(options_)) break;
    ++tried;
    if (offer(alternative)) {
      kept_alternative = tried;
      kept = true;
      moved_start_ = std::move(alternative);
    }
  }
  if (tried > 0) {
    std::string which;
    if (kept_alternative > 0) {
      which = ", the fit from candidate " + std::to_string(kept_alternative + 1);
      if (kept_alternative - 1 == screen.profiled_alternative) which += " (the profiled search's)";
      which += " kept";
    }
    *report += "; " + std::to_string(tried) + " next-best candidate(s) fitted" +
               (kept_alternative > 0 ? which : ", none ended lower");
  }
  if (kept && by_windows_first) *report += ", its fit by windows first";
  *report += Took(clock);
  // The later attempts start from the screened start: the whole runs'
  // screen's even when its fit was not kept (its best candidate by the
  // verdict's own measure), the windows' only when its fit was.
  if (kept || measure == ScreenMeasure::kWholeRuns) {
    moved_ = true;
  } else {
    moved_start_ = previous_start;
    moved_start_shot_ = previous_shot;
  }
}

void Attempts::CoordinateStart() {
  // A spec whose first stage replays the friction fit would refit the moved
  // coefficients before any simulation fit: nothing to search for.
  if (ExplainedNearNoise() || options_.coordinate_rounds <= 0 || stages_.front().friction_replay)
    return;
  const auto clock = std::chrono::steady_clock::now();
  // Neither start explains the runs, or the kept fit is well above the
  // noise: the given one with one friction coefficient at a time moved (the
  // others the component fits').
  CoordinateSearch moved = SearchFrictionCoordinates(start_, unit_, spec_, options_);
  if (!moved.moved) {
    coordinate_report_ = moved.report + Took(clock);
    return;
  }
  const double before = best_.result.reduced_chi_square;
  const std::string before_text = MeasureText(best_.result);
  StagedFit candidate = FitStages(moved.start, unit_, spec_, stages_, options_);
  candidate.from_moved_start = true;
  const std::string after_text = MeasureText(candidate.result);
  const bool clear_gain = ClearGain(candidate.result);
  if (!clear_gain) best_.result.iterations += candidate.result.iterations;
  const bool small_gain =
      !clear_gain && candidate.result.has_values() && candidate.result.reduced_chi_square < before;
  const bool kept = clear_gain && Offer(std::move(candidate), &coordinate_report_);
  if (kept) {
    moved_start_ = std::move(moved.start);
    moved_start_shot_ = false;
    moved_ = true;
  }
  char line[160];
  std::snprintf(line, sizeof(line), "; the fit from it: %s against %s, %s", after_text.c_str(),
                before_text.c_str(),
                kept         ? "kept"
                : small_gain ? "not kept (explained before, no clear gain)"
                             : "not kept");
  coordinate_report_ = moved.report + line + Took(clock);
}

bool Attempts::ExplainedNearNoise() const {
  return Explained() && best_.result.reduced_chi_square <= options_.coordinate_start_above;
}

bool Attempts::ClearGain(const RefineResult& candidate) const {
  return !Explained() || (candidate.has_values() &&
                          candidate.reduced_chi_square <= options_.coordinate_start_keep_ratio *
                                                              best_.result.reduced_chi_square);
}

void Attempts::VelocityStarts() {
  if (ExplainedNearNoise() || stages_.front().friction_replay) return;
  const auto clock = std::chrono::steady_clock::now();
  const std::vector<VelocityStart> starts =
      StribeckVelocityStarts(start_, spec_, options_.stribeck_velocity_divisor);
  if (starts.empty()) return;
  char line[200];
  std::snprintf(line, sizeof(line),
                "Stribeck velocity starts (the given start's vs divided by %g), median reduced "
                "chi-square against %s:",
                options_.stribeck_velocity_divisor, MeasureText(best_.result).c_str());
  std::string report = line, which;
  for (const VelocityStart& v : starts) {
    // The first kept and explained below coordinate_start_above: done.
    if (StopRequested(options_) || ExplainedNearNoise()) break;
    StagedFit candidate = FitStages(v.start, unit_, spec_, stages_, options_);
    candidate.from_moved_start = true;
    report += " " + v.direction + " " + MeasureText(candidate.result);
    if (!ClearGain(candidate.result)) {
      best_.result.iterations += candidate.result.iterations;
      continue;
    }
    if (!Offer(std::move(candidate), &velocity_report_)) continue;
    which += (which.empty() ? "the " : ", then the ") + v.direction + " kept";
    moved_start_ = v.start;
    moved_start_shot_ = false;
    moved_ = true;
  }
  velocity_report_ = report + "; " + (which.empty() ? "none kept" : which) + Took(clock);
}

void Attempts::Refit(const char* what, const std::vector<FitStage>& stages, bool robust_runs,
                     std::string* report) {
  const auto clock = std::chrono::steady_clock::now();
  const std::string before = MeasureText(best_.result);
  StagedFit candidate = FitStages(moved_start_, unit_, spec_, stages, options_, robust_runs);
  candidate.from_moved_start = moved_;
  const std::string after = MeasureText(candidate.result);
  const bool kept = Offer(std::move(candidate), report);
  char line[200];
  std::snprintf(line, sizeof(line), "%s: median reduced chi-square %s against %s, %s", what,
                after.c_str(), before.c_str(), kept ? "kept" : "not kept");
  *report = line + Took(clock);
}

void Attempts::RobustRefit() {
  if (Explained() || !options_.robust_refit) return;
  // A run the model cannot follow may be dragging the others: each run
  // through a Cauchy loss.
  Refit("robust refit (each run through a Cauchy loss)", stages_, true, &robust_report_);
}

void Attempts::WindowedRefit() {
  const std::optional<std::vector<FitStage>> windowed = ShootingFirst(stages_);
  if (Explained() || !options_.windowed_refit || !windowed) return;
  if (moved_start_shot_) {
    windowed_report_ =
        "windowed refit (the last stage by multiple shooting first): not run, the screened start "
        "was fitted so already";
    return;
  }
  Refit("windowed refit (the last stage by multiple shooting first)", *windowed, false,
        &windowed_report_);
}

void Attempts::Rescue() {
  RefineResult& r = best_.result;
  if (Explained() || !r.has_values() || options_.rescue_starts <= 0) return;
  // Stalled far above what the noise explains: the last stage again (from
  // what it started from in the fit from the given start, earlier stages
  // included; the kept fit's when that one found nothing) from starts in a
  // trust box around the given start's values (the component fits, not the
  // whole bounds), those alone. Only the result is replaced: the kept fit's
  // record of its start stays.
  const FitStage& last_stage = stages_.back();
  const FitSpec last = StageSpec(spec_, last_stage);
  const Parameters conditioned = WithRigConditions(start_, unit_);
  const ParameterMap map = MakeParameterMap(conditioned, last);
  RefineResult rescue = RefineStage(
      given_has_values_ ? given_before_last_ : best_.before_last, unit_, last, last_stage.windows,
      true, options_, false,
      TrustBox(map, conditioned, options_.rescue_starts, options_.rescue_box, spec_.seed),
      /*extra_starts_only=*/true);
  JudgeLastStage(last_stage, unit_, spec_, options_, &rescue);
  const int iterations = r.iterations + rescue.iterations;
  const int tried = rescue.starts;
  if (Better(rescue, r)) {
    rescue.replay_report = r.replay_report;
    r = rescue;
    if (kept_report_ != nullptr) *kept_report_ += "; a rescue start then ended lower";
  }
  r.rescue_starts_tried = tried;
  r.iterations = iterations;
}

void Attempts::WindowedPolish() {
  const std::optional<std::vector<FitStage>> windowed = ShootingFirst({stages_.back()});
  if (Explained() || !options_.windowed_polish || !windowed || !best_.result.has_values()) return;
  const auto clock = std::chrono::steady_clock::now();
  const std::string before = MeasureText(best_.result);
  StagedFit candidate = FitStages(best_.result.params, unit_, spec_, *windowed, options_);
  candidate.from_moved_start = true;
  // What the kept fit's attempts recorded stays (as the rescue keeps it).
  candidate.result.replay_report = best_.result.replay_report;
  candidate.result.rescue_starts_tried = best_.result.rescue_starts_tried;
  const std::string after = MeasureText(candidate.result);
  const bool kept = Offer(std::move(candidate), &polish_report_);
  char line[200];
  std::snprintf(line, sizeof(line),
                "windowed polish (the kept fit's last stage again from its result, by multiple "
                "shooting first): median reduced chi-square %s against %s, %s",
                after.c_str(), before.c_str(), kept ? "kept" : "not kept");
  polish_report_ = line + Took(clock);
}

}  // namespace pneumaid::refine_internal
