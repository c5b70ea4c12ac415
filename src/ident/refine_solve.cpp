#include "refine_solve.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <string>

#include "pneumaid/model/parameter_table.h"
#include "pneumaid/validate/validate.h"
#include "quiet_solver.h"
#include "refine_covariance.h"
#include "refine_verdict.h"

namespace pneumaid::refine_internal {

bool StopRequested(const RefineOptions& options) {
  return options.simulation.stop != nullptr && options.simulation.stop->load();
}

void LogQuietly(const std::function<void(const std::string&)>& log, const std::string& line) {
  try {
    log(line);
  } catch (...) {
    // The caller's sink failed: its line is lost, the fit goes on (never
    // throw through Ceres).
  }
}

ceres::CallbackReturnType ProgressCallback::operator()(const ceres::IterationSummary& summary) {
  char line[200];
  std::snprintf(line, sizeof(line),
                "iteration %3d: cost %.6e, change %.3e, |step| %.3e, radius %.3e, %s, %.2f s",
                summary.iteration, summary.cost, summary.cost_change, summary.step_norm,
                summary.trust_region_radius, summary.step_is_successful ? "accepted" : "rejected",
                summary.cumulative_time_in_seconds);
  LogQuietly(log_, line);
  return ceres::SOLVER_CONTINUE;
}

ceres::Solver::Options SolverOptions(const FitSpec& spec, const RefineOptions& options) {
  ceres::Solver::Options s = internal::QuietSolverOptions();
  s.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  s.linear_solver_type = ceres::DENSE_QR;
  s.max_num_iterations = spec.max_iterations;
  s.num_threads = options.threads;
  s.function_tolerance = options.function_tolerance;
  return s;
}

// An estimated start: the logged and the fitted initial pressures.
void RecordStartOffset(const FitExperiment& e, const StartOffsets& offsets, RefineResult* r) {
  EstimatedStart start;
  start.run = e.id;
  start.logged_p1_Pa = e.initial.p1_Pa;
  start.logged_p2_Pa = e.initial.p2_Pa;
  start.p1_offset_sigma = offsets[0];
  start.p2_offset_sigma = offsets[1];
  start.p1_Pa = e.initial.p1_Pa + offsets[0] * e.start_sigma_Pa[0];
  start.p2_Pa = e.initial.p2_Pa + offsets[1] * e.start_sigma_Pa[1];
  r->estimated_starts.push_back(start);
}

namespace {

// One stage's Ceres problem: a residual block per fitted run (or window),
// each through the Cauchy loss of a robust refit (its scale a^2 in
// run_scale; 0: plain least squares), then the weak prior toward its centre
// (the start, or RefineOptions::start_prior_centre; after the runs: Ceres' cost includes it, the
// costs reported are the runs').
void BuildProblem(const Parameters& conditioned, const ParameterMap& map,
                  const std::vector<FitExperiment>& experiments, const StartPrior& prior,
                  const RefineOptions& options, bool robust_runs, Problem* p,
                  std::vector<double>* run_scale) {
  p->theta = map.ThetaOf(conditioned);
  p->offsets.assign(experiments.size(), StartOffsets{0, 0});  // never reallocated below
  for (size_t k = 0; k < experiments.size(); ++k) {
    const FitExperiment& e = experiments[k];
    auto* block =
        new ExperimentResidual(&conditioned, &map, &e, &options.simulation, options.jacobian);
    run_scale->push_back(robust_runs ? options.acceptable_reduced_chi_square *
                                           static_cast<double>(std::max(e.residuals(), 1L))
                                     : 0.0);
    ceres::LossFunction* loss =
        robust_runs ? new ceres::CauchyLoss(std::sqrt(run_scale->back())) : nullptr;
    if (e.FitsStart()) {
      p->problem.AddResidualBlock(block, loss, p->theta.data(), p->offsets[k].data());
    } else {
      p->problem.AddResidualBlock(block, loss, p->theta.data());
    }
    p->blocks.push_back(block);
  }
  if (options.start_prior) {
    p->problem.AddResidualBlock(new StartPriorCost(&map, prior), nullptr, p->theta.data());
  }
}

// Levenberg-Marquardt from every start in `starts` (coordinates), each from
// the logged initial pressures; leaves the lowest usable point in p->theta
// and p->offsets (the stage's own start when none is) and records the
// iterations, starts, best start, provisional status and reason in `r`.
// Returns the best cost (infinite when no start gave a usable solution).
double SolveFromStarts(const std::vector<std::vector<double>>& starts,
                       const std::vector<FitExperiment>& experiments, const ParameterMap& map,
                       const FitSpec& spec, const RefineOptions& options, bool last, Problem* p,
                       RefineResult* r) {
  ceres::Solver::Options solver = SolverOptions(spec, options);
  const long start_columns = std::count_if(experiments.begin(), experiments.end(),
                                           [](const FitExperiment& e) { return e.FitsStart(); }) *
                             kStartOffsets;
  if (start_columns > map.size()) {
    // Dense QR's work grows with the square of the columns (two per window
    // of a windowed stage): eliminate the start offsets, each of which
    // touches one experiment (Schur complement), instead.
    solver.linear_solver_type = ceres::DENSE_SCHUR;
  }
  double best_cost = INFINITY;
  std::vector<double> best_theta = p->theta;
  std::vector<StartOffsets> best_offsets = p->offsets;
  for (size_t s = 0; s < starts.size(); ++s) {
    if (StopRequested(options)) {
      // Stopped before this start: its first evaluation would fail, and
      // Ceres would log that failure through glog (quiet_solver.h).
      if (r->status == FitStatus::kConverged) r->status = FitStatus::kNotConverged;
      r->reason = "stopped";
      break;
    }
    p->theta = starts[s];
    std::fill(p->offsets.begin(), p->offsets.end(), StartOffsets{0, 0});  // as logged
    // A stage before the last only prepares the next one's start, which
    // refits its parameters anyway: it stops at the first small gain.
    StallCallback stall(last ? options.stall_iterations : 1,
                        last ? options.stall_tolerance : options.earlier_stage_stall_tolerance,
                        options.simulation.stop);
    ceres::Solver::Options start_options = solver;
    start_options.callbacks.push_back(&stall);
    ProgressCallback progress(options.log);
    if (options.log) start_options.callbacks.push_back(&progress);
    ceres::Solver::Summary summary;
    ceres::Solve(start_options, &p->problem, &summary);
    // Also a stop raised before the first callback (the start's own
    // evaluation failed), which the stall rule never saw.
    const bool stopped = StopRequested(options);
    if (options.log) LogQuietly(options.log, summary.FullReport());
    r->iterations += internal::StepsTried(summary);
    if (summary.IsSolutionUsable() && summary.final_cost < best_cost) {
      best_cost = summary.final_cost;
      best_theta = p->theta;
      best_offsets = p->offsets;
      r->best_start = static_cast<int>(s);
      // Provisional: whether the runs are explained is the verdict's
      // (refine_verdict.h) once the last stage is done.
      const bool ended = !stopped && (summary.termination_type == ceres::CONVERGENCE ||
                                      summary.termination_type == ceres::USER_SUCCESS);
      r->status = ended ? FitStatus::kConverged : FitStatus::kNotConverged;
      r->reason = ended ? "" : stopped ? "stopped" : summary.message;
    } else if (!std::isfinite(best_cost)) {
      r->reason = summary.message;
    }
    r->starts = static_cast<int>(s + 1);
    if (stopped) {  // no further starts; the best so far is not converged
      if (r->status == FitStatus::kConverged) r->status = FitStatus::kNotConverged;
      r->reason = "stopped";
      break;
    }
  }
  p->theta = best_theta;
  p->offsets = best_offsets;
  return best_cost;
}

// What the runs tell at the best point, for the covariance: each run's
// information, misfit and correlation weighted by the robust loss's slope
// 1 / (1 + |r|^2 / a^2) there (1 for plain least squares).
struct AtBest {
  Eigen::MatrixXd normal;  // the runs' information, the starts eliminated; empty: a run failed
  // The runs' J^T J with the starts held (the stencil's curvature), kept
  // only where the stencil runs.
  Eigen::MatrixXd held_starts_normal;
  ResidualCorrelation correlation;
  double weighted_cost = 0, weighted_rows = 0;        // the runs' costs and rows, weighted
  std::map<std::string, Eigen::VectorXd> run_scores;  // J^T r summed per run
  ClusteredMeat time_blocks;                          // of the runs' time blocks
  std::vector<double> run_weight;                     // the robust loss's slope, per run
};

// Every run at the best point (p->theta, p->offsets): its cost into r->fitted
// and r->final_cost, its estimated start and (whole runs) its misfits into
// `r`, and what it tells the covariance.
AtBest EvaluateAtBest(const std::vector<FitExperiment>& experiments, const ParameterMap& map,
                      const Problem& p, const std::vector<double>& run_scale, bool windows,
                      bool measure_resolution, const RefineOptions& options, RefineResult* r) {
  AtBest at;
  at.normal = Eigen::MatrixXd::Zero(map.size(), map.size());
  at.held_starts_normal = Eigen::MatrixXd::Zero(map.size(), map.size());
  at.run_weight.assign(experiments.size(), 1.0);
  for (size_t k = 0; k < experiments.size(); ++k) {
    const EvaluationCache* cache = nullptr;
    const std::vector<double> z =
        Coordinates(experiments[k], p.theta.data(), map.size(), p.offsets[k].data());
    if (!p.blocks[k]->ResidualsAndJacobian(z, &cache)) {
      // No information matrix without the run's sensitivities, but its
      // residuals (the plain run, which may still succeed) count in the
      // cost and the verdict; a run that cannot be simulated counts as not
      // explained (NaN misfits).
      at.normal.resize(0, 0);
      Eigen::VectorXd residuals;
      const bool simulated = p.blocks[k]->ResidualsAt(z, &residuals);
      if (!simulated) residuals.setConstant(NAN);
      r->fitted[k].after = simulated ? 0.5 * residuals.squaredNorm() : NAN;
      if (simulated) r->final_cost += r->fitted[k].after;
      if (!windows) {
        if (simulated && experiments[k].FitsStart())
          RecordStartOffset(experiments[k], p.offsets[k], r);
        for (const ChannelMisfit& m :
             RunMisfits(experiments[k], residuals, options.misfit_window_s))
          r->misfits.push_back(m);
      }
      continue;
    }
    r->fitted[k].after = 0.5 * cache->residuals.squaredNorm();
    r->final_cost += r->fitted[k].after;
    // A run the robust loss down-weights informs the parameters less.
    const double weight =
        run_scale[k] > 0 ? 1.0 / (1.0 + cache->residuals.squaredNorm() / run_scale[k]) : 1.0;
    at.run_weight[k] = weight;
    at.weighted_cost += weight * r->fitted[k].after;
    at.weighted_rows += weight * static_cast<double>(experiments[k].data_rows());
    at.correlation.Add(experiments[k], cache->residuals, weight);
    if (at.normal.size() > 0) {
      at.normal += weight * ParameterInformation(*cache, map.size());
      if (measure_resolution) {
        const auto a = cache->jacobian.leftCols(map.size());
        at.held_starts_normal += weight * (a.transpose() * a);
      }
      if (options.run_clustered_errors) {
        // One cluster per run: a window's score adds to its run's.
        const std::string& run =
            experiments[k].parent.empty() ? experiments[k].id : experiments[k].parent;
        Eigen::VectorXd& score = at.run_scores[run];
        if (score.size() == 0) score = Eigen::VectorXd::Zero(map.size());
        score += weight * ParameterScore(*cache, map.size());
      }
      if (options.clustered_error_block_s > 0) {
        for (const Eigen::VectorXd& block :
             BlockScores(experiments[k], *cache, map.size(), options.clustered_error_block_s))
          at.time_blocks.Add(weight * block);
      }
    }
    // A window's start is one logged sample, and a windowed stage is judged
    // on the whole runs from their logged starts (JudgeLastStage): whole
    // runs' estimates only.
    if (experiments[k].FitsStart() && !windows) RecordStartOffset(experiments[k], p.offsets[k], r);
    if (!windows) {
      for (const ChannelMisfit& m :
           RunMisfits(experiments[k], cache->residuals, options.misfit_window_s))
        r->misfits.push_back(m);
    }
  }
  return at;
}

// The free parameters' values at `theta` into r->coefficients (start, value,
// at a bound); one whose information from the runs is below the prior's
// (its standard error from the runs alone above the prior's sigma) is held
// toward the prior's centre. Returns the information with the prior's added.
Eigen::MatrixXd RecordCoefficients(const Parameters& conditioned, const ParameterMap& map,
                                   const std::vector<double>& theta, const Eigen::MatrixXd& normal,
                                   const StartPrior& prior, const RefineOptions& options,
                                   RefineResult* r) {
  for (int j = 0; j < map.size(); ++j) {
    FittedCoefficient rp;
    rp.path = map.free[j].path;
    GetParameter(conditioned, rp.path, &rp.start);
    rp.value = map.ToValue(j, theta[j]);
    rp.at_bound = AtBound(rp.value, map.free[j].lower, map.free[j].upper);
    r->coefficients.push_back(rp);
  }
  Eigen::MatrixXd with_prior = normal;
  if (!options.start_prior || normal.size() == 0) return with_prior;
  for (int j = 0; j < map.size(); ++j) {
    const double slope = map.ScaleDerivative(j, theta[j]) / prior.sigma[j];
    if (normal(j, j) < slope * slope) {
      char why[200];
      std::snprintf(why, sizeof(why),
                    "not determined by the fitted runs (less information than the weak "
                    "prior, sigma %.3g in %s); regularised toward its centre",
                    prior.sigma[j], map.IsLog(j) ? "ln" : "SI");
      r->coefficients[j].held = why;
    }
    with_prior(j, j) += slope * slope;
  }
  return with_prior;
}

// The cost's resolution (RefineOptions::cost_resolution_directions),
// measured on a stencil one standard error out of the best point with the
// starts held where they ended, and the covariance `cov` widened by it
// (`covariance(resolution)` makes one); at most two rounds, not iterated to
// a fixed point (a wider band can reach rougher cost).
void MeasureResolution(const std::vector<FitExperiment>& experiments, const ParameterMap& map,
                       const Problem& p, const AtBest& at, const RefineOptions& options,
                       const std::function<Eigen::MatrixXd(double)>& covariance,
                       Eigen::MatrixXd* cov, RefineResult* r) {
  // The cost the covariance describes: each run's weighted as in the
  // information (a robust refit's runs at the loss's slope at the optimum).
  const auto runs_cost = [&](const std::vector<double>& theta) -> double {
    double total = 0;
    for (size_t k = 0; k < experiments.size(); ++k) {
      Eigen::VectorXd residuals(experiments[k].residuals());
      const double* blocks_at[2] = {theta.data(), p.offsets[k].data()};
      if (!p.blocks[k]->Evaluate(blocks_at, residuals.data(), nullptr)) return NAN;
      total += at.run_weight[k] * 0.5 * residuals.squaredNorm();
    }
    return total;
  };
  // Values -> coordinates; a coordinate whose value no longer moves (a
  // logistic rounded onto its bound) stays where it is.
  Eigen::VectorXd slope(map.size());
  for (int j = 0; j < map.size(); ++j) {
    const double derivative = map.Derivative(j, p.theta[j]);
    slope[j] = std::isfinite(derivative) && derivative != 0 ? 1.0 / derivative : 0.0;
  }
  double resolution = options.stall_tolerance;
  for (int round = 0; round < 2; ++round) {
    const Eigen::MatrixXd theta_cov = slope.asDiagonal() * *cov * slope.asDiagonal();
    const double jitter = StencilJitter(runs_cost, p.theta, at.weighted_cost, theta_cov,
                                        at.held_starts_normal, options.cost_resolution_directions);
    if (!(jitter / at.weighted_cost > resolution)) break;
    resolution = jitter / at.weighted_cost;
    *cov = covariance(resolution);
    r->cost_resolution_measured = true;
  }
  r->cost_resolution = resolution;
}

}  // namespace

RefineResult RefineStage(const Parameters& start, const Unit& unit, const FitSpec& spec,
                         bool windows, bool last, const RefineOptions& options, bool robust_runs,
                         const std::vector<std::vector<double>>& extra_starts,
                         bool extra_starts_only) {
  const Parameters conditioned = WithRigConditions(start, unit);
  const ParameterMap map = MakeParameterMap(conditioned, spec);
  const std::vector<FitExperiment> experiments =
      FittedRuns(conditioned, unit, spec, windows, options.lag_starts.get());
  const StartPrior prior = MakeStartPrior(
      map,
      options.start_prior_centre ? WithRigConditions(*options.start_prior_centre, unit)
                                 : conditioned,
      conditioned, options.start_prior_errors, options.start_prior_fraction);
  Problem p;
  std::vector<double> run_scale;
  BuildProblem(conditioned, map, experiments, prior, options, robust_runs, &p, &run_scale);

  std::vector<std::vector<double>> starts;
  if (!extra_starts_only || extra_starts.empty()) {
    starts.push_back(p.theta);
    for (auto& point : LatinHypercube(map, spec.multistart, spec.seed)) starts.push_back(point);
  }
  for (const auto& point : extra_starts) starts.push_back(point);
  RefineResult r;
  const double best_cost = SolveFromStarts(starts, experiments, map, spec, options, last, &p, &r);
  for (size_t k = 0; k < experiments.size(); ++k) {
    // Ceres' first evaluation is at the given start.
    r.fitted.push_back(
        {experiments[k].id, p.blocks[k]->FirstCost(), 0, experiments[k].residuals()});
    r.initial_cost += r.fitted.back().before;
  }
  if (!std::isfinite(best_cost)) {
    r.status = FitStatus::kNotFitted;
    r.params = start;
    r.reason = "no start gave a usable solution: " + r.reason;
  } else {
    r.params = WithValues(conditioned, map, p.theta.data());
    const bool measure_resolution = last && options.cost_resolution_directions > 0;
    const AtBest at =
        EvaluateAtBest(experiments, map, p, run_scale, windows, measure_resolution, options, &r);
    const Eigen::MatrixXd with_prior =
        RecordCoefficients(conditioned, map, p.theta, at.normal, prior, options, &r);
    ClusteredMeat runs;
    for (const auto& [run, score] : at.run_scores) runs.Add(score);
    const std::function<Eigen::MatrixXd(double)> covariance = [&](double resolution) {
      return ParameterCovariance(with_prior, map, p.theta, at.weighted_cost,
                                 std::lround(at.weighted_rows), at.correlation.Inflation(),
                                 resolution, {runs, at.time_blocks});
    };
    Eigen::MatrixXd cov = covariance(options.stall_tolerance);
    r.cost_resolution = options.stall_tolerance;
    if (measure_resolution && cov.rows() == map.size() && at.weighted_cost > 0) {
      MeasureResolution(experiments, map, p, at, options, covariance, &cov, &r);
    }
    Summarise(cov, map, options, &r);
  }
  if (windows) r.fitted = PerRun(r.fitted, experiments);
  return r;
}

}  // namespace pneumaid::refine_internal
