#include "tube_from_meters.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "../util/golden_section.h"
#include "determination.h"
#include "pneumaid/eval/lag.h"

namespace pneumaid::internal {
namespace {

// A tube log whose command is not held (a ramp, a sampled signal) gives no
// level flows to solve for. Both meters read lags of the one valve flow f:
// q_in = L_in f and q_out = L_out L_delta f, and first-order lags commute, so
// L_in q_out = L_out L_delta q_in whatever f is (the valve's own lag too):
// the residual of that identity, filtered from the readings alone, is fitted
// over delta (the scan, then a golden-section search in log delta).
class CrossFilter {
 public:
  CrossFilter(const Experiment& e, const Manifest& manifest)
      : t_(e.column("t")),
        q_in_(e.column("q_in")),
        tau_in_s_(manifest.DeclaredTau("q_in", 0.0)),
        tau_out_s_(manifest.DeclaredTau("q_out", 0.0)),
        out_through_in_(e.column("q_out")) {
    if (tau_in_s_ > 0) ApplyFirstOrderLag(Intervals(), tau_in_s_, &out_through_in_);
    out_noise_gain_ = tau_in_s_ > 0 ? PowerGain({tau_in_s_}) : 1.0;  // q_out's noise through L_in
  }

  // L_in q_out - L_out L_delta q_in.
  std::vector<double> Residuals(double delta_per_s) const {
    std::vector<double> r = q_in_;
    ApplyFirstOrderLag(Intervals(), 1.0 / delta_per_s, &r);
    if (tau_out_s_ > 0) ApplyFirstOrderLag(Intervals(), tau_out_s_, &r);
    for (std::size_t i = 0; i < r.size(); ++i) r[i] = out_through_in_[i] - r[i];
    return r;
  }

  double Squares(double delta_per_s) const {
    double sum = 0;
    for (double r : Residuals(delta_per_s)) sum += r * r;
    return sum;
  }

  // What the meters' white noise (sigma_in, sigma_out) leaves in one
  // residual: each noise through its filters, the power gain read off the
  // filters' impulse response at the mean interval.
  double NoiseVariance(double delta_per_s, double sigma_in, double sigma_out) const {
    return sigma_in * sigma_in * PowerGain({1.0 / delta_per_s, tau_out_s_}) +
           sigma_out * sigma_out * out_noise_gain_;
  }

  // Var(J'r) under the meters' white noise: sigma_out^2 |L_in' J|^2 +
  // sigma_in^2 |L_delta' L_out' J|^2, each adjoint a lag run backwards.
  double ScoreNoiseVariance(const std::vector<double>& j, double delta_per_s, double sigma_in,
                            double sigma_out) const {
    std::vector<double> through_in = j, through_out = j;
    if (tau_in_s_ > 0) AdjointLag(tau_in_s_, &through_in);
    if (tau_out_s_ > 0) AdjointLag(tau_out_s_, &through_out);
    AdjointLag(1.0 / delta_per_s, &through_out);
    double in = 0, out = 0;
    for (double v : through_in) out += v * v;  // n_out reaches r through L_in
    for (double v : through_out) in += v * v;
    return sigma_out * sigma_out * out + sigma_in * sigma_in * in;
  }

  std::size_t samples() const { return t_.size(); }
  double correlation_time_s(double delta_per_s) const {
    return std::max({tau_in_s_, tau_out_s_, 1.0 / delta_per_s});
  }
  double Time(std::size_t i) const { return t_[i]; }

 private:
  // The white-noise power gain of the lags `taus` in turn: the sum of the
  // squares of their impulse response at the mean interval.
  double PowerGain(const std::vector<double>& taus) const {
    std::vector<double> impulse(std::min<std::size_t>(t_.size(), 200000), 0.0);
    if (impulse.size() < 2) return 1.0;
    impulse[1] = 1.0;  // the filters act from the next sample on
    const double h = (t_.back() - t_.front()) / static_cast<double>(t_.size() - 1);
    for (double tau : taus) {
      if (tau > 0) ApplyFirstOrderLag([h](std::size_t) { return h; }, tau, &impulse);
    }
    double sum = 0;
    for (std::size_t i = 1; i < impulse.size(); ++i) sum += impulse[i] * impulse[i];
    return sum;
  }

  // w <- L' w for the lag L of ApplyFirstOrderLag (y_0 = x_0, y_i = a_i
  // y_(i-1) + (1 - a_i) x_(i-1)): lambda_k = w_k + a_(k+1) lambda_(k+1)
  // backwards, then x_j's share is (1 - a_(j+1)) lambda_(j+1), plus lambda_0
  // for x_0.
  void AdjointLag(double tau_s, std::vector<double>* w) const {
    const std::size_t n = w->size();
    if (n < 2) return;
    std::vector<double> lambda(*w);
    std::vector<double> keep(n, 0.0);
    for (std::size_t i = 1; i < n; ++i) keep[i] = std::exp(-(t_[i] - t_[i - 1]) / tau_s);
    for (std::size_t k = n - 1; k-- > 0;) lambda[k] += keep[k + 1] * lambda[k + 1];
    for (std::size_t j = 0; j + 1 < n; ++j) (*w)[j] = (1 - keep[j + 1]) * lambda[j + 1];
    (*w)[n - 1] = 0.0;
    (*w)[0] += lambda[0];
  }

  std::function<double(std::size_t)> Intervals() const {
    return [this](std::size_t i) { return t_[i] - t_[i - 1]; };
  }
  const std::vector<double>& t_;
  const std::vector<double>& q_in_;
  double tau_in_s_, tau_out_s_;
  std::vector<double> out_through_in_;
  double out_noise_gain_ = 1.0;
};

}  // namespace

void FitTubeFromMeters(const Experiment& e, const Manifest& manifest,
                       const PipelineFitOptions& options, double sigma_in, double sigma_out,
                       TubeFit* fit) {
  const CrossFilter filter(e, manifest);
  const DeltaScan scan(options);
  const auto at = [&scan](double k) { return scan.At(k); };
  // The meters' noise passes through L_out L_delta, more of it the faster
  // the tube: its expected share of the squares is taken off, so that noise
  // does not pull delta (an errors-in-variables correction).
  const double n = static_cast<double>(filter.samples());
  const auto objective = [&](double delta) {
    return filter.Squares(delta) - n * filter.NoiseVariance(delta, sigma_in, sigma_out);
  };
  int best_k = 0;
  double best = INFINITY;
  for (int k = 0; k <= scan.points; ++k) {
    const double value = objective(at(k));
    if (value < best) best = value, best_k = k;
  }
  // Golden section in k (log delta) across the best scan point's neighbours.
  double low = std::max(0.0, best_k - 1.0), high = std::min<double>(scan.points, best_k + 1.0);
  // The interval's middle after 60 steps (its ends are 1e-12 of a step apart).
  const auto at_k = [&](double k) { return objective(at(k)); };
  const internal::GoldenSectionMinimum found = internal::GoldenSection(at_k, low, high, 60);
  const double delta = at(0.5 * (found.low + found.high));
  fit->iterations = 60;
  // Sensitivities by central differences. The error: the meters' noise
  // through the filters, widened by the reduced chi-square where the fit is
  // worse than the noise, or the sandwich clustered by blocks of five
  // correlation times where that is larger.
  const double step = 1e-4 * delta;
  const std::vector<double> r = filter.Residuals(delta), up = filter.Residuals(delta + step),
                            down = filter.Residuals(delta - step);
  const double block_s = 5 * filter.correlation_time_s(delta);
  std::vector<double> jacobian(r.size());
  double information = 0, meat = 0, score = 0, squares = 0;
  double block_start = filter.Time(0);
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (filter.Time(i) - block_start > block_s) {
      meat += score * score;
      score = 0;
      block_start = filter.Time(i);
    }
    const double j = jacobian[i] = (up[i] - down[i]) / (2 * step);
    information += j * j;
    score += j * r[i];
    squares += r[i] * r[i];
  }
  meat += score * score;
  const double noise = filter.NoiseVariance(delta, sigma_in, sigma_out);
  fit->reduced_chi_square = squares / n / noise;
  fit->initial_cost = 0.5 * filter.Squares(options.initial_delta_per_s) / noise;
  fit->final_cost = 0.5 * squares / noise;
  for (double q : e.column("q_in")) {
    if (std::fabs(q) > std::fabs(fit->flow_kg_per_s)) fit->flow_kg_per_s = q;
  }
  const double from_noise = filter.ScoreNoiseVariance(jacobian, delta, sigma_in, sigma_out) *
                            std::max(1.0, fit->reduced_chi_square);
  const double error =
      information > 0 ? std::sqrt(std::max(from_noise, meat)) / information : INFINITY;
  char note[240];
  if (!internal::IsDetermined(delta, error, 0.0, options.determined_relative_error)) {
    std::snprintf(note, sizeof(note),
                  "delta is not determined by this log (%.3g +- %.2g 1/s from the meters' "
                  "readings alone: the command is not held)",
                  delta, error);
    fit->status = FitStatus::kNotFitted;
    fit->reason = note;
    fit->coefficients.front().held = note;
    return;
  }
  fit->status = FitStatus::kConverged;
  fit->reason = "the command is not held: delta from the meters' readings alone";
  fit->coefficients.front().value = delta;
  fit->coefficients.front().standard_error = error;
  fit->covariance = Eigen::MatrixXd::Constant(1, 1, error * error);
}

}  // namespace pneumaid::internal
