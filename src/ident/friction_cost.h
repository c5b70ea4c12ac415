// The friction fit (friction_fit.h), its cost functions: a segment's replay
// residuals (forward from breakaway, backward from the arrest) with
// derivatives from the narrowest Jet that covers what the replay touches, and
// the weak prior on each coefficient.
#pragma once

#include <ceres/ceres.h>

#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "friction_segments.h"

namespace pneumaid::friction_internal {

// (replayed x - logged x) x weight at every sample after the first: forward
// from the segment's start, and for a two-sided segment backward from the
// arrest after `split`.
struct SegmentResidual {
  const Segment* segment;
  RodReplayInput replay;

  template <typename T>
  void Write(const std::vector<T>& x, T* residual) const {
    const double* logged = segment->position_m->data() + segment->begin;
    for (std::size_t j = 1; j < replay.samples; ++j) {
      residual[j - 1] = (x[j] - T(logged[j])) * T(segment->weight[j]);
    }
  }

  // Residuals of the one-sided form (stop_time_s == nullptr) or the
  // two-sided one; `trace` records the directions the replays slid in.
  template <typename T>
  void Evaluate(const T* positive, const T* negative, const T* stop_time_s, T* residual,
                RodReplayTrace* trace) const {
    std::vector<T> x(replay.samples);
    if (stop_time_s == nullptr) {
      ReplayRod(replay, Coefficients(positive), Coefficients(negative), x.data(), trace);
    } else {
      const std::size_t split = segment->split - segment->begin;
      RodReplayInput forward = replay;
      forward.samples = split + 1;
      ReplayRod(forward, Coefficients(positive), Coefficients(negative), x.data(), trace);
      ReplayArrestBackward(replay, stop_time_s[0], segment->stop_position_m, segment->direction,
                           split + 1, Coefficients(positive), Coefficients(negative), x.data());
      if (trace != nullptr) trace->Record(segment->direction);
    }
    Write(x, residual);
  }

  template <typename T>
  bool operator()(const T* positive, const T* negative, T* residual) const {
    Evaluate(positive, negative, static_cast<const T*>(nullptr), residual, nullptr);
    return true;
  }

  template <typename T>
  bool operator()(const T* positive, const T* negative, const T* stop_time_s, T* residual) const {
    Evaluate(positive, negative, stop_time_s, residual, nullptr);
    return true;
  }
};

// A segment's cost with derivatives from the narrowest Jet that covers what
// its replay touches. A slide that keeps its logged direction depends on that
// direction's four coefficients and the arrest time only, so it is
// differentiated with 5 lanes instead of 9 (the fit's main cost); a replay
// that also slides the other way is redone with every lane. The derivatives
// are the same either way: the untouched block's columns are exactly zero.
class SegmentCost : public ceres::CostFunction {
 public:
  SegmentCost(const Segment* segment, const RodReplayInput& replay, int rows)
      : residual_{segment, replay} {
    set_num_residuals(rows);
    auto* blocks = mutable_parameter_block_sizes();
    blocks->assign(TwoSided() ? 3 : 2, kDirectionParameters);
    if (TwoSided()) blocks->back() = 1;
    auto* functor = new SegmentResidual(residual_);
    if (TwoSided()) {
      all_lanes_.reset(
          new ceres::AutoDiffCostFunction<SegmentResidual, ceres::DYNAMIC, kDirectionParameters,
                                          kDirectionParameters, 1>(functor, rows));
    } else {
      all_lanes_.reset(
          new ceres::AutoDiffCostFunction<SegmentResidual, ceres::DYNAMIC, kDirectionParameters,
                                          kDirectionParameters>(functor, rows));
    }
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* stop = TwoSided() ? parameters[2] : nullptr;
    if (jacobians == nullptr) {
      // Ceres' projected line search and its candidate evaluation often ask
      // for the same point twice in a row.
      const std::array<double, 2 * kDirectionParameters + 1> at = Point(parameters);
      if (at == last_point_ && !last_residuals_.empty()) {
        std::copy(last_residuals_.begin(), last_residuals_.end(), residuals);
        return true;
      }
      residual_.Evaluate(parameters[0], parameters[1], stop, residuals, nullptr);
      last_point_ = at;
      last_residuals_.assign(residuals, residuals + num_residuals());
      return true;
    }
    const int direction = residual_.segment->direction;
    if (direction == 0 || !OneDirection(parameters, direction, residuals, jacobians)) {
      return all_lanes_->Evaluate(parameters, residuals, jacobians);
    }
    return true;
  }

 private:
  // Lanes 0-3: the coefficients of the slide's direction; lane 4: the arrest time.
  using Jet5 = ceres::Jet<double, kDirectionParameters + 1>;

  bool TwoSided() const { return residual_.segment->two_sided; }

  std::array<double, 2 * kDirectionParameters + 1> Point(double const* const* parameters) const {
    std::array<double, 2 * kDirectionParameters + 1> at{};
    std::copy(parameters[0], parameters[0] + kDirectionParameters, at.begin());
    std::copy(parameters[1], parameters[1] + kDirectionParameters,
              at.begin() + kDirectionParameters);
    if (TwoSided()) at.back() = parameters[2][0];
    return at;
  }

  // Residuals and Jacobians with the other direction's coefficients held
  // constant; false (nothing written) when the replay slid that way too.
  bool OneDirection(double const* const* parameters, int direction, double* residuals,
                    double** jacobians) const {
    const int own = direction > 0 ? 0 : 1;
    std::array<Jet5, kDirectionParameters> blocks[2];
    for (int b = 0; b < 2; ++b) {
      for (int i = 0; i < kDirectionParameters; ++i) {
        blocks[b][i] = b == own ? Jet5(parameters[b][i], i) : Jet5(parameters[b][i]);
      }
    }
    Jet5 stop;
    if (TwoSided()) stop = Jet5(parameters[2][0], kDirectionParameters);
    std::vector<Jet5> r(num_residuals());
    RodReplayTrace trace;
    residual_.Evaluate(blocks[0].data(), blocks[1].data(), TwoSided() ? &stop : nullptr, r.data(),
                       &trace);
    if (direction > 0 ? trace.slid_negative : trace.slid_positive) return false;
    for (int row = 0; row < num_residuals(); ++row) {
      residuals[row] = r[row].a;
      for (int b = 0; b < 2; ++b) {
        if (jacobians[b] == nullptr) continue;
        for (int i = 0; i < kDirectionParameters; ++i) {
          jacobians[b][row * kDirectionParameters + i] = b == own ? r[row].v[i] : 0.0;
        }
      }
      if (TwoSided() && jacobians[2] != nullptr) jacobians[2][row] = r[row].v[kDirectionParameters];
    }
    return true;
  }

  SegmentResidual residual_;
  std::unique_ptr<ceres::CostFunction> all_lanes_;  // every lane: both directions slid
  // The last residual-only evaluation (Ceres never evaluates one block from
  // two threads at once).
  mutable std::array<double, 2 * kDirectionParameters + 1> last_point_{};
  mutable std::vector<double> last_residuals_;
};

inline std::array<double, kDirectionParameters> PriorSigmas(const FrictionFitOptions& options) {
  return {options.prior_static_sigma_N, options.prior_dynamic_sigma_N,
          options.prior_viscous_sigma_N_s_per_m, options.prior_stribeck_log_sigma};
}

// The slope of coefficient i's prior residual (PriorResidual) at `value`:
// 1 / sigma, vs on its log scale.
inline double PriorSlope(int i, double value,
                         const std::array<double, kDirectionParameters>& sigma) {
  return i == 3 ? 1.0 / (value * sigma[i]) : 1.0 / sigma[i];
}

// The weak prior: (theta - prior) / sigma per coefficient, vs on a log scale.
// It keeps a coefficient the logs do not determine near the prior instead of
// letting it wander (or the fit fail on a singular J'J), and is negligible
// against the logs wherever they determine one.
struct PriorResidual {
  Block prior;
  std::array<double, kDirectionParameters> sigma;

  template <typename T>
  bool operator()(const T* theta, T* residual) const {
    using std::log;
    for (int i = 0; i < 3; ++i) residual[i] = (theta[i] - T(prior[i])) / T(sigma[i]);
    residual[3] = (log(theta[3]) - T(std::log(prior[3]))) / T(sigma[3]);
    return true;
  }
};

}  // namespace pneumaid::friction_internal
