#include "refine_parameters.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <string>

#include "pneumaid/io/input_error.h"
#include "pneumaid/model/parameter_table.h"

namespace pneumaid::refine_internal {

ParameterMap MakeParameterMap(const Parameters& start, const FitSpec& spec) {
  ParameterMap map;
  map.free = spec.parameters;
  for (const FreeParameter& p : spec.parameters) {
    double value = 0;
    if (!GetParameter(start, p.path, &value)) {
      throw InputError(spec.source, 0, 0,
                       "parameter " + p.path + " is not in the starting parameter set");
    }
    if (!(value >= p.lower && value <= p.upper)) {
      throw InputError(spec.source, 0, 0,
                       "the start value of " + p.path + " (" + std::to_string(value) +
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

}  // namespace pneumaid::refine_internal
