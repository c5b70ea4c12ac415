#include "refine_residual.h"

#include "pneumaid/validate/validate.h"

namespace pneumaid::refine_internal {

std::vector<ExperimentCost> WholeRunCosts(const Parameters& params, const Unit& unit,
                                          const FitSpec& spec, const RefineOptions& options) {
  const Parameters conditioned = WithRigConditions(params, unit);
  const ParameterMap map = MakeParameterMap(conditioned, spec);
  const std::vector<double> theta = map.ThetaOf(conditioned);
  std::vector<ExperimentCost> costs;
  for (const FitExperiment& run : FittedRuns(conditioned, unit, spec, false)) {
    const ExperimentResidual residual(&conditioned, &map, &run, &options.simulation,
                                      options.jacobian);
    std::vector<double> r(static_cast<size_t>(residual.num_residuals()));
    const StartOffsets as_logged = {0, 0};
    const double* blocks[] = {theta.data(), as_logged.data()};
    const double cost =
        residual.Evaluate(blocks, r.data(), nullptr)
            ? 0.5 * Eigen::Map<Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size()))
                        .squaredNorm()
            : NAN;
    costs.push_back({run.id, cost, cost, run.residuals()});
  }
  return costs;
}

}  // namespace pneumaid::refine_internal
