#include "refine_residual.h"

#include <algorithm>
#include <cstdint>
#include <utility>

#include "../util/splitmix64.h"
#include "pneumaid/validate/validate.h"

namespace pneumaid::refine_internal {

FittedRunSet::FittedRunSet(const Parameters& params, const Unit& unit, const FitSpec& spec,
                           const RefineOptions& options, bool windows, std::size_t max_runs)
    : conditioned_(WithRigConditions(params, unit)),
      map_(MakeParameterMap(conditioned_, spec)),
      theta_(map_.ThetaOf(conditioned_)),
      simulation_(options.simulation),
      jacobian_(options.jacobian) {
  std::vector<FitExperiment> all =
      FittedRuns(conditioned_, unit, spec, windows, options.lag_starts.get());
  const std::vector<bool> kept = SubsetByHash(all.size(), max_runs);
  for (std::size_t k = 0; k < all.size(); ++k) {
    if (kept[k]) runs_.push_back(std::move(all[k]));
  }
}

Eigen::VectorXd FittedRunSet::Residuals(std::size_t k, FrictionUse* use) const {
  const FitExperiment& run = runs_[k];
  const ExperimentResidual residual(&conditioned_, &map_, &run, &simulation_, jacobian_);
  const StartOffsets as_logged = {0, 0};
  const std::vector<double> z = Coordinates(run, theta_.data(), map_.size(), as_logged.data());
  Eigen::VectorXd r;
  if (!residual.ResidualsAt(z, &r, use)) r.setConstant(NAN);
  return r;
}

std::vector<RunResiduals> FittedRunResiduals(const Parameters& params, const Unit& unit,
                                             const FitSpec& spec, const RefineOptions& options,
                                             bool windows, std::size_t max_runs) {
  FittedRunSet set(params, unit, spec, options, windows, max_runs);
  std::vector<Eigen::VectorXd> residuals;
  for (std::size_t k = 0; k < set.runs().size(); ++k) residuals.push_back(set.Residuals(k));
  std::vector<FitExperiment> runs = set.ReleaseRuns();
  std::vector<RunResiduals> out;
  for (std::size_t k = 0; k < runs.size(); ++k)
    out.push_back({std::move(runs[k]), std::move(residuals[k])});
  return out;
}

std::vector<bool> SubsetByHash(std::size_t n, std::size_t count) {
  count = SubsetSize(n, count);
  if (count == n) return std::vector<bool>(n, true);
  std::vector<std::pair<std::uint64_t, std::size_t>> keys(n);
  for (std::size_t i = 0; i < n; ++i)
    keys[i] = {internal::SplitMix64Mix(i + internal::kSplitMix64Increment), i};
  std::nth_element(keys.begin(), keys.begin() + static_cast<std::ptrdiff_t>(count), keys.end());
  std::vector<bool> kept(n, false);
  for (std::size_t i = 0; i < count; ++i) kept[keys[i].second] = true;
  return kept;
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
