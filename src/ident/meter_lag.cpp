#include "meter_lag.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "centred_mean.h"
#include "pneumaid/io/log_notes.h"
#include "uniform_clock.h"

namespace pneumaid::internal {

LagInverse PlanLagInverse(double period_s, double tau_s) {
  LagInverse plan;
  if (!(tau_s > 0) || !(period_s > 0)) return plan;
  const double keep = std::exp(-period_s / tau_s);
  const double exact = std::sqrt(1 + keep * keep) / -std::expm1(-period_s / tau_s);
  const auto gain = [exact](int m) { return std::sqrt(exact * exact + m - 1) / m; };
  int m = 1;
  // At most a mean over the whole lag's worth of samples and then some: the
  // gain falls below 1.5 by m = 2 G, so the loop ends; the cap guards a lag
  // absurdly longer than the sampling interval.
  while (gain(m) > kMaxLagNoiseGain && m < 1000001) m += 2;
  plan.samples = m;
  plan.noise_gain = std::max(1.0, gain(m));
  return plan;
}

std::vector<double> LagUndone(const std::vector<double>& t_s, const std::vector<double>& reading,
                              double tau_s) {
  const std::size_t n = reading.size();
  if (!(tau_s > 0) || n < 2 || t_s.size() != n) return reading;
  // The exact inverse: y[i] = k y[i-1] + (1 - k) u[i-1] (the input held
  // between samples), so u[i-1] = (y[i] - k y[i-1]) / (1 - k).
  std::vector<double> exact(n);
  for (std::size_t i = 1; i < n; ++i) {
    const double dt = t_s[i] - t_s[i - 1];
    exact[i - 1] =
        dt > 0 ? (reading[i] - std::exp(-dt / tau_s) * reading[i - 1]) / -std::expm1(-dt / tau_s)
               : reading[i - 1];
  }
  exact[n - 1] = exact[n - 2];
  const int m = PlanLagInverse(MedianInterval(t_s), tau_s).samples;
  if (m <= 1) return exact;
  // The last sample, which no later reading inverts, is the one before's.
  std::vector<double> out = CentredMean(exact, static_cast<std::size_t>(m / 2), n - 1);
  out.push_back(out.back());
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
