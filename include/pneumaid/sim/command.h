// The valve command u(t) [V] as a zero-order hold: steps and sampled logs are
// the same thing, a list of knots where the value changes.
#pragma once

#include <string>
#include <vector>

namespace pneumaid {

struct CommandSignal {
  // Value before the first knot (and the value the lags start settled at).
  double initial_V = 0.0;
  // Knot times [s], strictly increasing; from time_s[i] on, u = value_V[i].
  std::vector<double> time_s;
  std::vector<double> value_V;

  // u at time t (the knot value holds from its own time on).
  double ValueAt(double t_s) const;
  bool IsValid(std::string* error) const;
};

// u = 0 before the first step; each step (time, value) sets u from its time on.
CommandSignal StepCommand(const std::vector<std::pair<double, double>>& steps);

// A logged command: held from each sample to the next; before the first
// sample the first value holds. Knots only where the value changes.
CommandSignal SampledCommand(const std::vector<double>& t_s, const std::vector<double>& u_V);

}  // namespace pneumaid
