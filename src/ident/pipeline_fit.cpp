#include "pneumaid/ident/pipeline_fit.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "determination.h"
#include "held_levels.h"
#include "pneumaid/eval/lag.h"
#include "pneumaid/io/channel_noise.h"
#include "quiet_solver.h"
#include "tube_from_meters.h"

namespace pneumaid {
namespace {

using internal::DeltaScan;

// The variance of the parameter in column `column` of the blocks `free`
// (columns in their order) when their joint covariance is singular: one over
// its Schur complement in J'J, the other columns scaled to unit norm and
// their block inverted by a pseudo-inverse (eigenvalues below 1e-12 of the
// largest dropped), so a nuisance that no residual determines does not take
// the parameter with it. Infinite when the parameter itself is not determined.
double MarginalVariance(ceres::Problem* problem, const std::vector<double*>& free, int column) {
  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = free;
  ceres::CRSMatrix crs;
  if (!problem->Evaluate(options, nullptr, nullptr, nullptr, &crs)) return HUGE_VAL;
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int row = 0; row < crs.num_rows; ++row) {
    for (int k = crs.rows[row]; k < crs.rows[row + 1]; ++k)
      jacobian(row, crs.cols[k]) = crs.values[k];
  }
  const Eigen::MatrixXd normal = jacobian.transpose() * jacobian;
  const double own = normal(column, column);
  if (!(own > 0)) return HUGE_VAL;
  std::vector<int> others;
  for (int j = 0; j < normal.cols(); ++j) {
    if (j != column && normal(j, j) > 0) others.push_back(j);
  }
  const int m = static_cast<int>(others.size());
  Eigen::MatrixXd block(m, m);
  Eigen::VectorXd coupling(m);
  for (int a = 0; a < m; ++a) {
    const double scale_a = std::sqrt(normal(others[a], others[a]));
    coupling(a) = normal(others[a], column) / (scale_a * std::sqrt(own));
    for (int b = 0; b < m; ++b)
      block(a, b) =
          normal(others[a], others[b]) / (scale_a * std::sqrt(normal(others[b], others[b])));
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(block);
  const double largest = m > 0 ? eigen.eigenvalues().maxCoeff() : 0;
  double explained = 0;  // coupling' pinv(block) coupling
  for (int k = 0; k < m; ++k) {
    const double value = eigen.eigenvalues()(k);
    if (value <= 1e-12 * largest) continue;
    const double along = eigen.eigenvectors().col(k).dot(coupling);
    explained += along * along / value;
  }
  const double schur = 1.0 - explained;  // of the unit-scaled column
  return schur > 1e-10 ? 1.0 / (schur * own) : HUGE_VAL;
}

// What one tube log's fit needs: samples, the level each sample belongs to,
// meter lags and the channels' noise.
struct TubeLog {
  const std::vector<double>* t = nullptr;
  const std::vector<double>* q_in = nullptr;
  const std::vector<double>* q_out = nullptr;
  std::vector<int> level;  // per sample
  int levels = 0;
  double tau_in_s = 0, tau_out_s = 0, sigma_in = 1, sigma_out = 1;
  // Where the record does not start settled (its meters' first readings are
  // not their readings at the end of the first level: a record that starts
  // as the valve opens), the lags start at those first readings; NaN:
  // settled for the first level.
  double start_in = NAN, start_out = NAN;

  double Interval(std::size_t i) const { return (*t)[i] - (*t)[i - 1]; }

  // Both meters' readings for valve flows `flow` (one per level), delta and
  // the valve's own opening lag: the flow held per level, through the valve's
  // lag and the inlet meter; through Eq. 5 and the outlet meter. The lags
  // start settled for the first level, or, where the record does not start
  // settled, where its meters' first readings say (start_in, start_out). (A
  // tube test logged from the valve's opening was "not determined" from a
  // settled start, and delta came from the prior: 8 for 5.)
  template <typename T>
  void Predict(const T* flow, const T& delta, const T& valve_tau_s, std::vector<T>* inlet,
               std::vector<T>* outlet) const {
    const std::size_t n = t->size();
    outlet->resize(n);
    for (std::size_t i = 0; i < n; ++i) (*outlet)[i] = flow[level[i]];
    const auto interval = [this](std::size_t i) { return Interval(i); };
    const bool settled = std::isnan(start_in);
    const auto lag = [&](const T& tau_s, double start, std::vector<T>* signal) {
      if (settled) {
        ApplyFirstOrderLag(interval, tau_s, signal);
      } else {
        ApplyFirstOrderLagFrom(interval, tau_s, T(start), signal);
      }
    };
    if (valve_tau_s > T(0.0)) lag(valve_tau_s, start_in, outlet);
    *inlet = *outlet;
    if (tau_in_s > 0) lag(T(tau_in_s), start_in, inlet);
    lag(T(1.0) / delta, start_out, outlet);
    if (tau_out_s > 0) lag(T(tau_out_s), start_out, outlet);
  }
};

// Residuals of both meters for the blocks (valve flow per level [kg/s],
// delta [1/s]) and (valve lag [s]).
struct TubeResiduals {
  const TubeLog* log;

  template <typename T>
  bool operator()(T const* const* parameters, T* residuals) const {
    const T* theta = parameters[0];
    std::vector<T> inlet, outlet;
    log->Predict(theta, theta[log->levels], parameters[1][0], &inlet, &outlet);
    const std::size_t n = log->t->size();
    for (std::size_t i = 0; i < n; ++i) {
      residuals[i] = (inlet[i] - (*log->q_in)[i]) / log->sigma_in;
      residuals[n + i] = (outlet[i] - (*log->q_out)[i]) / log->sigma_out;
    }
    return true;
  }
};

// For a fixed delta (and no valve lag) the readings are linear in the level
// flows: the flows that fit best (least squares) and the cost they leave.
double BestLevels(const TubeLog& log, double delta, std::vector<double>* flow) {
  const std::size_t n = log.t->size();
  const int m = log.levels;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m);
  // The readings are affine in the flows: what the lags' start gives with
  // every flow 0, plus each level's response.
  std::vector<double> zero(m, 0.0), free_in, free_out;
  log.Predict(zero.data(), delta, 0.0, &free_in, &free_out);
  std::vector<std::vector<double>> inlet(m), outlet(m);
  std::vector<double> unit(m, 0.0);
  for (int k = 0; k < m; ++k) {
    unit.assign(m, 0.0);
    unit[k] = 1.0;
    log.Predict(unit.data(), delta, 0.0, &inlet[k], &outlet[k]);
    for (std::size_t i = 0; i < n; ++i) {
      inlet[k][i] -= free_in[i];
      outlet[k][i] -= free_out[i];
    }
  }
  const double w_in = 1 / (log.sigma_in * log.sigma_in),
               w_out = 1 / (log.sigma_out * log.sigma_out);
  for (int a = 0; a < m; ++a) {
    for (int b = a; b < m; ++b) {
      double sum = 0;
      for (std::size_t i = 0; i < n; ++i) {
        sum += w_in * inlet[a][i] * inlet[b][i] + w_out * outlet[a][i] * outlet[b][i];
      }
      normal(a, b) = normal(b, a) = sum;
    }
    for (std::size_t i = 0; i < n; ++i) {
      rhs(a) += w_in * inlet[a][i] * ((*log.q_in)[i] - free_in[i]) +
                w_out * outlet[a][i] * ((*log.q_out)[i] - free_out[i]);
    }
  }
  const Eigen::VectorXd solution = normal.completeOrthogonalDecomposition().solve(rhs);
  flow->assign(solution.data(), solution.data() + m);
  std::vector<double> in, out;
  log.Predict(flow->data(), delta, 0.0, &in, &out);
  double cost = 0;
  for (std::size_t i = 0; i < n; ++i) {
    cost += std::pow((in[i] - (*log.q_in)[i]) / log.sigma_in, 2) +
            std::pow((out[i] - (*log.q_out)[i]) / log.sigma_out, 2);
  }
  return 0.5 * cost;
}

// How much wider than the noise alone the errors are when the model misses
// the data: the reduced chi-square, times the larger of the two channels'
// correlation inflations (determination.h, CorrelationInflation). 1 when the
// residuals are the sensors' white noise.
double ModelErrorFactor(const std::vector<double>& residuals, std::size_t n, double chi_square) {
  double worst = 1;
  for (std::size_t channel = 0; channel < 2; ++channel) {
    const double* r = residuals.data() + channel * n;
    double lagged = 0, squares = 0;
    for (std::size_t i = 0; i < n; ++i) {
      squares += r[i] * r[i];
      if (i > 0) lagged += r[i] * r[i - 1];
    }
    worst = std::max(worst, internal::CorrelationInflation(lagged, squares));
  }
  return std::max(1.0, chi_square * worst);
}

TubeFit FitTube(const Experiment& e, const Manifest& manifest, const PipelineFitOptions& options) {
  TubeFit fit;
  fit.coefficients.push_back(
      {"pipeline.delta", options.initial_delta_per_s, options.initial_delta_per_s, 0.0, "", false});
  const auto not_fitted = [&fit](const std::string& why) {
    fit.status = FitStatus::kNotFitted;
    fit.reason = why;
    fit.coefficients.front().held = why;
    return fit;
  };
  fit.experiment = e.entry.id;
  fit.tube_length_m = e.entry.tube_length_m.value_or(0.0);
  TubeLog log;
  log.t = &e.column("t");
  log.q_in = &e.column("q_in");
  log.q_out = &e.column("q_out");
  const auto held = internal::HeldLevels(e.column("u"), options.level_change_V);
  const std::size_t n = log.t->size();
  fit.levels = log.levels = static_cast<int>(held.size());
  if (n < 20) return not_fitted("fewer than 20 samples");
  if (held.size() < 2) return not_fitted("the command never changes: a step response is needed");
  log.sigma_in = std::max(NoiseOf(manifest, "q_in", {log.q_in}, {log.t}).sigma, 1e-12);
  log.sigma_out = std::max(NoiseOf(manifest, "q_out", {log.q_out}, {log.t}).sigma, 1e-12);
  if (log.levels > options.max_levels) {
    internal::FitTubeFromMeters(e, manifest, options, log.sigma_in, log.sigma_out, &fit);
    return fit;
  }
  log.level.resize(n);
  for (std::size_t k = 0; k < held.size(); ++k) {
    for (std::size_t i = held[k].first; i < held[k].second; ++i) log.level[i] = static_cast<int>(k);
  }
  log.tau_in_s = manifest.DeclaredTau("q_in", 0.0);
  log.tau_out_s = manifest.DeclaredTau("q_out", 0.0);
  // Settled: the meters' first readings within 5 sigma of their last on the
  // first level (which a held level reaches).
  const std::size_t first_end = held.front().second - 1;
  const auto settled = [&](const std::vector<double>& q, double sigma) {
    return std::fabs(q.front() - q[first_end]) <= 5 * sigma;
  };
  if (!settled(*log.q_in, log.sigma_in) || !settled(*log.q_out, log.sigma_out)) {
    log.start_in = log.q_in->front();
    log.start_out = log.q_out->front();
  }

  // Start: the best of the prior's delta and a log-spaced scan, each with
  // its best level flows.
  std::vector<double> flow, best_flow;
  double best_delta = options.initial_delta_per_s;
  double best_cost = BestLevels(log, best_delta, &best_flow);
  const DeltaScan scan(options);
  for (int k = 0; k <= scan.points; ++k) {
    const double delta = scan.At(k);
    const double cost = BestLevels(log, delta, &flow);
    if (cost < best_cost) best_cost = cost, best_delta = delta, best_flow = flow;
  }
  std::vector<double> theta = best_flow;
  theta.push_back(best_delta);
  // The valve's lag: a nuisance that would bias delta low (it also takes up a
  // lag common to both meters that the manifest does not declare). It starts
  // off zero: there its derivative would vanish.
  double valve_tau_s = 0.5 * log.Interval(1);
  ceres::Problem problem;
  auto* cost = new ceres::DynamicAutoDiffCostFunction<TubeResiduals, 4>(new TubeResiduals{&log});
  cost->AddParameterBlock(static_cast<int>(theta.size()));
  cost->AddParameterBlock(1);
  cost->SetNumResiduals(static_cast<int>(2 * n));
  problem.AddResidualBlock(cost, nullptr, theta.data(), &valve_tau_s);
  problem.SetParameterLowerBound(theta.data(), log.levels, 1e-3);  // delta > 0
  problem.SetParameterLowerBound(&valve_tau_s, 0, 0.0);
  ceres::Solver::Options solver_options = internal::QuietSolverOptions();
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  fit.initial_cost = summary.initial_cost;
  fit.final_cost = summary.final_cost;
  fit.iterations = internal::StepsTried(summary);
  if (!summary.IsSolutionUsable()) return not_fitted("Ceres failed: " + summary.message);
  const double delta = theta[log.levels];
  const int m = static_cast<int>(theta.size());
  const double dof = std::max(1.0, 2.0 * static_cast<double>(n) - m - 1);
  fit.reduced_chi_square = 2 * summary.final_cost / dof;
  fit.valve_lag_s = valve_tau_s;
  std::vector<double> residuals;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, &residuals, nullptr, nullptr);
  // A valve lag at its bound (none) has no derivative: it is held there.
  if (!(valve_tau_s > 0)) problem.SetParameterBlockConstant(&valve_tau_s);
  ceres::Covariance covariance{ceres::Covariance::Options{}};
  std::vector<double> c(static_cast<std::size_t>(m * m));
  const std::vector<std::pair<const double*, const double*>> blocks = {
      {theta.data(), theta.data()}};
  char note[200];
  double delta_variance = 0;
  if (covariance.Compute(blocks, &problem) &&
      covariance.GetCovarianceBlock(theta.data(), theta.data(), c.data())) {
    delta_variance = c.back();
  } else {
    // Singular: a level's flow that no sample determines (a command changed
    // at the log's last sample) must not cost the tube its delta.
    std::vector<double*> free = {theta.data()};
    if (valve_tau_s > 0) free.push_back(&valve_tau_s);
    delta_variance = MarginalVariance(&problem, free, log.levels);
    if (!std::isfinite(delta_variance)) {
      std::snprintf(note, sizeof(note),
                    "delta is not determined by this log (singular covariance at delta %.3g 1/s)",
                    delta);
      return not_fitted(note);
    }
  }
  // Model error counts: a fit worse than the noise widens its error.
  const double error =
      std::sqrt(delta_variance * ModelErrorFactor(residuals, n, fit.reduced_chi_square));
  if (!internal::IsDetermined(delta, error, 0.0, options.determined_relative_error)) {
    std::snprintf(note, sizeof(note),
                  "delta is not determined by this log (%.3g +- %.2g 1/s; the sample rate or the "
                  "level changes do not resolve the tube's lag)",
                  delta, error);
    return not_fitted(note);
  }
  fit.status = summary.termination_type == ceres::NO_CONVERGENCE ? FitStatus::kNotConverged
                                                                 : FitStatus::kConverged;
  if (fit.status == FitStatus::kNotConverged) fit.reason = summary.message;
  fit.coefficients.front().value = delta;
  fit.coefficients.front().standard_error = error;
  fit.covariance = Eigen::MatrixXd::Constant(1, 1, error * error);
  for (int k = 0; k < log.levels; ++k) {
    if (std::fabs(theta[k]) > std::fabs(fit.flow_kg_per_s)) fit.flow_kg_per_s = theta[k];
  }
  return fit;
}

// Weighted straight line through (L, delta) with its value and error at L0.
void FitLaw(double rig_length_m, double initial_delta_per_s, PipelineFitResult* result) {
  double s = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  int count = 0;
  for (const auto& tube : result->tubes) {
    if (!tube.has_values()) continue;
    const double w = 1.0 / (tube.delta_standard_error() * tube.delta_standard_error());
    s += w;
    sx += w * tube.tube_length_m;
    sy += w * tube.delta_per_s();
    sxx += w * tube.tube_length_m * tube.tube_length_m;
    sxy += w * tube.tube_length_m * tube.delta_per_s();
    ++count;
  }
  FittedCoefficient delta{
      "pipeline.delta", initial_delta_per_s, initial_delta_per_s, 0.0, "", false};
  result->status = count == 0 ? FitStatus::kNotFitted : FitStatus::kConverged;
  for (const auto& tube : result->tubes) {
    result->iterations += tube.iterations;
    result->initial_cost += tube.initial_cost;
    result->final_cost += tube.final_cost;
    if (tube.has_values()) result->status = std::max(result->status, tube.status);
  }
  const double det = s * sxx - sx * sx;
  if (count == 0) {
    result->reason = result->tubes.empty() ? "no tube log" : "no tube could be fitted";
    for (std::size_t k = 0; k < result->tubes.size(); ++k) {
      const TubeFit& tube = result->tubes[k];
      result->reason += (k == 0 ? " (" : "; ") + tube.experiment + ": " + tube.reason +
                        (k + 1 == result->tubes.size() ? ")" : "");
    }
    delta.held = result->reason;
  } else if (count == 1 || det <= 1e-12 * s * sxx) {  // one length: a flat law
    result->law_intercept_per_s = sy / s;
    result->law_slope_per_s_m = 0;
    delta.value = sy / s;
    delta.standard_error = std::sqrt(1.0 / s);
    result->reason = "one tube length: delta(L) taken as flat";
  } else {
    result->law_slope_per_s_m = (s * sxy - sx * sy) / det;
    result->law_intercept_per_s = (sxx * sy - sx * sxy) / det;
    const double L = rig_length_m;
    delta.value = result->law_intercept_per_s + result->law_slope_per_s_m * L;
    // Var(a + b L) from the weighted normal equations' inverse.
    delta.standard_error = std::sqrt((sxx - 2 * L * sx + L * L * s) / det);
  }
  result->coefficients = {delta};
  result->covariance = Eigen::MatrixXd::Constant(1, 1, delta.standard_error * delta.standard_error);
}

}  // namespace

bool PipelineFitOptions::IsValid(std::string* error) const {
  const auto fail = [error](const char* what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (!(initial_delta_per_s > 0)) return fail("initial_delta_per_s must be > 0");
  if (!(min_delta_per_s > 0) || !(max_delta_per_s > min_delta_per_s))
    return fail("expected 0 < min_delta_per_s < max_delta_per_s");
  if (scan_points_per_decade < 1) return fail("scan_points_per_decade must be >= 1");
  if (!(level_change_V > 0)) return fail("level_change_V must be > 0");
  if (max_levels < 2) return fail("max_levels must be >= 2");
  if (!(determined_relative_error > 0)) return fail("determined_relative_error must be > 0");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(max_reduced_chi_square >= 1)) return fail("max_reduced_chi_square must be >= 1");
  return true;
}

PipelineFitResult FitPipeline(const Unit& unit, const PipelineFitOptions& options) {
  PipelineFitResult result;
  std::string unexplained;
  for (const Experiment& e : unit.experiments) {
    if (e.entry.kind != ExperimentKind::kPipeline) continue;
    TubeFit tube = FitTube(e, unit.manifest, options);
    // The verdict: a misfit the noise and the acceptable model error do not
    // explain. Its delta is still the best point found, and still written.
    if (tube.status == FitStatus::kConverged &&
        tube.reduced_chi_square > options.max_reduced_chi_square) {
      char reason[200];
      std::snprintf(reason, sizeof(reason),
                    "the tube model does not explain this log (reduced chi-square %.3g, "
                    "accepted up to %.3g)",
                    tube.reduced_chi_square, options.max_reduced_chi_square);
      tube.status = FitStatus::kNotExplained;
      tube.reason = tube.reason.empty() ? reason : std::string(reason) + "; " + tube.reason;
      unexplained += (unexplained.empty() ? "" : "; ") + tube.experiment + ": " + tube.reason;
    }
    result.tubes.push_back(std::move(tube));
  }
  FitLaw(unit.manifest.rig.tube_length_m, options.initial_delta_per_s, &result);
  if (!unexplained.empty()) {
    result.reason = unexplained + (result.reason.empty() ? "" : "; " + result.reason);
  }
  return result;
}

std::string PipelineFitResult::BriefReport() const {
  std::ostringstream out;
  char line[200];
  out << "Pipeline delta fit: " << tubes.size() << " tube logs, " << ToString(status);
  if (tubes.empty() && !reason.empty()) out << " (" << reason << ")";
  out << "\n";
  for (const auto& tube : tubes) {
    if (!tube.has_values()) {
      out << "  " << tube.experiment << ": not fitted (" << tube.reason << ")\n";
      continue;
    }
    std::snprintf(line, sizeof(line),
                  "  %s: L %.3g m, delta %.4g +- %.2g 1/s (%d levels, %d iterations, reduced "
                  "chi-square %.3g)%s\n",
                  tube.experiment.c_str(), tube.tube_length_m, tube.delta_per_s(),
                  tube.delta_standard_error(), tube.levels, tube.iterations,
                  tube.reduced_chi_square,
                  tube.status == FitStatus::kConverged      ? ""
                  : tube.status == FitStatus::kNotExplained ? ", not explained (below)"
                                                            : ", NOT converged");
    out << line;
  }
  if (has_values()) {
    std::snprintf(line, sizeof(line),
                  "  law delta(L) = %.4g + %.4g L [1/s]; at the rig's tube %.4g +- %.2g 1/s\n",
                  law_intercept_per_s, law_slope_per_s_m, coefficients.front().value,
                  coefficients.front().standard_error);
    out << line;
  }
  if (!reason.empty()) out << "  " << reason << "\n";
  out << "  pressure drop along the tube: not logged (p_in, p_out absent)\n";
  return out.str();
}

}  // namespace pneumaid
