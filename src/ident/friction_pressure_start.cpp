// FrictionFromSlides (friction_fit.h): the friction of both directions and
// the friction_pressure gain kp from the force balance of the smooth slides,
// friction = (1 + kp ((p1 + p2)/2 - p_atm)) S(|v|).
#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>

#include "friction_cost.h"
#include "friction_segments.h"
#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/model/effects.h"
#include "quiet_solver.h"

namespace pneumaid {
namespace {

using namespace friction_internal;

// One slide's samples: (measured friction - (1 + kp dp) S(|v|)) x weight.
struct PressureSlideResidual {
  const internal::SlideCluster* cluster;
  std::vector<double> gauge_pressure_Pa;  // (p1 + p2)/2 - p_atm of each sample

  template <typename T>
  bool operator()(const T* positive, const T* negative, const T* kp, T* residual) const {
    const T* theta = cluster->direction > 0 ? positive : negative;
    const StribeckCoefficients<T> c = Coefficients(theta);
    for (std::size_t i = 0; i < cluster->speed_m_per_s.size(); ++i) {
      const T model = (T(1.0) + kp[0] * T(gauge_pressure_Pa[i])) *
                      StribeckMagnitude(T(cluster->speed_m_per_s[i]), c);
      residual[i] = (T(cluster->friction_N[i]) - model) * T(cluster->weight[i]);
    }
    return true;
  }
};

}  // namespace

SlideFrictionStart FrictionFromSlides(const Unit& unit, const std::vector<std::string>& runs,
                                      const FrictionParams& prior,
                                      const FrictionFitOptions& options,
                                      const SlideFrictionOptions& slide_options) {
  const int min_samples = slide_options.min_samples;
  SlideFrictionStart out;
  out.friction = prior;
  if (runs.empty()) {
    out.why = "no runs";
    return out;
  }
  StrokeSelection selection;
  selection.runs = runs;
  selection.slides_under_segments = true;
  FrictionFitOptions with_slides = options;
  with_slides.force_balance = true;
  const StrokeData data = PrepareStrokes(unit, with_slides, selection);
  const double p_atm = unit.manifest.rig.atmospheric_pressure_Pa;
  std::vector<PressureSlideResidual> slides;
  int samples[2] = {0, 0};
  double low = INFINITY, high = -INFINITY;
  for (const internal::SlideCluster& c : data.clusters) {
    const Experiment& log = *data.experiments[c.log];
    const auto &p1 = log.column("p1"), &p2 = log.column("p2");
    PressureSlideResidual slide{&c, {}};
    for (std::size_t i : c.sample) {
      const double dp = 0.5 * (p1[i] + p2[i]) - p_atm;
      slide.gauge_pressure_Pa.push_back(dp);
      low = std::min(low, dp);
      high = std::max(high, dp);
    }
    samples[c.direction > 0 ? 0 : 1] += static_cast<int>(c.sample.size());
    slides.push_back(std::move(slide));
  }
  out.samples = samples[0] + samples[1];
  if (std::max(samples[0], samples[1]) < min_samples) {
    out.why = "too few smooth slide samples (" + std::to_string(samples[0]) + " extending, " +
              std::to_string(samples[1]) + " retracting; " + std::to_string(min_samples) +
              " needed in a direction)";
    return out;
  }
  // kp is read off how friction changes with the mean chamber pressure: the
  // slides must span some of it (0.1 bar).
  if (slide_options.pressure_gain && !(high - low > 1e4)) {
    out.why = "the slides' mean chamber pressure does not vary";
    return out;
  }
  Block blocks[2] = {Pack(prior.positive), Pack(prior.negative)};
  double kp = slide_options.kp_per_Pa;
  ceres::Problem problem;
  for (const PressureSlideResidual& slide : slides) {
    const int rows = static_cast<int>(slide.gauge_pressure_Pa.size());
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<PressureSlideResidual, ceres::DYNAMIC, kDirectionParameters,
                                        kDirectionParameters, 1>(new PressureSlideResidual(slide),
                                                                 rows),
        nullptr, blocks[0].data(), blocks[1].data(), &kp);
  }
  const std::array<double, kDirectionParameters> sigma = PriorSigmas(options);
  for (int d = 0; d < 2; ++d) {
    Block& block = blocks[d];
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<PriorResidual, kDirectionParameters, kDirectionParameters>(
            new PriorResidual{block, sigma}),
        nullptr, block.data());
    for (int i = 0; i < kDirectionParameters; ++i) {
      problem.SetParameterLowerBound(block.data(), i, kLowerBounds[i]);
      problem.SetParameterUpperBound(block.data(), i, kUpperBounds[i]);
    }
    // A direction with too few samples keeps the prior's coefficients; b and
    // vs (and Fs unless asked) are the prior's always.
    if (samples[d] < min_samples) {
      problem.SetParameterBlockConstant(block.data());
    } else {
      std::vector<int> held = {2, 3};
      if (!slide_options.static_friction) held.push_back(0);
      problem.SetManifold(block.data(), new ceres::SubsetManifold(kDirectionParameters, held));
    }
  }
  // The effect's plausible range (effects.h).
  const EffectParameterInfo& range = FindEffect("friction_pressure")->parameters.front();
  problem.SetParameterLowerBound(&kp, 0, range.plausible_min);
  problem.SetParameterUpperBound(&kp, 0, range.plausible_max);
  if (!slide_options.pressure_gain) problem.SetParameterBlockConstant(&kp);
  ceres::Solver::Options solver = internal::QuietSolverOptions();
  solver.max_num_iterations = options.max_iterations;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  if (!summary.IsSolutionUsable()) {
    out.why = "the force balance's least squares failed: " + summary.message;
    return out;
  }
  out.ok = true;
  out.friction.positive = Unpack(blocks[0]);
  out.friction.negative = Unpack(blocks[1]);
  out.kp_per_Pa = kp;
  return out;
}

}  // namespace pneumaid
