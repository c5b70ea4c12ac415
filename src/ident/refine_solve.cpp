#include "refine_solve.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "pneumaid/model/parameter_table.h"
#include "pneumaid/validate/validate.h"
#include "quiet_solver.h"
#include "refine_covariance.h"
#include "refine_verdict.h"

namespace pneumaid::refine_internal {

ceres::CallbackReturnType ProgressCallback::operator()(const ceres::IterationSummary& summary) {
  char line[200];
  std::snprintf(line, sizeof(line),
                "iteration %3d: cost %.6e, change %.3e, |step| %.3e, radius %.3e, %s, %.2f s",
                summary.iteration, summary.cost, summary.cost_change, summary.step_norm,
                summary.trust_region_radius, summary.step_is_successful ? "accepted" : "rejected",
                summary.cumulative_time_in_seconds);
  log_(line);
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

// Counts an estimated start and keeps the largest move of its pressures.
void RecordStartOffset(const FitExperiment& e, const StartOffsets& offsets, RefineResult* r) {
  ++r->estimated_starts;
  for (int k = 0; k < kStartOffsets; ++k) {
    if (std::fabs(offsets[k]) > r->largest_start_offset_sigma) {
      r->largest_start_offset_sigma = std::fabs(offsets[k]);
      r->largest_start_offset_Pa = std::fabs(offsets[k]) * e.start_sigma_Pa[k];
    }
  }
}

RefineResult RefineStage(const Parameters& start, const Unit& unit, const FitSpec& spec,
                         bool windows, bool last, const RefineOptions& options, bool robust_runs,
                         const std::vector<std::vector<double>>& extra_starts,
                         bool extra_starts_only) {
  const Parameters conditioned = WithRigConditions(start, unit);
  const ParameterMap map = MakeParameterMap(conditioned, spec);
  const std::vector<FitExperiment> experiments = FittedRuns(conditioned, unit, spec, windows);

  Problem p;
  p.theta = map.ThetaOf(conditioned);
  p.offsets.assign(experiments.size(), StartOffsets{0, 0});  // never reallocated below
  std::vector<double> run_scale;  // each run's robust scale a^2 (0: plain least squares)
  for (size_t k = 0; k < experiments.size(); ++k) {
    const FitExperiment& e = experiments[k];
    auto* block =
        new ExperimentResidual(&conditioned, &map, &e, &options.simulation, options.jacobian);
    run_scale.push_back(robust_runs ? options.acceptable_reduced_chi_square *
                                          static_cast<double>(std::max(e.residuals(), 1L))
                                    : 0.0);
    ceres::LossFunction* loss =
        robust_runs ? new ceres::CauchyLoss(std::sqrt(run_scale.back())) : nullptr;
    if (e.FitsStart()) {
      p.problem.AddResidualBlock(block, loss, p.theta.data(), p.offsets[k].data());
    } else {
      p.problem.AddResidualBlock(block, loss, p.theta.data());
    }
    p.blocks.push_back(block);
  }

  // The weak prior toward the start (after the runs: Ceres' cost includes it,
  // the costs reported are the runs').
  const StartPrior prior =
      MakeStartPrior(map, conditioned, options.start_prior_errors, options.start_prior_fraction);
  if (options.start_prior) {
    p.problem.AddResidualBlock(new StartPriorCost(&map, prior), nullptr, p.theta.data());
  }
  RefineResult r;
  const std::vector<double> start_theta = p.theta;
  std::vector<std::vector<double>> starts;
  if (!extra_starts_only || extra_starts.empty()) {
    starts.push_back(start_theta);
    for (auto& point : LatinHypercube(map, spec.multistart, spec.seed)) starts.push_back(point);
  }
  for (const auto& point : extra_starts) starts.push_back(point);

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
  std::vector<double> best_theta = start_theta;
  std::vector<StartOffsets> best_offsets = p.offsets;
  for (size_t s = 0; s < starts.size(); ++s) {
    p.theta = starts[s];
    std::fill(p.offsets.begin(), p.offsets.end(), StartOffsets{0, 0});  // as logged
    // A stage before the last only prepares the next one's start, which
    // refits its parameters anyway: it stops at the first small gain.
    StallCallback stall(last ? options.stall_iterations : 1,
                        last ? options.stall_tolerance : options.earlier_stage_stall_tolerance);
    ceres::Solver::Options start_options = solver;
    start_options.callbacks.push_back(&stall);
    ProgressCallback progress(options.log);
    if (options.log) start_options.callbacks.push_back(&progress);
    ceres::Solver::Summary summary;
    ceres::Solve(start_options, &p.problem, &summary);
    if (options.log) options.log(summary.FullReport());
    r.iterations += static_cast<int>(summary.iterations.size());
    if (summary.IsSolutionUsable() && summary.final_cost < best_cost) {
      best_cost = summary.final_cost;
      best_theta = p.theta;
      best_offsets = p.offsets;
      r.best_start = static_cast<int>(s);
      // Provisional: whether the runs are explained is the verdict's
      // (refine_verdict.h) once the last stage is done.
      const bool stopped = summary.termination_type == ceres::CONVERGENCE ||
                           summary.termination_type == ceres::USER_SUCCESS;
      r.status = stopped ? FitStatus::kConverged : FitStatus::kNotConverged;
      r.reason = stopped ? "" : summary.message;
    } else if (!std::isfinite(best_cost)) {
      r.reason = summary.message;
    }
  }
  r.starts = static_cast<int>(starts.size());
  for (size_t k = 0; k < experiments.size(); ++k) {
    // Ceres' first evaluation is at the given start.
    r.fitted.push_back(
        {experiments[k].id, p.blocks[k]->FirstCost(), 0, experiments[k].residuals()});
    r.initial_cost += r.fitted.back().before;
  }
  p.theta = best_theta;
  p.offsets = best_offsets;
  if (!std::isfinite(best_cost)) {
    r.status = FitStatus::kNotFitted;
    r.params = start;
    r.reason = "no start gave a usable solution: " + r.reason;
  } else {
    r.params = WithValues(conditioned, map, p.theta.data());
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(map.size(), map.size());
    ResidualCorrelation correlation;
    double weighted_cost = 0, weighted_rows = 0;        // the runs' costs and rows, weighted
    std::map<std::string, Eigen::VectorXd> run_scores;  // J^T r summed per run
    ClusteredMeat blocks;                               // of the runs' time blocks
    // The stencil's curvature (the runs' J^T J with the starts held), kept
    // only where the stencil runs.
    const bool measure_resolution = last && options.cost_resolution_directions > 0;
    Eigen::MatrixXd held_starts_normal = Eigen::MatrixXd::Zero(map.size(), map.size());
    std::vector<double> run_weight(experiments.size(), 1.0);  // the robust loss's slope, held
    for (size_t k = 0; k < experiments.size(); ++k) {
      const EvaluationCache* at_best = nullptr;
      const std::vector<double> z =
          Coordinates(experiments[k], p.theta.data(), map.size(), p.offsets[k].data());
      if (!p.blocks[k]->ResidualsAndJacobian(z, &at_best)) {
        normal.resize(0, 0);
        r.fitted[k].after = NAN;
        continue;
      }
      r.fitted[k].after = 0.5 * at_best->residuals.squaredNorm();
      r.final_cost += r.fitted[k].after;
      // A run the robust loss down-weights informs the parameters less: its
      // information, its misfit and its correlation count with the loss's
      // slope 1 / (1 + |r|^2 / a^2).
      const double weight =
          run_scale[k] > 0 ? 1.0 / (1.0 + at_best->residuals.squaredNorm() / run_scale[k]) : 1.0;
      run_weight[k] = weight;
      weighted_cost += weight * r.fitted[k].after;
      weighted_rows += weight * static_cast<double>(experiments[k].data_rows());
      correlation.Add(experiments[k], at_best->residuals, weight);
      if (normal.size() > 0) {
        normal += weight * ParameterInformation(*at_best, map.size());
        if (measure_resolution) {
          const auto a = at_best->jacobian.leftCols(map.size());
          held_starts_normal += weight * (a.transpose() * a);
        }
        if (options.run_clustered_errors) {
          // One cluster per run: a window's score adds to its run's.
          const std::string& run =
              experiments[k].parent.empty() ? experiments[k].id : experiments[k].parent;
          Eigen::VectorXd& score = run_scores[run];
          if (score.size() == 0) score = Eigen::VectorXd::Zero(map.size());
          score += weight * ParameterScore(*at_best, map.size());
        }
        if (options.clustered_error_block_s > 0) {
          for (const Eigen::VectorXd& block :
               BlockScores(experiments[k], *at_best, map.size(), options.clustered_error_block_s))
            blocks.Add(weight * block);
        }
      }
      if (experiments[k].FitsStart()) RecordStartOffset(experiments[k], p.offsets[k], &r);
      if (!windows) {
        for (const ChannelMisfit& m :
             RunMisfits(experiments[k], at_best->residuals, options.misfit_window_s))
          r.misfits.push_back(m);
      }
    }
    for (int j = 0; j < map.size(); ++j) {
      FittedCoefficient rp;
      rp.path = map.free[j].path;
      GetParameter(conditioned, rp.path, &rp.start);
      rp.value = map.ToValue(j, p.theta[j]);
      const double span = map.free[j].upper - map.free[j].lower;
      rp.at_bound =
          std::min(rp.value - map.free[j].lower, map.free[j].upper - rp.value) < 1e-6 * span;
      r.coefficients.push_back(rp);
    }
    // What the fitted runs determine: a parameter whose information from the
    // runs is below the prior's (its standard error from the runs alone
    // above the prior's sigma) is reported as held toward the start.
    Eigen::MatrixXd with_prior = normal;
    if (options.start_prior && normal.size() > 0) {
      for (int j = 0; j < map.size(); ++j) {
        const double slope = map.ScaleDerivative(j, p.theta[j]) / prior.sigma[j];
        if (normal(j, j) < slope * slope) {
          char why[200];
          std::snprintf(why, sizeof(why),
                        "not determined by the fitted runs (less information than the prior "
                        "toward the start, sigma %.3g in %s); regularised toward the start",
                        prior.sigma[j], map.IsLog(j) ? "ln" : "SI");
          r.coefficients[j].held = why;
        }
        with_prior(j, j) += slope * slope;
      }
    }
    ClusteredMeat runs;
    for (const auto& [run, score] : run_scores) runs.Add(score);
    const auto covariance = [&](double resolution) {
      return ParameterCovariance(with_prior, map, p.theta, weighted_cost,
                                 std::lround(weighted_rows), correlation.Inflation(), resolution,
                                 {runs, blocks});
    };
    Eigen::MatrixXd cov = covariance(options.stall_tolerance);
    r.cost_resolution = options.stall_tolerance;
    if (measure_resolution && cov.rows() == map.size() && weighted_cost > 0) {
      // The cost the covariance describes: each run's weighted as in the
      // information (a robust refit's runs at the loss's slope at the
      // optimum), the starts held where they ended.
      const auto runs_cost = [&](const std::vector<double>& theta) -> double {
        double total = 0;
        for (size_t k = 0; k < experiments.size(); ++k) {
          Eigen::VectorXd residuals(experiments[k].residuals());
          const double* blocks_at[2] = {theta.data(), p.offsets[k].data()};
          if (!p.blocks[k]->Evaluate(blocks_at, residuals.data(), nullptr)) return NAN;
          total += run_weight[k] * 0.5 * residuals.squaredNorm();
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
      // Measured once more at the widened errors (a wider band can reach
      // rougher cost); at most two rounds, not iterated to a fixed point.
      double resolution = options.stall_tolerance;
      for (int round = 0; round < 2; ++round) {
        const Eigen::MatrixXd theta_cov = slope.asDiagonal() * cov * slope.asDiagonal();
        const double jitter = StencilJitter(runs_cost, p.theta, weighted_cost, theta_cov,
                                            held_starts_normal, options.cost_resolution_directions);
        if (!(jitter / weighted_cost > resolution)) break;
        resolution = jitter / weighted_cost;
        cov = covariance(resolution);
        r.cost_resolution_measured = true;
      }
      r.cost_resolution = resolution;
    }
    Summarise(cov, map, options, &r);
  }
  if (windows) r.fitted = PerRun(r.fitted, experiments);
  return r;
}

}  // namespace pneumaid::refine_internal
