// The friction fit's second kind of evidence: the force balance of the rod
// while it slides smoothly, friction(v) = F(t) - M a, with v and a read off
// the logged positions by a local quadratic (Savitzky-Golay) over a window.
//
// The stuck-to-arrest replays (friction_segments.h, friction_cost.h) need stick-slip: a rod that
// slides through the stroke in one go (a heavy load, little Stribeck drop)
// gives them no segment, and a replay over a long slide integrates any force
// bias twice. The force balance needs no stick and no integration: it is the
// friction-velocity map of the seed paper's Figs. 8 and 9, sample by sample.
// Samples near a stuck phase, a reversal or a stroke end are left out (the
// window would straddle them, or the acceleration still changes within it),
// and so are samples that a replay segment already covers. Consecutive samples share a window, so
// their residuals are correlated: each slide is one cluster of the fit's robust covariance.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include "pneumaid/model/friction.h"

namespace pneumaid::internal {

struct SlideCluster {
  int direction = 0;                  // +1 or -1 for every sample
  std::vector<double> speed_m_per_s;  // |v| > 0
  std::vector<double> friction_N;     // dir (F - M a): the friction magnitude
  std::vector<double> weight;         // 1 / its standard error [1/N]
  std::vector<std::size_t> sample;    // each one's index in its log
  int log = -1;                       // which log (the caller's numbering)
};

struct SlideSampling {
  double period_s = 1e-3;  // the median interval when irregular
  // The sample times of a log sampled at irregular intervals (else null): v
  // and a are then a least-squares quadratic in time over each window.
  const std::vector<double>* time_s = nullptr;
  double mass_kg = 0.15;
  double sigma_x_m = 5e-6;     // position noise
  double sigma_force_N = 0.1;  // the driving force's noise
  double half_stroke_m = 0.025;
  double end_zone_m = 1e-3;         // samples this close to an end are left out
  double window_s = 0.01;           // the smoothing window (at least 7 samples)
  double min_speed_m_per_s = 2e-3;  // slower samples count as not sliding
  int min_cluster_samples = 5;
};

// A slide's window is smooth when the position's RMS about its quadratic is
// at most the larger of kSmoothMisfitSigmas position sigmas and
// kSmoothMisfitFloor_m (measured at 250 Hz, sigma_x 5 um: smooth slides of a
// 1.5 kg rod up to 14 um, the paper rod's stick-slip between stuck phases
// too short to be found from 47 um, median 172 um).
inline constexpr double kSmoothMisfitSigmas = 4.0;
inline constexpr double kSmoothMisfitFloor_m = 25e-6;

// The smoothly sliding samples of one log, grouped by slide. `covered[i]`
// marks samples to leave out (stuck, or in a replay segment); a window the
// quadratic does not follow (above) is not sliding smoothly.
std::vector<SlideCluster> SlidingSamples(const std::vector<double>& x_m,
                                         const std::vector<double>& force_N,
                                         const std::vector<bool>& covered,
                                         const SlideSampling& sampling);

// (dir (F - M a) - Stribeck magnitude(|v|; direction's coefficients)) x weight.
struct SlideResidual {
  const SlideCluster* cluster;

  template <typename T>
  bool operator()(const T* positive, const T* negative, T* residual) const {
    const T* theta = cluster->direction > 0 ? positive : negative;
    const StribeckCoefficients<T> c{theta[0], theta[1], theta[2], theta[3]};
    for (std::size_t i = 0; i < cluster->speed_m_per_s.size(); ++i) {
      residual[i] =
          (T(cluster->friction_N[i]) - StribeckMagnitude(T(cluster->speed_m_per_s[i]), c)) *
          T(cluster->weight[i]);
    }
    return true;
  }
};

}  // namespace pneumaid::internal
