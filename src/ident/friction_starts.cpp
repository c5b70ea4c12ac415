#include "friction_starts.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "../util/median.h"

namespace pneumaid::friction_internal {

namespace {

// The breakaway forces ReadOffLogs reads Fs from: the slides' of `direction`, or
// with fewer than three those at the stroke ends; empty with fewer than three.
std::vector<double> Breakaways(const StrokeData& data, int direction) {
  std::vector<double> forces;
  for (const Segment& s : data.segments) {
    if (s.direction == direction) forces.push_back(s.breakaway_force_N);
  }
  if (forces.size() >= 3) return forces;
  const std::vector<double>& at_ends = data.end_breakaway_N[direction > 0 ? 0 : 1];
  return at_ends.size() >= 3 ? at_ends : std::vector<double>{};
}

// The standard error of the median of `forces` (not empty) from their
// robust spread.
double MedianError(const std::vector<double>& forces, double median) {
  std::vector<double> deviations;
  for (double f : forces) deviations.push_back(std::fabs(f - median));
  // A median's error is sqrt(pi / 2) of a mean's; MAD -> sigma by 1.4826.
  return 1.2533 * 1.4826 * internal::Median(deviations) /
         std::sqrt(static_cast<double>(forces.size()));
}

}  // namespace

// (Fd, b) of one direction from its force-balance samples with Fs and vs
// given: the magnitude Fs e + Fd (1 - e) + b v, e = exp(-(v/vs)^2), is
// linear in (Fd, b); Fd in [0, Fs] and b >= 0.
double FitSliding(const std::vector<internal::SlideCluster>& clusters, int direction, double fs,
                  double vs, double* fd, double* b) {
  std::size_t samples = 0;
  for (const auto& c : clusters) {
    if (c.direction == direction) samples += c.speed_m_per_s.size();
  }
  if (samples < kMinSlideSamples) return HUGE_VAL;
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  const auto each = [&](const auto& use) {
    for (const auto& c : clusters) {
      if (c.direction != direction) continue;
      for (std::size_t i = 0; i < c.speed_m_per_s.size(); ++i) {
        const double v = c.speed_m_per_s[i], e = std::exp(-(v / vs) * (v / vs));
        use(Eigen::Vector2d(1 - e, v), c.friction_N[i] - fs * e, c.weight[i] * c.weight[i]);
      }
    }
  };
  each([&](const Eigen::Vector2d& x, double y, double w) {
    normal += w * x * x.transpose();
    rhs += w * y * x;
  });
  Eigen::Vector2d theta = normal.ldlt().solve(rhs);
  if (!(theta(1) >= 0)) theta = Eigen::Vector2d(rhs(0) / normal(0, 0), 0.0);
  theta(0) = std::clamp(theta(0), 0.0, std::max(fs, 0.0));
  double cost = 0;
  each([&](const Eigen::Vector2d& x, double y, double w) {
    cost += w * std::pow(y - x.dot(theta), 2);
  });
  *fd = theta(0);
  *b = theta(1);
  return cost;
}

// Fd, b, vs of one direction from its force-balance samples with Fs given
// (the breakaways): the best point of a vs grid (1 mm/s to 0.1 m/s), (Fd, b)
// solved exactly at each. Leaves `block` as it is, and returns false, with
// too few samples.
bool ForceBalanceStart(const StrokeData& data, int direction, Block* block) {
  const double fs = (*block)[0];
  double best = HUGE_VAL;
  for (int g = 0; g <= 24; ++g) {
    const double vs = 1e-3 * std::pow(100.0, g / 24.0);
    double fd = 0, b = 0;
    const double cost = FitSliding(data.clusters, direction, fs, vs, &fd, &b);
    if (cost < best) best = cost, *block = {fs, fd, b, vs};
  }
  return best < HUGE_VAL;
}

LogsReading ReadOffLogs(const StrokeData& data, int direction, const Block& fallback) {
  LogsReading r;
  r.value = fallback;
  const std::vector<double> forces = Breakaways(data, direction);
  if (!forces.empty()) {
    r.value[0] = internal::Median(forces);
    r.error[0] = MedianError(forces, r.value[0]);
    r.read[0] = true;
  }
  r.read[1] = r.read[2] = r.read[3] = ForceBalanceStart(data, direction, &r.value);
  return r;
}

}  // namespace pneumaid::friction_internal
