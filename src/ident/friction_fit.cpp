#include "pneumaid/ident/friction_fit.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>
#include <sstream>

#include "../util/median.h"
#include "friction_cost.h"
#include "friction_covariance.h"
#include "friction_problem.h"
#include "friction_segments.h"
#include "friction_slides.h"
#include "friction_starts.h"
#include "pneumaid/ident/rod_replay.h"
#include "pneumaid/model/load.h"
#include "quiet_solver.h"

namespace pneumaid {
namespace {

// A direction with fewer slides that break away mid-stroke also replays its
// breakaways from the end stops (FrictionFitOptions::end_slide_m).
constexpr int kMinMidStrokeBreakaways = 3;

using namespace friction_internal;

bool Evaluate(const StrokeData& data, const std::vector<double*>& free_blocks, SegmentProblem* p,
              std::vector<SegmentJacobian>* out) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = free_blocks;
  std::vector<int> stop_column(data.segments.size(), -1);
  int column = static_cast<int>(free_blocks.size()) * kDirectionParameters;
  for (std::size_t k = 0; k < data.segments.size(); ++k) {
    if (!data.segments[k].two_sided) continue;
    evaluate.parameter_blocks.push_back(&(*p->stop_time_s)[k]);
    stop_column[k] = column++;
  }
  std::vector<double> r;
  ceres::CRSMatrix crs;
  if (!p->problem.Evaluate(evaluate, nullptr, &r, nullptr, &crs)) return false;
  const int friction_columns = static_cast<int>(free_blocks.size()) * kDirectionParameters;
  out->assign(p->rows.size(), {});
  stop_column.resize(p->rows.size(), -1);  // force-balance clusters have none
  int row = 0;
  for (std::size_t k = 0; k < p->rows.size(); ++k) {
    const int n = p->rows[k];
    SegmentJacobian& j = (*out)[k];
    j.residuals = Eigen::Map<Eigen::VectorXd>(r.data() + row, n);
    j.friction.setZero(n, friction_columns);
    if (stop_column[k] >= 0) j.stop_time.setZero(n);
    for (int i = 0; i < n; ++i, ++row) {
      for (int e = crs.rows[row]; e < crs.rows[row + 1]; ++e) {
        if (crs.cols[e] < friction_columns) {
          j.friction(i, crs.cols[e]) = crs.values[e];
        } else if (crs.cols[e] == stop_column[k]) {
          j.stop_time(i) = crs.values[e];
        }
      }
    }
  }
  return true;
}

std::string ColumnPath(int column) {
  return std::string(column < kDirectionParameters ? "friction.positive." : "friction.negative.") +
         kParameterNames[column % kDirectionParameters];
}

// Every coefficient (columns 0-3 positive, 4-7 negative) at `values`, the
// `held` ones with their reason, the others with `covariance` (over `free`).
void SetCoefficients(const Block (&starts)[2], const Block (&values)[2],
                     const std::array<std::string, 2 * kDirectionParameters>& held,
                     const std::vector<int>& free, const Eigen::MatrixXd& covariance,
                     FitResult* result) {
  result->coefficients.clear();
  result->covariance = Eigen::MatrixXd::Zero(2 * kDirectionParameters, 2 * kDirectionParameters);
  for (int c = 0; c < 2 * kDirectionParameters; ++c) {
    const int d = c / kDirectionParameters, i = c % kDirectionParameters;
    FittedCoefficient coefficient;
    coefficient.path = ColumnPath(c);
    coefficient.start = starts[d][i];
    coefficient.value = values[d][i];
    coefficient.held = held[c];
    const auto at = std::find(free.begin(), free.end(), c) - free.begin();
    if (held[c].empty() && at < static_cast<long>(free.size())) {
      coefficient.standard_error = std::sqrt(std::max(covariance(at, at), 0.0));
      coefficient.at_bound = AtBound(values[d][i], kLowerBounds[i], kUpperBounds[i]);
      for (std::size_t b = 0; b < free.size(); ++b)
        result->covariance(c, free[b]) = covariance(at, static_cast<Eigen::Index>(b));
    }
    result->coefficients.push_back(coefficient);
  }
}

// One fit from a start: the solve and, when some segments fit far worse than
// the typical one (a disturbed stroke, a bump on the rod), a refit with each
// segment's influence bounded by a Huber loss; the Jacobians of the last
// problem, and the misfit (DirectionMisfits, no loss) that ranks fits from
// other starts.
struct Attempt {
  Block blocks[2];
  std::vector<double> stop_time_s;
  std::vector<SegmentJacobian> jacobians;
  double initial_cost = 0, final_cost = 0, misfit = HUGE_VAL;
  int iterations = 0, outlier_segments = 0;
  bool stopped = true;  // the last solve stopped before its iteration limit
  std::string failure;  // why Ceres failed; empty: usable
};

// One solve of the segment problem from the attempt's current values, with
// the weak prior on the free directions and a Huber loss of `huber_scale`
// per segment (empty: plain least squares); the attempt's costs (its
// initial one from its first solve), iterations and stop recorded. False
// (and a->failure) without a usable solution.
bool SolveOnce(const StrokeData& data, double mass_kg, const FrictionFitOptions& options,
               const Block (&prior_blocks)[2], const bool (&free_direction)[2],
               const std::array<double, kDirectionParameters>& sigma,
               const std::vector<double>& huber_scale, bool first_solve, Attempt* a,
               SegmentProblem* problem) {
  problem->stop_time_s = &a->stop_time_s;
  BuildProblem(data, mass_kg, options, huber_scale, &a->blocks[0], &a->blocks[1], problem);
  for (int d = 0; d < 2; ++d) {
    double* block = a->blocks[d].data();
    if (!free_direction[d]) {
      problem->problem.SetParameterBlockConstant(block);
      continue;
    }
    problem->problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<PriorResidual, kDirectionParameters, kDirectionParameters>(
            new PriorResidual{prior_blocks[d], sigma}),
        nullptr, block);
  }
  const ceres::Solver::Summary summary = Solve(options, &problem->problem);
  if (first_solve) a->initial_cost = summary.initial_cost;
  a->final_cost = summary.final_cost;
  a->iterations += internal::StepsTried(summary);
  a->stopped = summary.termination_type != ceres::NO_CONVERGENCE;
  if (!summary.IsSolutionUsable()) a->failure = summary.message;
  return summary.IsSolutionUsable();
}

// Huber's a per segment when some segments fit far worse than the typical
// one (their mean square above outlier_ratio x the median): the loss turns
// robust where a segment's squared norm passes a^2 = outlier_ratio x the
// typical mean square x its rows. Empty when none does; false when a replay
// fails.
bool HuberScales(const FrictionFitOptions& options, SegmentProblem* problem,
                 std::vector<double>* scale, int* outliers) {
  std::vector<double> mean_squares;
  if (!SegmentMeanSquares(problem, &mean_squares)) return false;
  std::vector<double> weighted;  // blocks with a weighted row (not all in a gap)
  for (double m : mean_squares)
    if (!std::isnan(m)) weighted.push_back(m);
  if (weighted.empty()) return true;
  const double typical = internal::Median(weighted);
  *outliers = static_cast<int>(std::count_if(weighted.begin(), weighted.end(), [&](double m) {
    return m > options.outlier_ratio * typical;
  }));
  if (*outliers > 0) {
    for (int n : problem->weighted_rows)
      scale->push_back(std::sqrt(options.outlier_ratio * typical * std::max(n, 1)));
  }
  return true;
}

Attempt FitFrom(const StrokeData& data, double mass_kg, const FrictionFitOptions& options,
                const Block (&prior_blocks)[2], const Block (&start)[2],
                const bool (&free_direction)[2],
                const std::array<double, kDirectionParameters>& sigma) {
  Attempt a;
  a.blocks[0] = start[0];
  a.blocks[1] = start[1];
  for (const Segment& s : data.segments) a.stop_time_s.push_back(s.stop_time_guess_s);
  std::vector<double*> free_blocks;
  for (int d = 0; d < 2; ++d) {
    if (free_direction[d]) free_blocks.push_back(a.blocks[d].data());
  }
  SegmentProblem plain_fit, robust_fit;
  if (!SolveOnce(data, mass_kg, options, prior_blocks, free_direction, sigma, {}, true, &a,
                 &plain_fit))
    return a;
  std::vector<double> huber_scale;
  if (!HuberScales(options, &plain_fit, &huber_scale, &a.outlier_segments)) {
    a.failure = "a replay failed at the solution";
    return a;
  }
  SegmentProblem* last = &plain_fit;
  if (!huber_scale.empty()) {  // the Jacobians are taken after the refit
    if (!SolveOnce(data, mass_kg, options, prior_blocks, free_direction, sigma, huber_scale, false,
                   &a, &robust_fit))
      return a;
    last = &robust_fit;
  }
  if (!Evaluate(data, free_blocks, last, &a.jacobians)) {
    a.failure = "a replay failed at the solution";
    return a;
  }
  // The misfit without the Huber loss, at the values found: the plain
  // problem's segment and slide rows (its prior rows come after them).
  double misfit[3];
  if (DirectionMisfits(data, &plain_fit, misfit)) a.misfit = misfit[0] + misfit[1] + misfit[2];
  return a;
}

// FitFriction on the strokes `data` cut from `unit`.
FrictionFitResult FitStrokes(const Unit& unit, const StrokeData& data, const FrictionParams& prior,
                             const FrictionFitOptions& options) {
  FrictionFitResult result;
  result.positive.params = prior.positive;
  result.negative.params = prior.negative;
  const Block prior_blocks[2] = {Pack(prior.positive), Pack(prior.negative)};
  result.excluded_segments = data.excluded;
  result.positive.segments = SegmentsOf(data, +1);
  result.negative.segments = SegmentsOf(data, -1);
  result.positive.smooth_slides = ClustersOf(data, +1);
  result.negative.smooth_slides = ClustersOf(data, -1);
  result.smooth_samples = 0;
  for (const auto& c : data.clusters)
    result.smooth_samples += static_cast<int>(c.speed_m_per_s.size());
  if (result.positive.segments + result.negative.segments + result.positive.smooth_slides +
          result.negative.smooth_slides ==
      0) {
    const std::string why = "no slide found in the stroke logs " + data.skipped;
    result.reason = why + "; the prior is kept";
    std::array<std::string, 2 * kDirectionParameters> held;
    held.fill(why);
    SetCoefficients(prior_blocks, prior_blocks, held, {}, {}, &result);
    return result;
  }
  // Starts from the data: Fs from the breakaways, Fd, b, vs from the force
  // balance of the smooth slides; the prior where the logs give none.
  LogsReading reading[2] = {ReadOffLogs(data, +1, prior_blocks[0]),
                            ReadOffLogs(data, -1, prior_blocks[1])};
  Block positive = reading[0].value, negative = reading[1].value;
  for (Block* block : {&positive, &negative}) {  // Ceres refuses a start outside
    for (int i = 0; i < kDirectionParameters; ++i)
      (*block)[i] = std::clamp((*block)[i], kLowerBounds[i], kUpperBounds[i]);
  }
  Block* const blocks[2] = {&positive, &negative};
  const double mass_kg = unit.manifest.rig.load_mass_kg;
  Block logs_start[2] = {positive, negative};
  bool stopped = true;  // the kept solve stopped before its iteration limit
  if (options.screen_starts && !data.segments.empty()) {
    result.start_screen = ScreenStarts(data, mass_kg, options, &positive, &negative);
  }
  // Held coefficients (columns 0-3 positive, 4-7 negative) with why: a
  // direction without slides keeps the prior whole.
  std::array<std::string, 2 * kDirectionParameters> held;
  for (int d = 0; d < 2; ++d) {
    const DirectionFit& fit = d == 0 ? result.positive : result.negative;
    if (fit.segments + fit.smooth_slides > 0) continue;
    for (int i = 0; i < kDirectionParameters; ++i)
      held[d * kDirectionParameters + i] = "no slide this way";
    *blocks[d] = prior_blocks[d];
    logs_start[d] = prior_blocks[d];
    reading[d].read.fill(false);
  }
  std::vector<SegmentJacobian> jacobians;
  std::vector<int> free;  // the columns fitted (then: determined)
  Eigen::MatrixXd covariance;
  const std::array<double, kDirectionParameters> sigma = PriorSigmas(options);
  // One fit of every coefficient of a direction with slides (the weak prior
  // keeps it regular); what it finds undetermined is then reported as held,
  // its value the regularised one or the prior's (held_at_prior). A refit
  // with them held at the prior's distorted the determined ones (Fd 0.19 for
  // 0.29 on a heavy unit whose one fit gave 0.292), so there is none.
  {
    bool free_direction[2] = {false, false};
    std::vector<int> columns;  // of the free blocks, in Evaluate's order
    for (int d = 0; d < 2; ++d) {
      for (int i = 0; i < kDirectionParameters; ++i)
        free_direction[d] = free_direction[d] || held[d * kDirectionParameters + i].empty();
      if (!free_direction[d]) continue;
      for (int i = 0; i < kDirectionParameters; ++i)
        columns.push_back(d * kDirectionParameters + i);
    }
    for (int c : columns) {
      if (held[c].empty()) free.push_back(c);
    }
    // From the starts read off the logs and, when the screen found a better
    // one, from that too: the screened fit is kept when its misfit is lower
    // by more than 1 % (two fits into one minimum differ in the fifth digit,
    // and the refinement started from either takes another path).
    const Block start[2] = {positive, negative};
    Attempt fit = FitFrom(data, mass_kg, options, prior_blocks, logs_start, free_direction, sigma);
    if (start[0] != logs_start[0] || start[1] != logs_start[1]) {
      Attempt screened =
          FitFrom(data, mass_kg, options, prior_blocks, start, free_direction, sigma);
      const int iterations = fit.iterations + screened.iterations;  // both fits ran
      if (screened.failure.empty() &&
          (!fit.failure.empty() || screened.misfit < 0.99 * fit.misfit)) {
        fit = std::move(screened);
        result.start_screen.used = true;
      }
      fit.iterations = iterations;
    }
    if (!fit.failure.empty()) {
      result.reason = "Ceres failed (" + fit.failure + "); the prior is kept";
      std::array<std::string, 2 * kDirectionParameters> all;
      all.fill("Ceres failed");
      SetCoefficients(prior_blocks, prior_blocks, all, {}, {}, &result);
      return result;
    }
    positive = fit.blocks[0];
    negative = fit.blocks[1];
    jacobians = std::move(fit.jacobians);
    result.initial_cost = fit.initial_cost;
    result.final_cost = fit.final_cost;
    result.iterations = fit.iterations;
    result.outlier_segments = fit.outlier_segments;
    stopped = fit.stopped;
    covariance = RobustCovariance(jacobians, columns, free, blocks, sigma);
    MarkUndetermined(covariance, free, blocks, options, &held);
    for (int c = 0; c < 2 * kDirectionParameters; ++c) {
      if (!held[c].empty() && options.held_at_prior) {
        (*blocks[c / kDirectionParameters])[c % kDirectionParameters] =
            prior_blocks[c / kDirectionParameters][c % kDirectionParameters];
      }
    }
    KeepDetermined(held, &free, &covariance);
    WidenByDisagreement(reading, blocks, free, &covariance);
  }
  result.segments = static_cast<int>(data.segments.size());
  double squares = 0;
  for (std::size_t k = 0; k < data.segments.size(); ++k) {
    const Eigen::VectorXd& r = jacobians[k].residuals;
    for (Eigen::Index i = 0; i < r.size(); ++i) {
      const double weight = data.segments[k].weight[i + 1];
      if (weight == 0) continue;  // in a gap of the log: no measurement
      squares += std::pow(r(i) / weight, 2);
      ++result.samples;
    }
  }
  result.position_rms_m = std::sqrt(squares / std::max(result.samples, 1));
  result.status = stopped ? FitStatus::kConverged : FitStatus::kNotConverged;
  result.positive.params = Unpack(positive);
  result.negative.params = Unpack(negative);
  const Block fitted[2] = {positive, negative};
  SetCoefficients(prior_blocks, fitted, held, free, covariance, &result);
  if (!stopped) result.reason = "the solver reached its iteration limit";
  if (!data.skipped.empty())
    result.reason += (result.reason.empty() ? "not used: " : "; not used: ") + data.skipped;
  return result;
}

}  // namespace

FrictionFitResult FitFriction(const Unit& unit, const FrictionParams& prior,
                              const FrictionFitOptions& options) {
  StrokeData data = PrepareStrokes(unit, options);
  // A breakaway from a stop is replayed through the fast pressure transient
  // of a chamber near its dead volume (FrictionFitOptions::end_slide_m):
  // only a direction with too few slides that break away mid-stroke
  // (strokes from stop to stop) reads its Fs there from the start...
  std::array<bool, 2> from_stops = {SegmentsOf(data, +1) < kMinMidStrokeBreakaways,
                                    SegmentsOf(data, -1) < kMinMidStrokeBreakaways};
  const auto departs = [&data, &options](int d) {
    return options.end_slide_m > 0 && data.stop_departures[d] > 0;
  };
  if ((from_stops[0] && departs(0)) || (from_stops[1] && departs(1))) {
    data = PrepareStrokes(unit, options, {}, from_stops);
  }
  FrictionFitResult result = FitStrokes(unit, data, prior, options);
  // ... and one whose Fs its slides mid-stroke do not determine, fitted again.
  bool again_needed = false;
  for (int d = 0; d < 2; ++d) {
    const FittedCoefficient* fs =
        result.Find(std::string("friction.") + (d == 0 ? "positive" : "negative") + ".Fs");
    const bool undetermined = fs != nullptr && !fs->determined();
    if (!from_stops[d] && departs(d) && undetermined) from_stops[d] = again_needed = true;
  }
  if (!again_needed) return result;
  const StrokeData with_stops = PrepareStrokes(unit, options, {}, from_stops);
  FrictionFitResult again = FitStrokes(unit, with_stops, prior, options);
  // Kept unless it failed or ran out of iterations where the first did not.
  const bool first_converged = result.status == FitStatus::kConverged;
  if (again.status == FitStatus::kConverged || (!first_converged && again.has_values()))
    return again;
  return result;
}

std::string FrictionFitResult::BriefReport() const {
  std::ostringstream out;
  out << "Friction fit: " << ToString(status);
  if (!has_values()) {
    out << " (" << reason << ")\n";
    return out.str();
  }
  char line[320];
  std::snprintf(line, sizeof(line),
                ", %d segments (%d samples, %d near the stroke ends left out, %d outliers), %d "
                "force-balance samples, cost %.4g -> %.4g in %d iterations, position RMS %.3g mm\n",
                segments, samples, excluded_segments, outlier_segments, smooth_samples,
                initial_cost, final_cost, iterations, position_rms_m * 1e3);
  out << line;
  for (const auto& [name, fit] :
       {std::make_pair("positive", &positive), std::make_pair("negative", &negative)}) {
    std::snprintf(line, sizeof(line), "  %s: %d slides replayed, %d smooth slides\n", name,
                  fit->segments, fit->smooth_slides);
    out << line;
  }
  if (start_screen.candidates > 0) {
    std::snprintf(line, sizeof(line),
                  "  start screened (%d candidates): misfit positive %.4g -> %.4g, negative %.4g "
                  "-> %.4g; %s\n",
                  start_screen.candidates, start_screen.start_misfit[0],
                  start_screen.best_misfit[0], start_screen.start_misfit[1],
                  start_screen.best_misfit[1],
                  start_screen.used ? "the fit from the screened start was kept"
                                    : "the fit from the logs' start was kept");
    out << line;
  }
  out << CoefficientReport("  ");
  if (!reason.empty()) out << "  " << reason << "\n";
  return out.str();
}

}  // namespace pneumaid
