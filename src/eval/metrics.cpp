#include "pneumaid/eval/metrics.h"

#include <cmath>
#include <numeric>

#include "pneumaid/eval/lag.h"

namespace pneumaid {

ChannelMetrics CompareChannel(const std::vector<double>& measured,
                              const std::vector<double>& simulated,
                              std::optional<double> noise_sigma) {
  ChannelMetrics out;
  const std::size_t n = std::min(measured.size(), simulated.size());
  if (n == 0) return out;
  const double mean = std::accumulate(measured.begin(), measured.begin() + n, 0.0) / n;
  double error_sq = 0, spread_sq = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double error = measured[i] - simulated[i];
    error_sq += error * error;
    spread_sq += (measured[i] - mean) * (measured[i] - mean);
    out.max_abs = std::max(out.max_abs, std::fabs(error));
  }
  out.rmse = std::sqrt(error_sq / n);
  const double spread = std::sqrt(spread_sq);
  const double noise_floor = noise_sigma ? *noise_sigma * std::sqrt(static_cast<double>(n)) : 0.0;
  if (spread > noise_floor && spread > 0) {
    out.nrmse_fit_percent = 100.0 * (1.0 - std::sqrt(error_sq) / spread);
  }
  return out;
}

std::map<std::string, ChannelMetrics> CompareRuns(
    const Trajectory& measured, const Trajectory& simulated,
    const std::map<std::string, double>& noise_sigma) {
  std::map<std::string, ChannelMetrics> out;
  for (const auto& [name, member] : kComparedChannels) {
    const auto& y = measured.*member;
    const auto& y_sim = simulated.*member;
    if (y.empty() || y_sim.size() != y.size()) continue;
    const auto sigma = noise_sigma.find(name);
    out[name] = CompareChannel(
        y, y_sim, sigma == noise_sigma.end() ? std::nullopt : std::optional<double>(sigma->second));
  }
  return out;
}

std::vector<double> FirstOrderLag(const std::vector<double>& t_s, const std::vector<double>& signal,
                                  double tau_s) {
  std::vector<double> out = signal;
  if (tau_s > 0)
    ApplyFirstOrderLag([&t_s](std::size_t i) { return t_s[i] - t_s[i - 1]; }, tau_s, &out);
  return out;
}

}  // namespace pneumaid
