#include "friction_slides.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace pneumaid::internal {
namespace {

// The RMS of x about the window's quadratic mean + c1 j + c2 (j^2 - m),
// j = -k..k around sample i (three coefficients fitted).
double QuadraticMisfit(const std::vector<double>& x_m, std::size_t i, int k, double m, double c1,
                       double c2) {
  double mean = 0;
  for (int j = -k; j <= k; ++j) mean += x_m[i + j];
  mean /= 2 * k + 1;
  double squares = 0;
  for (int j = -k; j <= k; ++j) {
    const double r = x_m[i + j] - mean - c1 * j - c2 * (j * j - m);
    squares += r * r;
  }
  return std::sqrt(squares / (2 * k + 1 - 3));
}

// v, a and the RMS misfit of the least-squares quadratic in time through
// x over samples i - k .. i + k of a log sampled at the times `t` (time in
// units of the median interval `h` for the normal equations).
struct WindowFit {
  double v, a, misfit;
};
WindowFit QuadraticInTime(const std::vector<double>& x_m, const std::vector<double>& t,
                          std::size_t i, int k, double h) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d right = Eigen::Vector3d::Zero();
  for (int j = -k; j <= k; ++j) {
    const double tau = (t[i + j] - t[i]) / h;
    const Eigen::Vector3d row(1.0, tau, tau * tau);
    normal += row * row.transpose();
    right += row * (x_m[i + j] - x_m[i]);
  }
  const Eigen::Vector3d c = normal.ldlt().solve(right);
  double squares = 0;
  for (int j = -k; j <= k; ++j) {
    const double tau = (t[i + j] - t[i]) / h;
    const double r = x_m[i + j] - x_m[i] - c(0) - tau * (c(1) + tau * c(2));
    squares += r * r;
  }
  return {c(1) / h, 2 * c(2) / (h * h), std::sqrt(squares / (2 * k + 1 - 3))};
}

}  // namespace

std::vector<SlideCluster> SlidingSamples(const std::vector<double>& x_m,
                                         const std::vector<double>& force_N,
                                         const std::vector<bool>& covered,
                                         const SlideSampling& sampling) {
  const double h = sampling.period_s;
  const int k = std::max(3, static_cast<int>(std::lround(0.5 * sampling.window_s / h)));
  // Savitzky-Golay weights of a quadratic over j = -k..k: the first
  // derivative sum(j x_j) / sum(j^2), the second 2 sum((j^2 - m) x_j) /
  // sum((j^2 - m)^2), m the mean of j^2.
  double s2 = 0, s4 = 0;
  for (int j = -k; j <= k; ++j) s2 += j * j;
  const double m = s2 / (2 * k + 1);
  for (int j = -k; j <= k; ++j) s4 += (j * j - m) * (j * j - m);
  const double sigma_v = sampling.sigma_x_m / (h * std::sqrt(s2));
  const double sigma_a = 2 * sampling.sigma_x_m / (h * h * std::sqrt(s4));
  const double sigma_N = std::hypot(sampling.sigma_force_N, sampling.mass_kg * sigma_a);
  // A sample counts as sliding when its speed is well above the speed noise.
  const double min_speed = std::max(sampling.min_speed_m_per_s, 5 * sigma_v);
  const double max_misfit =
      std::max(kSmoothMisfitSigmas * sampling.sigma_x_m, kSmoothMisfitFloor_m);
  const std::size_t n = x_m.size();
  std::vector<SlideCluster> clusters;
  SlideCluster current;
  // ... and so are its last 2k (its end is a stop, a reversal or an end).
  const auto close = [&] {
    const std::size_t keep = current.speed_m_per_s.size() > static_cast<std::size_t>(2 * k)
                                 ? current.speed_m_per_s.size() - 2 * k
                                 : 0;
    current.speed_m_per_s.resize(keep);
    current.friction_N.resize(keep);
    current.weight.resize(keep);
    current.sample.resize(keep);
    if (static_cast<int>(keep) >= sampling.min_cluster_samples) clusters.push_back(current);
    current = SlideCluster{};
  };
  // Samples of a slide since it began (after a stuck phase, a replayed
  // stretch, an end or a reversal): its first 2k are skipped, where the
  // acceleration still changes within the window (the quadratic would bias a)...
  int since_start = 0;
  for (std::size_t i = 0; i < n; ++i) {
    bool usable = i >= static_cast<std::size_t>(k) && i + k < n;
    double v = 0, a = 0;
    if (usable) {
      for (int j = -k; j <= k; ++j) {
        const std::size_t at = i + j;
        // The whole window must be free: no stuck or replayed sample, no end.
        if (covered[at] || std::fabs(x_m[at]) > sampling.half_stroke_m - sampling.end_zone_m) {
          usable = false;
          break;
        }
        v += j * x_m[at];
        a += (j * j - m) * x_m[at];
      }
      v /= s2 * h;
      a *= 2 / (s4 * h * h);
      // A window the quadratic does not follow is no smooth slide: stick-slip
      // cycles shorter than a stuck phase can be (at 250 Hz the paper rod's
      // 4 to 40 ms sticks) read as a steady speed there, and F - M a swings.
      if (usable && sampling.time_s != nullptr) {
        const WindowFit fit = QuadraticInTime(x_m, *sampling.time_s, i, k, h);
        v = fit.v;
        a = fit.a;
        usable = fit.misfit <= max_misfit;
      } else if (usable && QuadraticMisfit(x_m, i, k, m, v * h, 0.5 * a * h * h) > max_misfit) {
        usable = false;
      }
    }
    const int direction = v > 0 ? +1 : -1;
    if (!usable || std::fabs(v) < min_speed ||
        (current.direction != 0 && direction != current.direction)) {
      close();
      since_start = 0;
      if (!usable || std::fabs(v) < min_speed) continue;
    }
    current.direction = direction;
    if (since_start++ < 2 * k) continue;
    current.speed_m_per_s.push_back(std::fabs(v));
    current.friction_N.push_back(direction * (force_N[i] - sampling.mass_kg * a));
    current.weight.push_back(1.0 / sigma_N);
    current.sample.push_back(i);
  }
  close();
  return clusters;
}

}  // namespace pneumaid::internal
