#include "friction_problem.h"

#include <algorithm>
#include <cmath>

#include "friction_cost.h"
#include "friction_slides.h"
#include "quiet_solver.h"

namespace pneumaid::friction_internal {

void BuildProblem(const StrokeData& data, double mass_kg, const FrictionFitOptions& options,
                  const std::vector<double>& huber_scale, Block* positive, Block* negative,
                  SegmentProblem* p) {
  for (std::size_t k = 0; k < data.segments.size(); ++k) {
    const Segment& s = data.segments[k];
    const RodReplayInput replay = ReplayOf(s, mass_kg, options);
    const int rows = static_cast<int>(replay.samples) - 1;
    auto* cost = new SegmentCost(&s, replay, rows);
    ceres::LossFunction* loss =
        huber_scale.empty() ? nullptr : new ceres::HuberLoss(huber_scale[k]);
    if (s.two_sided) {
      double* stop = &(*p->stop_time_s)[k];
      p->problem.AddResidualBlock(cost, loss, positive->data(), negative->data(), stop);
      p->problem.SetParameterLowerBound(stop, 0, s.stop_time_min_s);
      p->problem.SetParameterUpperBound(stop, 0, s.stop_time_max_s);
    } else {
      p->problem.AddResidualBlock(cost, loss, positive->data(), negative->data());
    }
    p->rows.push_back(rows);
    p->weighted_rows.push_back(static_cast<int>(std::count_if(
        s.weight.begin() + 1, s.weight.begin() + 1 + rows, [](double w) { return w != 0; })));
  }
  for (std::size_t c = 0; c < data.clusters.size(); ++c) {
    const int rows = static_cast<int>(data.clusters[c].speed_m_per_s.size());
    auto* cost = new ceres::AutoDiffCostFunction<internal::SlideResidual, ceres::DYNAMIC,
                                                 kDirectionParameters, kDirectionParameters>(
        new internal::SlideResidual{&data.clusters[c]}, rows);
    const std::size_t k = data.segments.size() + c;
    ceres::LossFunction* loss =
        huber_scale.empty() ? nullptr : new ceres::HuberLoss(huber_scale[k]);
    p->problem.AddResidualBlock(cost, loss, positive->data(), negative->data());
    p->rows.push_back(rows);
    p->weighted_rows.push_back(rows);
  }
  for (Block* block : {positive, negative}) {
    for (int i = 0; i < kDirectionParameters; ++i) {
      p->problem.SetParameterLowerBound(block->data(), i, kLowerBounds[i]);
      p->problem.SetParameterUpperBound(block->data(), i, kUpperBounds[i]);
    }
  }
}

ceres::Solver::Summary Solve(const FrictionFitOptions& options, ceres::Problem* problem) {
  ceres::Solver::Options solver_options = internal::QuietSolverOptions();
  // The arrest times are eliminated per segment (Schur complement).
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  solver_options.max_num_iterations = options.max_iterations;
  // Relative changes far below the standard errors: more iterations would
  // move nothing that the covariance resolves.
  solver_options.function_tolerance = 1e-8;
  solver_options.parameter_tolerance = 1e-8;
  // With bounds, Ceres follows every trust-region step with a projected
  // Armijo search along it. That search is what keeps steps that push arrest
  // times against their bounds useful (without it: 24 iterations instead of 9
  // on the benchmark's 10^5 samples), but its default cubic interpolation
  // evaluates the whole Jacobian at each trial point, doubling the cost of an
  // iteration. Bisection needs the cost alone.
  solver_options.line_search_interpolation_type = ceres::BISECTION;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, problem, &summary);
  return summary;
}

// Mean squared residual of each segment (residuals only: cheap).
bool SegmentMeanSquares(SegmentProblem* p, std::vector<double>* out) {
  std::vector<double> r;
  if (!p->problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, &r, nullptr, nullptr)) {
    return false;
  }
  out->clear();
  std::size_t row = 0;
  for (std::size_t k = 0; k < p->rows.size(); ++k) {
    double squares = 0;
    for (int i = 0; i < p->rows[k]; ++i, ++row) squares += r[row] * r[row];
    out->push_back(p->weighted_rows[k] > 0 ? squares / p->weighted_rows[k] : NAN);
  }
  return true;
}

bool DirectionMisfits(const StrokeData& data, SegmentProblem* p, double misfit[3]) {
  std::vector<double> mean_squares;
  if (!SegmentMeanSquares(p, &mean_squares)) return false;
  misfit[0] = misfit[1] = misfit[2] = 0;
  for (std::size_t k = 0; k < mean_squares.size(); ++k) {
    // Segments first, then the force-balance slides.
    const int direction = k < data.segments.size()
                              ? data.segments[k].direction
                              : data.clusters[k - data.segments.size()].direction;
    if (p->weighted_rows[k] == 0) continue;  // all of it in or after a gap
    misfit[direction > 0   ? 0
           : direction < 0 ? 1
                           : 2] += p->weighted_rows[k] * std::log1p(mean_squares[k]);
  }
  return true;
}

FrictionStartScreen ScreenStarts(const StrokeData& data, double mass_kg,
                                 const FrictionFitOptions& options, Block* positive,
                                 Block* negative) {
  FrictionStartScreen out;
  std::vector<double> stop_time_s;
  for (const Segment& s : data.segments) stop_time_s.push_back(s.stop_time_guess_s);
  Block trial[2] = {*positive, *negative};
  SegmentProblem problem;
  problem.stop_time_s = &stop_time_s;
  BuildProblem(data, mass_kg, options, {}, &trial[0], &trial[1], &problem);
  // The misfit of `trial`: per direction with the stuck segments' part, and
  // the total; false when a replay failed.
  const auto score = [&](double* direction, double* total) {
    for (std::size_t k = 0; k < data.segments.size(); ++k)
      stop_time_s[k] = data.segments[k].stop_time_guess_s;
    double misfit[3];
    if (!DirectionMisfits(data, &problem, misfit)) return false;
    direction[0] = misfit[0] + misfit[2];
    direction[1] = misfit[1] + misfit[2];
    *total = misfit[0] + misfit[1] + misfit[2];
    return true;
  };
  const Block start[2] = {*positive, *negative};
  double start_total = HUGE_VAL;
  if (!score(out.start_misfit, &start_total)) out.start_misfit[0] = out.start_misfit[1] = HUGE_VAL;
  out.best_misfit[0] = out.start_misfit[0];
  out.best_misfit[1] = out.start_misfit[1];
  Block best[2] = {start[0], start[1]};
  // Fs around the breakaways' (which read a slow creep or an early slip as
  // breakaway), Fd as a fraction of Fs, b and vs over the fleet's ranges.
  static constexpr double kStaticFactor[] = {0.8, 1.0, 1.25};
  static constexpr double kDynamicFraction[] = {0.02, 0.08, 0.25, 0.6};
  static constexpr double kViscous_N_s_per_m[] = {1.5, 4.0, 10.0};
  static constexpr double kStribeck_m_per_s[] = {2e-3, 5e-3, 12e-3, 30e-3};
  for (const double fs : kStaticFactor) {
    for (const double fd : kDynamicFraction) {
      for (const double b : kViscous_N_s_per_m) {
        for (const double vs : kStribeck_m_per_s) {
          for (int d = 0; d < 2; ++d) {
            const double static_N = std::min(fs * start[d][0], kUpperBounds[0]);
            trial[d] = {static_N, fd * static_N, b, vs};
          }
          double misfit[2], total = 0;
          ++out.candidates;
          if (!score(misfit, &total)) continue;
          for (int d = 0; d < 2; ++d) {
            if (misfit[d] < out.best_misfit[d]) out.best_misfit[d] = misfit[d], best[d] = trial[d];
          }
        }
      }
    }
  }
  // Each direction's best was scored with the other at the same grid point
  // (a replay can slide back the other way): the pairs are replayed
  // together, the start last, and the lowest total kept.
  *positive = start[0];
  *negative = start[1];
  double kept = start_total;
  for (const auto& [p, n] : {std::make_pair(best[0], best[1]), std::make_pair(best[0], start[1]),
                             std::make_pair(start[0], best[1])}) {
    trial[0] = p;
    trial[1] = n;
    double misfit[2], total = HUGE_VAL;
    if (score(misfit, &total) && total < kept) kept = total, *positive = p, *negative = n;
  }
  return out;
}

}  // namespace pneumaid::friction_internal
