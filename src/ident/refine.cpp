#include "pneumaid/ident/refine.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "pneumaid/io/channel_noise.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/actuator.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/validate/logged_run.h"
#include "refine_attempts.h"
#include "refine_covariance.h"
#include "refine_creep.h"
#include "refine_provenance.h"
#include "refine_residual.h"
#include "refine_solve.h"
#include "refine_verdict.h"

// Refinement (refine.h): the checks of its inputs, its attempts in order
// (refine_attempts), and the result assembled from the fit kept: whole-run
// costs before and after, the start's values, the widening by the start's
// disagreement, provenance (refine_provenance), and the held-out validation
// before and after. Its parts: refine_attempts (the fit from the given start and the later
// attempts), refine_parameters (bounds map, multistart and trust-box points,
// the prior toward the start), refine_runs (runs and windows),
// refine_residual (the residual block), refine_solve (one stage's
// Levenberg-Marquardt), refine_covariance (uncertainty), refine_verdict (the
// stopping verdict), refine_friction_screen (friction starts read off the
// logs).
namespace pneumaid {
namespace {

using namespace refine_internal;

ValidationReport HeldOut(const Parameters& params, const Unit& unit,
                         const std::vector<const Experiment*>& held_out,
                         const RefineOptions& options) {
  if (held_out.empty()) return {};
  ValidationOptions v;
  v.simulation = options.validation;
  for (const Experiment* e : held_out) v.experiment_ids.push_back(e->entry.id);
  return ValidateUnit(params, unit, v);
}

// InputError for options or a spec (however it was made) that are not valid.
void CheckInputs(const FitSpec& spec, const RefineOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("refine options", 0, 0, error);
  if (!spec.IsValid(&error)) throw InputError(spec.Name(), 0, 0, error);
}

// InputError for a friction replay of a set whose rod creeps: the replay
// sticks the rod exactly (FitFriction), so it would fit a model the set does
// not use.
void CheckReplayModel(const Parameters& start, const FitSpec& spec) {
  for (size_t k = 0; k < spec.stages.size(); ++k) {
    if (!spec.stages[k].friction_replay) continue;
    for (const auto& [name, values] : start.effects) {
      const EffectInfo* effect = FindEffect(name);
      if (effect == nullptr || !effect->acts_on_friction) continue;
      throw InputError(spec.Name(), 0, 0,
                       "stages: stage " + std::to_string(k + 1) +
                           " replays friction under the paper's Stribeck law with exact stick, "
                           "and the start parameter set holds the " +
                           name + " effect (" + effect->doc +
                           "): expected no friction_replay stage for a set with " + name);
    }
  }
}

// RefineResult::noise_note: of the spec's channels that take the unit's noise.
std::string NoiseNote(const FitSpec& spec, const Unit& unit) {
  std::vector<std::string> from_unit;
  for (const auto& [channel, given] : spec.channels) {
    if (!(given.sigma > 0)) from_unit.push_back(channel);
  }
  return ChannelNoiseNote(unit, from_unit);
}

}  // namespace

bool RefineOptions::IsValid(std::string* error) const {
  const auto fail = [error](const char* what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (threads < 1) return fail("threads must be >= 1");
  if (!(function_tolerance > 0)) return fail("function_tolerance must be > 0");
  if (stall_iterations < 1) return fail("stall_iterations must be >= 1");
  if (!(stall_tolerance >= 0)) return fail("stall_tolerance must be >= 0");
  if (!(earlier_stage_stall_tolerance >= 0))
    return fail("earlier_stage_stall_tolerance must be >= 0");
  if (!(acceptable_reduced_chi_square >= 1))
    return fail("acceptable_reduced_chi_square must be >= 1");
  if (rescue_starts < 0) return fail("rescue_starts must be >= 0");
  if (screened_alternatives < 0) return fail("screened_alternatives must be >= 0");
  if (screen_windows_max < 0) return fail("screen_windows_max must be >= 0");
  if (coordinate_rounds < 0) return fail("coordinate_rounds must be >= 0");
  if (!(coordinate_span > 1)) return fail("coordinate_span must be > 1");
  if (!(coordinate_start_above >= 1)) return fail("coordinate_start_above must be >= 1");
  if (!(coordinate_start_keep_ratio > 0 && coordinate_start_keep_ratio <= 1))
    return fail("coordinate_start_keep_ratio must be in (0, 1]");
  if (!(rescue_box > 0 && rescue_box < 1)) return fail("rescue_box must be in (0, 1)");
  if (rounds < 1) return fail("rounds must be >= 1");
  if (!(misfit_window_s > 0)) return fail("misfit_window_s must be > 0");
  if (!(clustered_error_block_s >= 0)) return fail("clustered_error_block_s must be >= 0");
  if (cost_resolution_directions < 0) return fail("cost_resolution_directions must be >= 0");
  if (!(start_prior_errors > 0) || !(start_prior_fraction > 0))
    return fail("start_prior_errors and start_prior_fraction must be > 0");
  if (!(stick_creep_keep_ratio > 0 && stick_creep_keep_ratio <= 1))
    return fail("stick_creep_keep_ratio must be in (0, 1]");
  if (!(stick_creep_freed_ratio >= 1)) return fail("stick_creep_freed_ratio must be >= 1");
  const EffectParameterInfo& creep = *FindEffectParameter("effects.stick_creep.v");
  for (double v : stick_creep_profile) {
    if (!(v >= creep.plausible_min && v <= creep.plausible_max))
      return fail("stick_creep_profile: each creep speed must lie in the catalog's range");
  }
  if (!(stribeck_velocity_divisor == 0 || stribeck_velocity_divisor > 1))
    return fail("stribeck_velocity_divisor must be 0 (off) or > 1");
  if (!(out_of_reach_ratio == 0 || out_of_reach_ratio >= 1))
    return fail("out_of_reach_ratio must be 0 (never) or >= 1");
  if (!(correlation_flag > 0 && correlation_flag < 1)) {
    return fail("correlation_flag must be in (0, 1)");
  }
  // The two simulations' fields, named by which (as a caller sets them).
  for (const auto& [name, sim] :
       {std::make_pair("simulation", &simulation), std::make_pair("validation", &validation)}) {
    if (!sim->IsValid(error)) {
      if (error != nullptr) *error = std::string(name) + "." + *error;
      return false;
    }
  }
  return true;
}

namespace {

// `options` with the fitted runs' lag starts read at `start` (once for all
// of a refinement's attempts and inner fits), unless they have them.
RefineOptions WithLagStarts(const Parameters& start, const Unit& unit, const FitSpec& spec,
                            const RefineOptions& options) {
  if (options.lag_starts) return options;
  RefineOptions with = options;
  with.lag_starts = std::make_shared<const std::map<std::string, LagStart>>(
      ReadLagStarts(WithRigConditions(start, unit), unit, spec, options.simulation));
  return with;
}

// The fit of the spec's model (Refine without the creep fit) from `start`,
// or, for a later round, from `earlier`'s result, told of the caller's
// `start` as `earlier` was (FromCallersStart).
RefineResult RefineModel(const Parameters& start, const Unit& unit, const FitSpec& spec,
                         const RefineOptions& options, const RefineResult* earlier = nullptr) {
  const auto clock = std::chrono::steady_clock::now();
  const Parameters& from = earlier != nullptr ? earlier->params : start;
  CheckInputs(spec, options);
  CheckReplayModel(from, spec);
  const std::vector<FitStage> stages =
      spec.stages.empty() ? std::vector<FitStage>{FitStage{}} : spec.stages;
  Attempts attempts(from, unit, spec, stages, options);
  for (void (Attempts::*attempt)() :
       {&Attempts::ScreenFriction, &Attempts::CoordinateStart, &Attempts::VelocityStarts,
        &Attempts::RobustRefit, &Attempts::WindowedRefit, &Attempts::Rescue,
        &Attempts::WindowedPolish}) {
    if (StopRequested(options)) break;  // none after a stop
    (attempts.*attempt)();
  }
  StagedFit& fit = attempts.best();
  RefineResult& r = fit.result;
  r.screen_report = attempts.screen_report();
  r.screened_candidates = attempts.screened_candidates();
  r.coordinate_report = attempts.coordinate_report();
  r.velocity_report = attempts.velocity_report();
  r.robust_report = attempts.robust_report();
  r.windowed_report = attempts.windowed_report();
  r.polish_report = attempts.polish_report();
  const Parameters conditioned = WithRigConditions(start, unit);
  const auto held_out = Select(unit, spec, ExperimentList::kHoldOut, false);
  if (earlier != nullptr) {
    FromCallersStart(*earlier, &r);
  } else {
    std::vector<ExperimentCost> before = std::move(fit.before);
    r.initial_cost = fit.cost_before;
    // A windowed stage's costs are windows': report whole runs, as
    // validated (and at the caller's start when friction was replayed first
    // or the kept fit started elsewhere).
    if (fit.first_fit_windowed || stages.front().friction_replay || fit.from_moved_start) {
      before = WholeRunCosts(start, unit, spec, options);
      r.initial_cost = 0;
      for (const ExperimentCost& e : before) r.initial_cost += e.before;
    }
    for (ExperimentCost& e : r.fitted) {
      for (const ExperimentCost& b : before)
        if (b.id == e.id) e.before = b.before;
    }
    for (FittedCoefficient& p : r.coefficients) GetParameter(conditioned, p.path, &p.start);
    r.held_out_before = HeldOut(conditioned, unit, held_out, options);
  }
  // Only against component fits: a start refined before on these runs is no
  // experiment of its own.
  if (r.has_values() && options.start_disagreement_errors && !RefinedBefore(start))
    WidenByStartDisagreement(start, &r);
  r.stages = static_cast<int>(stages.size());  // before the entry, which records it
  if (r.has_values()) {
    r.params.provenance_yaml = WithRefineEntry(r.params.provenance_yaml, r, spec);
  }
  r.held_out_after = HeldOut(r.has_values() ? r.params : conditioned, unit, held_out, options);
  r.noise_note = NoiseNote(spec, unit);
  if (const PositionZero zero = ReadPositionZero(unit); zero.offset_m != 0)
    r.position_note = zero.note;
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
  return r;
}

// RefineOptions::rounds: the refinement again from its result while that
// is not explained, the Better result kept. The kept round's attempts (and
// their counts: starts, screened candidates, rescue starts) are the ones
// reported, its iterations the rounds' sum; what it says of the caller's
// start (the costs there, the coefficients' start values, the held-out runs
// before) is the first round's, and its errors are widened by the component
// fits' disagreement as the first round's were.
RefineResult LaterRounds(RefineResult r, const Parameters& start, const Unit& unit,
                         const FitSpec& spec, const RefineOptions& options) {
  std::string report;
  for (int round = 2; round <= options.rounds; ++round) {
    if (!r.has_values() || r.explained() || StopRequested(options)) break;
    const auto clock = std::chrono::steady_clock::now();
    // The prior toward the caller's start, as the first round's: centred on
    // the first round's result with its errors, it would count the runs twice.
    RefineOptions round_options = options;
    if (!round_options.start_prior_centre)
      round_options.start_prior_centre = std::make_shared<const Parameters>(start);
    RefineResult again = RefineModel(start, unit, spec, round_options, &r);
    const bool kept = refine_internal::Better(again, r);
    char line[200];
    std::snprintf(line, sizeof(line),
                  "round %d (the refinement again from the result so far): median reduced "
                  "chi-square %s against %s, %s",
                  round, refine_internal::MeasureText(again).c_str(),
                  refine_internal::MeasureText(r).c_str(),
                  kept ? "kept (the attempts above are its)" : "not kept");
    report += (report.empty() ? "" : "; ") + std::string(line) + refine_internal::Took(clock);
    if (!kept) {  // a next round would start from the same result
      r.iterations += again.iterations;
      break;
    }
    again.iterations += r.iterations;
    r = std::move(again);
  }
  r.rounds_report = report;
  // The entry records the rounds' counts (the iterations of all of them).
  if (!report.empty() && r.has_values())
    r.params.provenance_yaml = WithRefineEntry(r.params.provenance_yaml, r, spec);
  return r;
}

// The creep fit (RefineOptions::fit_stick_creep) after the paper model's
// fit `paper`; when kept, validated on the held-out runs (its inner fits
// are not) and widened by the component fits it started from, as the paper
// fit was.
RefineResult WithCreepFit(RefineResult paper, const Parameters& start, const Unit& unit,
                          const FitSpec& spec, const RefineOptions& options) {
  RefineResult r = WithStickCreep(std::move(paper), start, unit, spec, options);
  if (Creeps(r.params) && !Creeps(start)) {
    r.held_out_after =
        HeldOut(r.params, unit, Select(unit, spec, ExperimentList::kHoldOut, false), options);
    if (options.start_disagreement_errors && !RefinedBefore(start))
      WidenByStartDisagreement(start, &r);
  }
  if (r.has_values()) r.params.provenance_yaml = WithRefineEntry(r.params.provenance_yaml, r, spec);
  return r;
}

// RefineOptions::out_of_reach_ratio: the first round `first` ended "not
// explained" too far above the verdict's threshold for a later round or the
// creep fit, where a refined set not explained is not written.
bool OutOfReach(const RefineResult& first, const RefineOptions& options) {
  const bool later = options.rounds > 1 || options.fit_stick_creep;
  return later && options.out_of_reach_ratio > 0 && options.write_start_unless_explained &&
         first.status == FitStatus::kNotExplained && !StopRequested(options) &&
         first.reduced_chi_square >
             options.out_of_reach_ratio * options.acceptable_reduced_chi_square;
}

// The first round `first` as the result, the later rounds and the creep fit
// each reported as not run, with why.
void EndOutOfReach(const Parameters& start, const FitSpec& spec, const RefineOptions& options,
                   RefineResult* first) {
  char because[200];
  std::snprintf(because, sizeof(because),
                "the first round ends at a median reduced chi-square of %.3g, more than %g times "
                "the acceptable %.3g (out_of_reach_ratio)",
                first->reduced_chi_square, options.out_of_reach_ratio,
                options.acceptable_reduced_chi_square);
  if (options.rounds > 1) first->rounds_report = std::string("round 2: not run, ") + because;
  // The provenance entry with this line is written with the start
  // (WriteStartUnlessExplained: OutOfReach asks for it).
  if (options.fit_stick_creep)
    first->creep_report = CreepNotRunReport(*first, start, spec, options, because);
}

// RefineOptions::write_start_unless_explained: a refinement the verdict does
// not accept writes the start (under the unit's conditions, as validated
// before: held_out_before) with its own entries, and this refinement's as
// `refine_not_written`, with the refined values.
void WriteStartUnlessExplained(const Parameters& start, const Unit& unit, const FitSpec& spec,
                               RefineResult* r) {
  if (!r->has_values() || r->status != FitStatus::kNotExplained) return;
  r->params = WithRigConditions(start, unit);
  r->start_written = true;
  r->params.provenance_yaml = WithRefineEntry(r->params.provenance_yaml, *r, spec);
  r->held_out_after = r->held_out_before;
}

}  // namespace

RefineResult Refine(const Parameters& start, const Unit& unit, const FitSpec& spec,
                    const RefineOptions& given) {
  const auto clock = std::chrono::steady_clock::now();
  CheckInputs(spec, given);
  const RefineOptions options = WithLagStarts(start, unit, spec, given);
  RefineResult r = RefineModel(start, unit, spec, options);
  if (OutOfReach(r, options)) {
    EndOutOfReach(start, spec, options, &r);
  } else {
    r = LaterRounds(std::move(r), start, unit, spec, options);
    if (options.fit_stick_creep) r = WithCreepFit(std::move(r), start, unit, spec, options);
  }
  if (options.write_start_unless_explained) WriteStartUnlessExplained(start, unit, spec, &r);
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
  return r;
}

void CheckRefinable(const Parameters& start, const Unit& unit, const FitSpec& spec,
                    const RefineOptions& options) {
  CheckInputs(spec, options);
  CheckReplayModel(start, spec);
  // `start` is the prior: identify puts the unit's own constants (geometry
  // included) over it before the refinement, so the prior's geometry is no
  // reason to refuse.
  const Parameters conditioned = WithRigConditions(WithUnitConstants(start, unit), unit);
  CheckPathsIn(conditioned, spec);
  // The runs, their channels and sigmas (as logged: no lag start is read).
  FittedRuns(conditioned, unit, spec, false, nullptr);
}

RefineResult EvaluateFit(const Parameters& params, const Unit& unit, const FitSpec& spec,
                         const RefineOptions& given) {
  CheckInputs(spec, given);
  const RefineOptions options = WithLagStarts(params, unit, spec, given);
  RefineResult r;
  r.params = params;
  r.misfits = WholeRunMisfits(params, unit, spec, options);
  r.status = FitStatus::kConverged;  // provisional: the verdict decides
  Judge(options, &r);
  return r;
}

std::string RefineResult::CreepLine() const {
  return creep_report.empty() ? "" : creep_report + refine_internal::SecondsText(creep_wall_time_s);
}

std::string RefineResult::BriefReport() const {
  std::ostringstream out;
  char line[256];
  std::snprintf(line, sizeof(line),
                "Refinement: %s, cost %.6g -> %.6g, %d iterations in %d stage(s), %d start(s) "
                "(best: %d), %.2f s\n",
                ToString(status), initial_cost, final_cost, iterations, stages, starts, best_start,
                wall_time_s);
  out << line;
  if (!reason.empty()) out << "  " << reason << "\n";
  if (!misfits.empty()) {
    std::snprintf(line, sizeof(line),
                  "  verdict: median reduced chi-square over the runs %.3g (acceptable %.3g)%s\n",
                  reduced_chi_square, acceptable_reduced_chi_square,
                  rescue_starts_tried > 0 ? (", after " + std::to_string(rescue_starts_tried) +
                                             " starts around the start")
                                                .c_str()
                                          : "");
    out << line;
  }
  if (!noise_note.empty()) out << "  " << noise_note << "\n";
  if (!position_note.empty()) out << "  " << position_note << "\n";
  if (!screen_report.empty()) out << "  " << screen_report << "\n";
  if (!coordinate_report.empty()) out << "  " << coordinate_report << "\n";
  if (!velocity_report.empty()) out << "  " << velocity_report << "\n";
  if (!robust_report.empty()) out << "  " << robust_report << "\n";
  if (!windowed_report.empty()) out << "  " << windowed_report << "\n";
  if (!polish_report.empty()) out << "  " << polish_report << "\n";
  if (!rounds_report.empty()) out << "  " << rounds_report << "\n";
  if (!creep_report.empty()) out << "  " << CreepLine() << "\n";
  if (!replay_report.empty()) out << "  friction replay stage: " << replay_report;
  if (!estimated_starts.empty()) {
    double largest_sigma = 0, largest_Pa = 0;  // the largest move of either pressure
    for (const EstimatedStart& e : estimated_starts) {
      for (const auto& [sigmas, pascals] :
           {std::make_pair(e.p1_offset_sigma, e.p1_Pa - e.logged_p1_Pa),
            std::make_pair(e.p2_offset_sigma, e.p2_Pa - e.logged_p2_Pa)}) {
        if (std::fabs(sigmas) <= largest_sigma) continue;
        largest_sigma = std::fabs(sigmas);
        largest_Pa = std::fabs(pascals);
      }
    }
    std::snprintf(line, sizeof(line),
                  "  initial pressures of %zu run(s) estimated: largest move %.2g standard errors "
                  "(%.3g Pa) from the logged values\n",
                  estimated_starts.size(), largest_sigma, largest_Pa);
    out << line;
  }
  if (cost_resolution > 0) {
    std::snprintf(
        line, sizeof(line), "  standard errors include the cost's resolution, %.3g of the cost%s\n",
        cost_resolution, cost_resolution_measured ? " (measured one standard error out)" : "");
    out << line;
  }
  out << CoefficientReport("  ", correlation_flag);
  if (start_written) {
    out << "  written: the start's coefficients; the refined ones above absorb what the model "
           "lacks (provenance refine_not_written.refined)\n";
  }
  for (const ExperimentCost& e : fitted) {
    std::snprintf(line, sizeof(line), "  fitted   %-16s cost %.6g -> %.6g (%ld residuals)\n",
                  e.id.c_str(), e.before, e.after, e.residuals);
    out << line;
  }
  for (size_t i = 0; i < held_out_after.experiments.size(); ++i) {
    const auto& before = held_out_before.experiments[i];
    const auto& after = held_out_after.experiments[i];
    const auto rmse = [](const ExperimentValidation& e, const char* channel) {
      const auto found = e.channels.find(channel);
      return found == e.channels.end() ? NAN : found->second.rmse;
    };
    std::snprintf(line, sizeof(line),
                  "  held out %-16s x RMSE %.4g -> %.4g mm, p1 RMSE %.4g -> %.4g bar, p2 RMSE %.4g "
                  "-> %.4g bar",
                  after.id.c_str(), rmse(before, "x") * 1e3, rmse(after, "x") * 1e3,
                  rmse(before, "p1") * 1e-5, rmse(after, "p1") * 1e-5, rmse(before, "p2") * 1e-5,
                  rmse(after, "p2") * 1e-5);
    out << line;
    // A threshold missed in any channel, p2's or a flow's too, is said here.
    for (std::size_t k = 0; k < after.missed.size(); ++k)
      out << (k == 0 ? "; missed: " : "; ") << after.missed[k];
    out << "\n";
  }
  return out.str();
}

}  // namespace pneumaid
