#include "refine_residual.h"

#include "pneumaid/validate/validate.h"

namespace pneumaid::refine_internal {

std::vector<RunResiduals> FittedRunResiduals(const Parameters& params, const Unit& unit,
                                             const FitSpec& spec, const RefineOptions& options,
                                             bool windows) {
  const Parameters conditioned = WithRigConditions(params, unit);
  const ParameterMap map = MakeParameterMap(conditioned, spec);
  const std::vector<double> theta = map.ThetaOf(conditioned);
  std::vector<RunResiduals> out;
  for (FitExperiment& run : FittedRuns(conditioned, unit, spec, windows)) {
    const ExperimentResidual residual(&conditioned, &map, &run, &options.simulation,
                                      options.jacobian);
    Eigen::VectorXd r(residual.num_residuals());
    const StartOffsets as_logged = {0, 0};
    const double* blocks[] = {theta.data(), as_logged.data()};
    if (!residual.Evaluate(blocks, r.data(), nullptr)) r.setConstant(NAN);
    out.push_back({std::move(run), std::move(r)});
  }
  return out;
}

std::vector<ExperimentCost> CostsOf(const std::vector<RunResiduals>& runs) {
  std::vector<ExperimentCost> costs;
  for (const RunResiduals& run : runs) {
    const double cost = 0.5 * run.residuals.squaredNorm();  // NaN where not simulated
    costs.push_back({run.run.id, cost, cost, run.run.residuals()});
  }
  return costs;
}

std::vector<ExperimentCost> WholeRunCosts(const Parameters& params, const Unit& unit,
                                          const FitSpec& spec, const RefineOptions& options) {
  return CostsOf(WholeRunResiduals(params, unit, spec, options));
}

}  // namespace pneumaid::refine_internal
