#include "meter_lag.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace pneumaid::internal {

LagInverse PlanLagInverse(double period_s, double tau_s) {
  LagInverse plan;
  if (!(tau_s > 0) || !(period_s > 0)) return plan;
  const double keep = std::exp(-period_s / tau_s);
  const double exact_gain = std::sqrt(1 + keep * keep) / (1 - keep);
  // The mean of m successive inverse values telescopes to a difference over
  // m samples: its noise gain is about the exact one's over m.
  plan.samples = std::max(1, static_cast<int>(std::ceil(exact_gain / kMaxLagNoiseGain)));
  plan.noise_gain = std::max(1.0, exact_gain / plan.samples);
  return plan;
}

std::vector<double> LagUndone(const std::vector<double>& t_s, const std::vector<double>& reading,
                              double tau_s) {
  const std::size_t n = std::min(t_s.size(), reading.size());
  if (!(tau_s > 0) || n < 2) return reading;
  // The exact inverse: y[i] = k y[i-1] + (1 - k) u[i-1] (the input held
  // between samples), so u[i-1] = (y[i] - k y[i-1]) / (1 - k).
  std::vector<double> exact(n);
  for (std::size_t i = 1; i < n; ++i) {
    const double keep = std::exp(-(t_s[i] - t_s[i - 1]) / tau_s);
    exact[i - 1] = (reading[i] - keep * reading[i - 1]) / (1 - keep);
  }
  exact[n - 1] = exact[n - 2];
  std::vector<double> intervals(n - 1);
  for (std::size_t i = 1; i < n; ++i) intervals[i - 1] = t_s[i] - t_s[i - 1];
  std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
  const int m = PlanLagInverse(intervals[intervals.size() / 2], tau_s).samples;
  if (m <= 1) return exact;
  // A moving mean of m samples centred on each (running sums).
  std::vector<double> sum(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) sum[i + 1] = sum[i] + exact[i];
  std::vector<double> out(n);
  const std::size_t before = static_cast<std::size_t>(m - 1) / 2, after = m / 2;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t lo = i >= before ? i - before : 0, hi = std::min(n - 1, i + after);
    out[i] = (sum[hi + 1] - sum[lo]) / static_cast<double>(hi - lo + 1);
  }
  return out;
}

std::shared_ptr<const Experiment> WithLagsUndone(const Experiment& e, const Manifest& manifest,
                                                 const std::vector<std::string>& columns) {
  std::shared_ptr<Experiment> out;
  for (const std::string& name : columns) {
    const double tau_s = manifest.DeclaredTau(name, 0.0);
    if (!(tau_s > 0) || e.column(name).empty()) continue;
    if (!out) out = std::make_shared<Experiment>(e);
    out->columns[name] = LagUndone(e.column("t"), e.column(name), tau_s);
  }
  return out;
}

}  // namespace pneumaid::internal
