#include "pneumaid/ident/pipeline_fit.h"

#include <ceres/ceres.h>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "pneumaid/eval/lag.h"

namespace pneumaid {
namespace {

// Residuals of both meters for theta = (flow amplitude [kg/s], delta [1/s]):
// the valve's flow is a step at the command's step time; q_in is it through
// the inlet meter, q_out through Eq. 5 and the outlet meter.
struct TubeStepResiduals {
  const std::vector<double>* t;
  const std::vector<double>* q_in;
  const std::vector<double>* q_out;
  double step_time_s, tau_in_s, tau_out_s, sigma_in, sigma_out;

  template <typename T>
  bool operator()(T const* const* parameters, T* residuals) const {
    const T* theta = parameters[0];
    const std::size_t n = t->size();
    std::vector<T> flow(n);
    for (std::size_t i = 0; i < n; ++i) flow[i] = (*t)[i] >= step_time_s ? theta[0] : T(0.0);
    const auto interval = [this](std::size_t i) { return (*t)[i] - (*t)[i - 1]; };
    std::vector<T> inlet = flow;
    if (tau_in_s > 0) ApplyFirstOrderLag(interval, T(tau_in_s), &inlet);
    ApplyFirstOrderLag(interval, T(1.0) / theta[1], &flow);
    if (tau_out_s > 0) ApplyFirstOrderLag(interval, T(tau_out_s), &flow);
    for (std::size_t i = 0; i < n; ++i) {
      residuals[i] = (inlet[i] - (*q_in)[i]) / sigma_in;
      residuals[n + i] = (flow[i] - (*q_out)[i]) / sigma_out;
    }
    return true;
  }
};

double Spread(const std::vector<double>& v, std::size_t end) {
  // Noise level from the samples before the step (flow should be zero there).
  double mean = 0, sq = 0;
  for (std::size_t i = 0; i < end; ++i) mean += v[i];
  mean /= static_cast<double>(end);
  for (std::size_t i = 0; i < end; ++i) sq += (v[i] - mean) * (v[i] - mean);
  return std::sqrt(sq / static_cast<double>(end - 1));
}

TubeFit FitTube(const Experiment& e, const Manifest& manifest, const PipelineFitOptions& options) {
  TubeFit fit;
  fit.experiment = e.entry.id;
  fit.tube_length_m = e.entry.tube_length_m.value_or(0.0);
  const auto &t = e.column("t"), &u = e.column("u");
  std::size_t step = 0;
  while (step < u.size() && u[step] <= 0) ++step;
  if (step < 10 || step + 10 >= u.size()) {
    fit.note = "no step of the command with samples before and after it";
    return fit;
  }
  for (std::size_t i = step; i < u.size(); ++i) {
    if (u[i] != u[step]) {
      fit.note = "the command must be one step and then held";
      return fit;
    }
  }
  const double sigma_in = manifest.DeclaredSigma("q_in", Spread(e.column("q_in"), step));
  const double sigma_out = manifest.DeclaredSigma("q_out", Spread(e.column("q_out"), step));
  const std::size_t n = t.size();
  const double tail_flow = e.column("q_in").back();
  double theta[2] = {tail_flow, options.initial_delta_per_s};
  ceres::Problem problem;
  auto* cost = new ceres::DynamicAutoDiffCostFunction<TubeStepResiduals, 4>(new TubeStepResiduals{
      &t, &e.column("q_in"), &e.column("q_out"), t[step], manifest.DeclaredTau("q_in", 0.0),
      manifest.DeclaredTau("q_out", 0.0), std::max(sigma_in, 1e-12), std::max(sigma_out, 1e-12)});
  cost->AddParameterBlock(2);
  cost->SetNumResiduals(static_cast<int>(2 * n));
  problem.AddResidualBlock(cost, nullptr, theta);
  problem.SetParameterLowerBound(theta, 1, 1e-3);  // delta > 0
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  fit.final_cost = summary.final_cost;
  fit.iterations = static_cast<int>(summary.iterations.size());
  if (!summary.IsSolutionUsable()) {
    fit.note = "Ceres did not converge: " + summary.message;
    return fit;
  }
  ceres::Covariance covariance{ceres::Covariance::Options{}};
  double c[4];
  std::vector<std::pair<const double*, const double*>> blocks = {{theta, theta}};
  if (!covariance.Compute(blocks, &problem) || !covariance.GetCovarianceBlock(theta, theta, c)) {
    fit.note = "delta is not identifiable from this log (singular covariance)";
    return fit;
  }
  fit.fitted = true;
  fit.flow_kg_per_s = theta[0];
  fit.delta_per_s = theta[1];
  fit.delta_standard_error = std::sqrt(c[3]);
  return fit;
}

// Weighted straight line through (L, delta) with its value and error at L0.
void FitLaw(double rig_length_m, PipelineFitResult* result) {
  double s = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  int count = 0;
  for (const auto& tube : result->tubes) {
    if (!tube.fitted) continue;
    const double w = 1.0 / (tube.delta_standard_error * tube.delta_standard_error);
    s += w;
    sx += w * tube.tube_length_m;
    sy += w * tube.delta_per_s;
    sxx += w * tube.tube_length_m * tube.tube_length_m;
    sxy += w * tube.tube_length_m * tube.delta_per_s;
    ++count;
  }
  if (count == 0) {
    result->note = "no tube could be fitted";
    return;
  }
  result->fitted = true;
  const double det = s * sxx - sx * sx;
  if (count == 1 || det <= 1e-12 * s * sxx) {  // one length: a flat law
    result->law_intercept_per_s = sy / s;
    result->law_slope_per_s_m = 0;
    result->delta_at_rig_per_s = sy / s;
    result->delta_at_rig_standard_error = std::sqrt(1.0 / s);
    result->note = "one tube length: delta(L) taken as flat";
    return;
  }
  result->law_slope_per_s_m = (s * sxy - sx * sy) / det;
  result->law_intercept_per_s = (sxx * sy - sx * sxy) / det;
  const double L = rig_length_m;
  result->delta_at_rig_per_s = result->law_intercept_per_s + result->law_slope_per_s_m * L;
  // Var(a + b L) from the weighted normal equations' inverse.
  result->delta_at_rig_standard_error = std::sqrt((sxx - 2 * L * sx + L * L * s) / det);
}

}  // namespace

bool PipelineFitOptions::IsValid(std::string* error) const {
  if (max_iterations < 1 || !(initial_delta_per_s > 0)) {
    if (error) *error = "max_iterations must be >= 1 and initial_delta_per_s > 0";
    return false;
  }
  return true;
}

PipelineFitResult FitPipeline(const Unit& unit, const PipelineFitOptions& options) {
  PipelineFitResult result;
  for (const Experiment& e : unit.experiments) {
    if (e.entry.kind == ExperimentKind::kPipeline) {
      result.tubes.push_back(FitTube(e, unit.manifest, options));
    }
  }
  FitLaw(unit.manifest.rig.tube_length_m, &result);
  return result;
}

std::string PipelineFitResult::BriefReport() const {
  std::ostringstream out;
  char line[200];
  out << "Pipeline delta fit: " << tubes.size() << " tube logs\n";
  for (const auto& tube : tubes) {
    if (!tube.fitted) {
      out << "  " << tube.experiment << ": not fitted (" << tube.note << ")\n";
      continue;
    }
    std::snprintf(line, sizeof(line), "  %s: L %.3g m, delta %.4g +- %.2g 1/s (%d iterations)\n",
                  tube.experiment.c_str(), tube.tube_length_m, tube.delta_per_s,
                  tube.delta_standard_error, tube.iterations);
    out << line;
  }
  if (fitted) {
    std::snprintf(line, sizeof(line),
                  "  law delta(L) = %.4g + %.4g L [1/s]; at the rig's tube %.4g +- %.2g 1/s\n",
                  law_intercept_per_s, law_slope_per_s_m, delta_at_rig_per_s,
                  delta_at_rig_standard_error);
    out << line;
  }
  if (!note.empty()) out << "  " << note << "\n";
  out << "  pressure drop along the tube: not logged (p_in, p_out absent)\n";
  return out.str();
}

}  // namespace pneumaid
