#include "pneumaid/sim/command.h"

#include <algorithm>
#include <cmath>

namespace pneumaid {

double CommandSignal::ValueAt(double t_s) const {
  const auto after = std::upper_bound(time_s.begin(), time_s.end(), t_s);
  if (after == time_s.begin()) return initial_V;
  return value_V[static_cast<size_t>(after - time_s.begin()) - 1];
}

bool CommandSignal::IsValid(std::string* error) const {
  const auto fail = [error](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (time_s.size() != value_V.size()) return fail("command: times and values differ in length");
  if (!std::isfinite(initial_V)) return fail("command: initial value is not finite");
  for (size_t i = 0; i < time_s.size(); ++i) {
    if (!std::isfinite(time_s[i]) || !std::isfinite(value_V[i])) {
      return fail("command: knot " + std::to_string(i) + " is not finite");
    }
    if (i > 0 && !(time_s[i] > time_s[i - 1])) {
      return fail("command: knot times must be strictly increasing (knot " + std::to_string(i) +
                  ")");
    }
  }
  return true;
}

CommandSignal StepCommand(const std::vector<std::pair<double, double>>& steps) {
  auto sorted = steps;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  CommandSignal command;
  for (const auto& [time, value] : sorted) {
    if (!command.time_s.empty() && command.time_s.back() == time) {
      command.value_V.back() = value;  // the later of two steps at one time wins
      continue;
    }
    command.time_s.push_back(time);
    command.value_V.push_back(value);
  }
  return command;
}

CommandSignal SampledCommand(const std::vector<double>& t_s, const std::vector<double>& u_V) {
  CommandSignal command;
  command.initial_V = u_V.empty() ? 0.0 : u_V.front();
  // Only the samples where u changes are knots: a held command costs the
  // integrator nothing, and a logged step is the same signal as the step.
  for (std::size_t i = 0; i < t_s.size() && i < u_V.size(); ++i) {
    const double previous = i == 0 ? command.initial_V : u_V[i - 1];
    if (i > 0 && u_V[i] == previous) continue;
    if (i == 0) continue;  // equal to initial_V by construction
    command.time_s.push_back(t_s[i]);
    command.value_V.push_back(u_V[i]);
  }
  return command;
}

}  // namespace pneumaid
