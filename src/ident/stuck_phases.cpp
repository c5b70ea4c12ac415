#include "stuck_phases.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>

#include "../util/median.h"
#include "pneumaid/io/channel_noise.h"

namespace pneumaid::internal {

namespace {

// Slope [per sample] and curvature (second derivative, per sample^2) of
// x[from, to) by a least-squares quadratic.
std::pair<double, double> SlopeAndCurvature(const std::vector<double>& x, std::size_t from,
                                            std::size_t to) {
  const double n = static_cast<double>(to - from), mid = 0.5 * (n - 1);
  double sxy = 0, sxx = 0, m2 = 0;
  for (std::size_t i = from; i < to; ++i) m2 += std::pow(static_cast<double>(i - from) - mid, 2);
  m2 /= n;
  double sqy = 0, sqq = 0;
  for (std::size_t i = from; i < to; ++i) {
    const double j = static_cast<double>(i - from) - mid, q = j * j - m2;
    sxy += j * x[i];
    sxx += j * j;
    sqy += q * x[i];
    sqq += q * q;
  }
  return {sxx > 0 ? sxy / sxx : 0.0, sqq > 0 ? 2 * sqy / sqq : 0.0};
}

// The noise of SlopeAndCurvature over n samples of position noise sigma.
std::pair<double, double> SlopeAndCurvatureNoise(double sigma, double n) {
  const double mid = 0.5 * (n - 1);
  double sxx = 0, m2 = 0, sqq = 0;
  for (int i = 0; i < n; ++i) sxx += (i - mid) * (i - mid);
  m2 = sxx / n;
  for (int i = 0; i < n; ++i) sqq += std::pow((i - mid) * (i - mid) - m2, 2);
  return {sigma / std::sqrt(sxx), 2 * sigma / std::sqrt(sqq)};
}

}  // namespace

double PositionNoise(const Unit& unit) { return std::max(NoiseSigma(unit, "x"), 1e-7); }

double PositionQuantum(const std::vector<double>& x) {
  double quantum = 0;
  for (std::size_t i = 1; i < x.size(); ++i) {
    const double step = std::fabs(x[i] - x[i - 1]);
    if (step > 0 && (quantum == 0 || step < quantum)) quantum = step;
  }
  return quantum;
}

StuckRule StuckRuleOf(const FrictionFitOptions& options, double sigma_x_m, double quantum_m,
                      double period_s) {
  assert(period_s > 0 && std::isfinite(period_s));
  StuckRule rule;
  rule.band_m = options.stuck_band_m + std::max(6.0 * sigma_x_m, kRestQuanta * quantum_m);
  rule.min_samples = std::max(options.min_stuck_samples,
                              static_cast<int>(std::ceil(options.min_stuck_s / period_s)));
  rule.max_slope_m_per_sample = options.max_stuck_speed_m_per_s * period_s;
  rule.max_curvature_m_per_sample2 = options.max_stuck_acceleration_m_per_s2 * period_s * period_s;
  rule.sigma_x_m = sigma_x_m;
  rule.rest_tolerance_m = std::max(kRestSigmas * sigma_x_m, kRestQuanta * quantum_m);
  return rule;
}

Runs StuckRuns(const std::vector<double>& x, const StuckRule& rule) {
  Runs runs;
  std::size_t begin = 0;
  while (begin < x.size()) {
    double low = x[begin], high = x[begin];
    std::size_t end = begin + 1;
    while (end < x.size() && std::max(high, x[end]) - std::min(low, x[end]) <= rule.band_m) {
      low = std::min(low, x[end]);
      high = std::max(high, x[end]);
      ++end;
    }
    const std::size_t length = end - begin;
    bool still = static_cast<int>(length) >= rule.min_samples;
    if (still) {
      const std::size_t fitted = std::min(length, std::max<std::size_t>(3, length * 4 / 5));
      const auto [slope, curvature] = SlopeAndCurvature(x, begin, begin + fitted);
      const auto [slope_noise, curvature_noise] =
          SlopeAndCurvatureNoise(rule.sigma_x_m, static_cast<double>(fitted));
      still =
          std::fabs(slope) <= std::max(rule.max_slope_m_per_sample, 4 * slope_noise) &&
          std::fabs(curvature) <= std::max(rule.max_curvature_m_per_sample2, 4 * curvature_noise);
    }
    if (still) {
      runs.push_back({begin, end});
      begin = end;
    } else {
      ++begin;
    }
  }
  return runs;
}

double RestPosition(const std::vector<double>& x, const Run& run) {
  assert(run.first < run.second && run.second <= x.size());
  return Median(std::vector<double>(x.begin() + run.first, x.begin() + run.second));
}

std::size_t ArrivalSample(const std::vector<double>& x, const Run& run, const StuckRule& rule) {
  const double rested = RestPosition(x, run);
  std::size_t at = run.first;
  while (at + 1 < run.second && std::fabs(x[at] - rested) > rule.rest_tolerance_m) ++at;
  return at;
}

std::size_t BreakawaySample(const std::vector<double>& x, const Run& run, const StuckRule& rule) {
  const double rested = RestPosition(x, run);
  std::size_t at = run.second - 1;
  while (at > run.first && std::fabs(x[at] - rested) > rule.rest_tolerance_m) --at;
  return at;
}

void SmoothStuckForce(const Runs& runs, std::size_t window, double sigma_N,
                      const std::vector<double>& t, std::vector<double>* force) {
  for (const Run& run : runs) {
    const std::size_t begin = run.first, end = run.second;  // (a lambda below reads `end`)
    // The first samples of a run still carry the arrest's pressure transient.
    const std::size_t first =
        end - std::min(window, end - begin - std::min<std::size_t>(3, end - begin));
    // The run's last sample may already move (a run of 3 samples or fewer,
    // which min_stuck_samples allows, leaves none).
    const std::size_t n = end > first + 1 ? end - 1 - first : 0;
    if (n < 8) continue;
    Eigen::MatrixXd design(n, 3);
    Eigen::VectorXd y(n);
    const double centre = 0.5 * static_cast<double>(first + end - 1);
    // Where sample i lies in the run's window, about -0.5 .. 0.5.
    const auto coordinate = [&](std::size_t i) {
      if (t.empty()) return (static_cast<double>(i) - centre) / static_cast<double>(n);
      return (t[i] - 0.5 * (t[first] + t[end - 1])) / (t[end - 1] - t[first]);
    };
    for (std::size_t i = 0; i < n; ++i) {
      const double s = coordinate(first + i);
      for (int power = 0; power < 3; ++power) design(i, power) = std::pow(s, power);
      y(i) = (*force)[first + i];
    }
    const Eigen::Vector3d c = design.colPivHouseholderQr().solve(y);
    const double misfit = (design * c - y).squaredNorm() / static_cast<double>(n - 3);
    if (misfit > kSmoothStuckMisfit * sigma_N * sigma_N) continue;
    for (std::size_t i = first; i < end; ++i) {
      const double s = coordinate(i);
      (*force)[i] = c(0) + s * (c(1) + s * c(2));
    }
  }
}

}  // namespace pneumaid::internal
