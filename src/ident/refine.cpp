#include "pneumaid/ident/refine.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "../io/provenance_map.h"
#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/provenance.h"
#include "pneumaid/model/parameter_table.h"
#include "refine_covariance.h"
#include "refine_friction_screen.h"
#include "refine_residual.h"
#include "refine_solve.h"
#include "refine_verdict.h"

// Refinement's orchestration: stages (friction replay, windows, parameter
// subsets) in order; the order of attempts (the fit from the given start;
// when it is not explained or leaves friction at a bound, the friction
// screen and a fit from its start; when still not explained, a robust refit,
// a windowed refit and then the rescue starts; the Better one kept at each step); the
// held-out validation before and after, provenance.
// Its parts: refine_parameters (bounds map, multistart and trust-box points,
// the prior toward the start), refine_runs (runs and windows),
// refine_residual (the residual block), refine_solve (one stage's
// Levenberg-Marquardt), refine_covariance (uncertainty), refine_verdict (the
// stopping verdict).
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

// Whether the set was already refined: its standard errors then come from
// a fit of the same runs, not from the component fits' own experiments.
bool RefinedBefore(const Parameters& start) {
  return HasProvenanceEntry(start.provenance_yaml, "refine");
}

// The start's provenance with this refinement's entry `refine` (replacing
// any earlier one: a mapping has one key of a name), in flow style.
std::string AppendProvenance(const std::string& provenance, const RefineResult& r,
                             const FitSpec& spec) {
  YAML::Node entry(YAML::NodeType::Map);
  entry["spec"] = spec.source;
  entry["cost_before"] = r.initial_cost;
  entry["cost_after"] = r.final_cost;
  entry["iterations"] = r.iterations;
  entry["stages"] = r.stages;
  entry["starts"] = r.starts;
  entry["experiments"] = r.fitted.size();
  entry["initial_pressures"] = spec.fit_initial_pressures ? "fit" : "logged";
  entry["status"] = ToString(r.status);
  entry["reduced_chi_square"] = r.reduced_chi_square;
  entry["acceptable_reduced_chi_square"] = r.acceptable_reduced_chi_square;
  entry["converged"] = r.status == FitStatus::kConverged;
  // Fitted, but on a bound of its range: no standard error, so no entry in
  // `uncertainty` (a reader would otherwise take it for the prior's).
  YAML::Node at_bound(YAML::NodeType::Sequence);
  for (const FittedCoefficient& c : r.coefficients)
    if (c.at_bound) at_bound.push_back(c.path);
  entry["at_bound"] = at_bound;
  return WithProvenanceEntry(provenance, "refine", entry);
}

// FitStage::friction_replay: the identification's friction fit on the
// stroke logs, from the current friction; directions without slides keep it.
void ReplayFriction(const Unit& unit, Parameters* params, std::string* report) {
  const FrictionFitResult fit = FitFriction(unit, params->friction, FrictionFitOptions{});
  *report += fit.BriefReport();
  fit.ApplyTo(params);  // a direction without slides holds the current values
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

// InputError for options or a spec (however it was made) that are not valid.
void CheckInputs(const FitSpec& spec, const RefineOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("refine options", 0, 0, error);
  if (!spec.IsValid(&error)) {
    throw InputError(spec.source.empty() ? "fit spec" : spec.source, 0, 0, error);
  }
}

// The verdict on a fit's last stage: a windowed stage's runs are judged
// whole, from their logged starts.
void JudgeLastStage(const FitStage& last, const Unit& unit, const FitSpec& spec,
                    const RefineOptions& options, RefineResult* r) {
  if (last.windows && r->has_values()) {
    r->misfits = WholeRunMisfits(r->params, unit, spec, options);
  }
  Judge(options, r);
}

// One fit through every stage from `from`, judged by the verdict.
struct StagedFit {
  RefineResult result;
  Parameters before_last;              // what the last stage started from
  std::vector<ExperimentCost> before;  // the first fitted stage's costs at its start
  double cost_before = 0;
  bool first_fit_windowed = false;   // `before` and `cost_before` are windows'
  bool from_screened_start = false;  // else from the caller's start
};

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
  }
  r.iterations = iterations;
  JudgeLastStage(stages.back(), unit, spec, options, &r);
  return out;
}

// Whether fit `a` is better than `b`: explained first, then any with values
// by the lower median (NaN, no run simulated, counts as infinite), nothing
// usable last.
bool Better(const RefineResult& a, const RefineResult& b) {
  if (!a.has_values()) return false;
  if (!b.has_values()) return true;
  const bool a_explained = a.status == FitStatus::kConverged;
  const bool b_explained = b.status == FitStatus::kConverged;
  if (a_explained != b_explained) return a_explained;
  const auto median = [](const RefineResult& r) {
    return std::isnan(r.reduced_chi_square) ? HUGE_VAL : r.reduced_chi_square;
  };
  return median(a) < median(b);
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
  if (!(rescue_box > 0 && rescue_box < 1)) return fail("rescue_box must be in (0, 1)");
  if (!(misfit_window_s > 0)) return fail("misfit_window_s must be > 0");
  if (!(clustered_error_block_s >= 0)) return fail("clustered_error_block_s must be >= 0");
  if (cost_resolution_directions < 0) return fail("cost_resolution_directions must be >= 0");
  if (!(start_prior_errors > 0) || !(start_prior_fraction > 0))
    return fail("start_prior_errors and start_prior_fraction must be > 0");
  if (!(correlation_flag > 0 && correlation_flag < 1)) {
    return fail("correlation_flag must be in (0, 1)");
  }
  return simulation.IsValid(error);
}

RefineResult Refine(const Parameters& start, const Unit& unit, const FitSpec& spec,
                    const RefineOptions& options) {
  const auto clock = std::chrono::steady_clock::now();
  CheckInputs(spec, options);
  const std::vector<FitStage> stages =
      spec.stages.empty() ? std::vector<FitStage>{FitStage{}} : spec.stages;
  StagedFit fit = FitStages(start, unit, spec, stages, options);
  const bool given_has_values = fit.result.has_values();
  const Parameters given_before_last = fit.before_last;
  std::string screen_report, robust_report, windowed_report;
  std::string* kept_report = nullptr;  // the report of the later attempt kept, if any
  int screened_candidates = 0;
  // Keeps `candidate` when it is Better; the iterations add up either way.
  const auto keep_better = [&fit](StagedFit&& candidate) {
    const int iterations = fit.result.iterations + candidate.result.iterations;
    const bool better = Better(candidate.result, fit.result);
    if (better) fit = std::move(candidate);
    fit.result.iterations = iterations;
    return better;
  };
  const auto explained = [&fit] { return fit.result.status == FitStatus::kConverged; };
  // A friction coefficient at a bound of its range (Fd and b at 0, vs at
  // 1 m/s: Coulomb friction passed off as Stribeck) is a basin the runs
  // tolerate but do not determine: screened like a stall, even when the
  // given start itself passes the verdict.
  const bool friction_at_bound =
      fit.result.has_values() &&
      std::any_of(fit.result.coefficients.begin(), fit.result.coefficients.end(),
                  [](const FittedCoefficient& c) {
                    return c.at_bound && c.path.rfind("friction.", 0) == 0;
                  });
  Parameters screened_start = start;
  bool screened = false;  // screened_start differs from start
  if ((!explained() || friction_at_bound) && options.screen_friction_starts) {
    // The fit from the given start stalled (not explained, out of
    // iterations or nothing usable) or left friction at a bound: a start
    // whose friction is read off the logs may lie in the basin that explains
    // the runs.
    FrictionScreen screen = ScreenFrictionStarts(start, unit, spec, options, friction_at_bound,
                                                 options.screened_alternatives);
    screen_report = screen.report;
    screened_candidates = screen.candidates;
    if (!screen_report.empty()) {
      screened_start = std::move(screen.start);
      screened = true;
      StagedFit from_screened = FitStages(screened_start, unit, spec, stages, options);
      from_screened.from_screened_start = true;
      if (keep_better(std::move(from_screened))) {
        kept_report = &screen_report;
      } else {
        screen_report += "; not kept: the fit from the given start ends lower";
      }
      // Not explained from the best candidate either: the next-best ones.
      int tried = 0, kept = 0;
      for (Parameters& alternative : screen.alternatives) {
        if (explained()) break;
        ++tried;
        StagedFit from_alternative = FitStages(alternative, unit, spec, stages, options);
        from_alternative.from_screened_start = true;
        if (keep_better(std::move(from_alternative))) {
          kept_report = &screen_report;
          kept = tried;
          screened_start = std::move(alternative);
        }
      }
      if (tried > 0) {
        screen_report +=
            "; " + std::to_string(tried) + " next-best candidate(s) fitted" +
            (kept > 0 ? ", the fit from candidate " + std::to_string(kept + 1) + " kept"
                      : ", none ended lower");
      }
    }
  }
  // One more fit from the screened start (the given one when the screen
  // moved nothing) through `fit_stages`, kept when Better; its one-line report.
  const auto refit = [&](const char* what, const std::vector<FitStage>& fit_stages,
                         bool robust_runs, std::string* report) {
    const double before = fit.result.reduced_chi_square;
    StagedFit candidate = FitStages(screened_start, unit, spec, fit_stages, options, robust_runs);
    candidate.from_screened_start = screened;
    const double after = candidate.result.reduced_chi_square;
    const bool kept = keep_better(std::move(candidate));
    if (kept) kept_report = report;
    char line[200];
    std::snprintf(line, sizeof(line), "%s: median reduced chi-square %.3g against %.3g, %s", what,
                  after, before, kept ? "kept" : "not kept");
    *report = line;
  };
  if (!explained() && options.robust_refit) {
    // Still not explained: a run the model cannot follow may be dragging the
    // others. Each run through a Cauchy loss.
    refit("robust refit (each run through a Cauchy loss)", stages, true, &robust_report);
  }
  if (!explained() && options.windowed_refit && !stages.back().windows) {
    // Still not explained: the last stage first by multiple shooting.
    // Restarted at every stuck phase, a slip at another instant cannot carry
    // into the rest of the run, so a chaotic stick-slip no longer makes the
    // cost rugged around the optimum; the whole runs are fitted after.
    std::vector<FitStage> windowed = stages;
    FitStage shooting = stages.back();
    shooting.windows = true;
    windowed.insert(windowed.end() - 1, shooting);
    refit("windowed refit (the last stage by multiple shooting first)", windowed, false,
          &windowed_report);
  }
  RefineResult& r = fit.result;
  if (!explained() && r.has_values() && options.rescue_starts > 0) {
    // Stalled far above what the noise explains: the last stage again (from
    // what it started from in the fit from the given start, earlier stages
    // included; the kept fit's when that one found nothing) from starts in a
    // trust box around the given start's values (the component fits, not the
    // whole bounds), those alone.
    const FitSpec last = StageSpec(spec, stages.back());
    const Parameters conditioned = WithRigConditions(start, unit);
    const ParameterMap map = MakeParameterMap(conditioned, last);
    RefineResult rescue = RefineStage(
        given_has_values ? given_before_last : fit.before_last, unit, last, stages.back().windows,
        true, options, false,
        TrustBox(map, conditioned, options.rescue_starts, options.rescue_box, spec.seed),
        /*extra_starts_only=*/true);
    JudgeLastStage(stages.back(), unit, spec, options, &rescue);
    const int iterations = r.iterations + rescue.iterations;
    const int tried = rescue.starts;
    if (Better(rescue, r)) {
      rescue.replay_report = r.replay_report;
      r = rescue;
      if (kept_report != nullptr) *kept_report += "; a rescue start then ended lower";
    }
    r.rescue_starts = tried;
    r.iterations = iterations;
  }
  std::vector<ExperimentCost> before = std::move(fit.before);
  double cost_before = fit.cost_before;
  // A windowed stage's costs are windows': report whole runs, as validated
  // (and at the caller's start when friction was replayed first or the kept
  // fit started elsewhere).
  if (fit.first_fit_windowed || stages.front().friction_replay || fit.from_screened_start) {
    before = WholeRunCosts(start, unit, spec, options);
    cost_before = 0;
    for (const ExperimentCost& e : before) cost_before += e.before;
  }
  if (stages.back().windows && r.has_values()) {
    r.fitted = WholeRunCosts(r.params, unit, spec, options);
    r.final_cost = 0;
    for (const ExperimentCost& e : r.fitted) r.final_cost += e.after;
  }
  r.initial_cost = cost_before;
  r.screen_report = screen_report;
  r.screened_candidates = screened_candidates;
  r.robust_report = robust_report;
  r.windowed_report = windowed_report;
  for (size_t k = 0; k < r.fitted.size() && k < before.size(); ++k) {
    r.fitted[k].before = before[k].before;
  }
  const Parameters conditioned = WithRigConditions(start, unit);
  for (FittedCoefficient& p : r.coefficients) GetParameter(conditioned, p.path, &p.start);
  // Only against component fits: a start refined before on these runs is no
  // experiment of its own.
  if (r.has_values() && options.start_disagreement_errors && !RefinedBefore(start))
    WidenByStartDisagreement(start, &r);
  if (r.has_values()) {
    r.params.provenance_yaml = AppendProvenance(r.params.provenance_yaml, r, spec);
  }
  const auto held_out = Select(unit, spec.hold_out, spec, false);
  r.held_out_before = HeldOut(conditioned, unit, held_out, options);
  r.held_out_after = HeldOut(r.has_values() ? r.params : conditioned, unit, held_out, options);
  r.stages = static_cast<int>(stages.size());
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
  return r;
}

RefineResult EvaluateFit(const Parameters& params, const Unit& unit, const FitSpec& spec,
                         const RefineOptions& options) {
  CheckInputs(spec, options);
  RefineResult r;
  r.params = params;
  r.misfits = WholeRunMisfits(params, unit, spec, options);
  r.status = FitStatus::kConverged;  // provisional: the verdict decides
  Judge(options, &r);
  return r;
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
    std::snprintf(
        line, sizeof(line),
        "  verdict: median reduced chi-square over the runs %.3g (acceptable %.3g)%s\n",
        reduced_chi_square, acceptable_reduced_chi_square,
        rescue_starts > 0
            ? (", after " + std::to_string(rescue_starts) + " starts around the start").c_str()
            : "");
    out << line;
  }
  if (!screen_report.empty()) out << "  " << screen_report << "\n";
  if (!robust_report.empty()) out << "  " << robust_report << "\n";
  if (!windowed_report.empty()) out << "  " << windowed_report << "\n";
  if (!replay_report.empty()) out << "  friction replay stage: " << replay_report;
  if (estimated_starts > 0) {
    std::snprintf(line, sizeof(line),
                  "  initial pressures of %d run(s) estimated: largest move %.2g standard errors "
                  "(%.3g Pa) from the logged values\n",
                  estimated_starts, largest_start_offset_sigma, largest_start_offset_Pa);
    out << line;
  }
  if (cost_resolution > 0) {
    std::snprintf(
        line, sizeof(line), "  standard errors include the cost's resolution, %.3g of the cost%s\n",
        cost_resolution, cost_resolution_measured ? " (measured one standard error out)" : "");
    out << line;
  }
  out << CoefficientReport("  ", correlation_flag);
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
                  "  held out %-16s x RMSE %.4g -> %.4g mm, p1 RMSE %.4g -> %.4g bar\n",
                  after.id.c_str(), rmse(before, "x") * 1e3, rmse(after, "x") * 1e3,
                  rmse(before, "p1") * 1e-5, rmse(after, "p1") * 1e-5);
    out << line;
  }
  return out.str();
}

}  // namespace pneumaid
