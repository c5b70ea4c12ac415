#include "refine_parameters.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <string>

#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/parameter_table.h"

namespace pneumaid::refine_internal {

void CheckPathsIn(const Parameters& start, const FitSpec& spec) {
  for (const FreeParameter& p : spec.parameters) {
    double value = 0;
    if (!GetParameter(start, p.path, &value)) {
      throw InputError(spec.Name(), p.line, 0,
                       "parameter " + p.path + " is not in the starting parameter set");
    }
  }
}

ParameterMap MakeParameterMap(const Parameters& start, const FitSpec& spec) {
  CheckPathsIn(start, spec);
  ParameterMap map;
  map.free = spec.parameters;
  for (const FreeParameter& p : spec.parameters) {
    double value = 0;
    GetParameter(start, p.path, &value);
    if (!(value >= p.lower && value <= p.upper)) {
      throw InputError(spec.Name(), p.line, 0,
                       "the start value of " + p.path + " (" + FormatDouble(value) +
                           ") lies outside its bounds");
    }
  }
  return map;
}

Parameters WithValues(const Parameters& base, const ParameterMap& map, const double* theta) {
  Parameters p = base;
  for (int j = 0; j < map.size(); ++j) SetParameter(&p, map.free[j].path, map.ToValue(j, theta[j]));
  return p;
}

std::vector<std::vector<double>> LatinHypercube(const ParameterMap& map, int count,
                                                std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<std::vector<double>> points(count, std::vector<double>(map.size()));
  for (int j = 0; j < map.size(); ++j) {
    std::vector<int> strata(count);
    std::iota(strata.begin(), strata.end(), 0);
    std::shuffle(strata.begin(), strata.end(), random);
    for (int k = 0; k < count; ++k) {
      // Uniform in the scale coordinate (p, or ln p), not in theta.
      const double fraction = (strata[k] + unit(random)) / count;
      const double w = map.Low(j) + map.Span(j) * fraction;
      points[k][j] = map.ToTheta(j, map.IsLog(j) ? std::exp(w) : w);
    }
  }
  return points;
}

std::vector<std::vector<double>> TrustBox(const ParameterMap& map, const Parameters& start,
                                          int count, double box, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<std::vector<double>> points(count, std::vector<double>(map.size()));
  for (int j = 0; j < map.size(); ++j) {
    double value = 0;
    GetParameter(start, map.free[j].path, &value);
    // Half-width relative to the value: at least `box`, 3 standard errors
    // where the start has them, and wide (a factor 3) where it has none (a
    // coefficient its fit did not determine).
    const auto error = start.uncertainty.find(map.free[j].path);
    const bool known = error != start.uncertainty.end() && error->second > 0;
    // A linear parameter at 0 gets a box measured on its span.
    const double size = std::max(std::fabs(value), 1e-3 * (map.free[j].upper - map.free[j].lower));
    double width = known ? std::max(box, 3 * error->second / size) : 2.0;
    double low = 0, high = 0;
    if (map.IsLog(j)) {
      width = std::min(width, 9.0);
      low = value / (1 + width);
      high = value * (1 + width);
    } else {
      low = value - std::min(width * size, value > 0 ? 0.95 * value : width * size);
      high = value + width * size;
    }
    low = std::max(low, map.free[j].lower);
    high = std::min(high, map.free[j].upper);
    std::vector<int> strata(count);
    std::iota(strata.begin(), strata.end(), 0);
    std::shuffle(strata.begin(), strata.end(), random);
    for (int k = 0; k < count; ++k) {
      const double fraction = (strata[k] + unit(random)) / count;
      const double p = map.IsLog(j) && low > 0 ? low * std::pow(high / low, fraction)
                                               : low + (high - low) * fraction;
      points[k][j] = map.ToTheta(j, p);
    }
  }
  return points;
}

StartPrior MakeStartPrior(const ParameterMap& map, const Parameters& centre,
                          const Parameters& start, double errors, double fraction) {
  StartPrior prior;
  for (int j = 0; j < map.size(); ++j) {
    const std::string& path = map.free[j].path;
    double value = 0;
    const bool centred = GetParameter(centre, path, &value) && (!map.IsLog(j) || value > 0);
    if (!centred) GetParameter(start, path, &value);
    const auto error = centre.uncertainty.find(path);
    const bool known = centred && error != centre.uncertainty.end() && error->second > 0;
    const double span = map.free[j].upper - map.free[j].lower;
    if (map.IsLog(j)) {
      prior.w.push_back(std::log(value));
      prior.sigma.push_back(known ? std::log1p(std::max(errors * error->second / value, fraction))
                                  : std::log(3.0));
    } else {
      prior.w.push_back(value);
      const double size = std::max(std::fabs(value), 1e-3 * span);
      prior.sigma.push_back(known ? std::max(errors * error->second, fraction * size) : size);
    }
  }
  return prior;
}

StartPriorCost::StartPriorCost(const ParameterMap* map, StartPrior prior)
    : map_(map), prior_(std::move(prior)) {
  set_num_residuals(map->size());
  mutable_parameter_block_sizes()->push_back(map->size());
}

bool StartPriorCost::Evaluate(double const* const* theta, double* residuals,
                              double** jacobians) const {
  const int m = map_->size();
  for (int j = 0; j < m; ++j) {
    residuals[j] = (map_->ScaleCoordinate(j, theta[0][j]) - prior_.w[j]) / prior_.sigma[j];
  }
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    std::fill(jacobians[0], jacobians[0] + m * m, 0.0);
    for (int j = 0; j < m; ++j)
      jacobians[0][j * m + j] = map_->ScaleDerivative(j, theta[0][j]) / prior_.sigma[j];
  }
  return true;
}

void ForgetMoved(const Parameters& start, const FitSpec& spec, Parameters* p) {
  for (const FreeParameter& free : spec.parameters) {
    double before = 0, after = 0;
    if (GetParameter(start, free.path, &before) && GetParameter(*p, free.path, &after) &&
        before != after) {
      p->uncertainty.erase(free.path);
    }
  }
}

}  // namespace pneumaid::refine_internal
