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

#include "determination.h"
#include "friction_slides.h"
#include "pneumaid/ident/rod_replay.h"
#include "pneumaid/model/load.h"

namespace pneumaid {
namespace {

constexpr int kDirectionParameters = 4;  // Fs, Fd, b, vs
// params-v1 names (friction.<direction>.<name>).
const char* const kParameterNames[kDirectionParameters] = {"Fs", "Fd", "b", "vs"};
// Lower bounds: forces and damping are magnitudes; vs > 0 keeps Eq. 12 defined.
const double kLowerBounds[kDirectionParameters] = {0.0, 0.0, 0.0, 1e-4};
// Upper bounds: configs/fit-default.yaml's, so that refinement can start
// from whatever the fit gives (a vs of 1.9 m/s once came out of a unit whose
// slides never slowed down).
const double kUpperBounds[kDirectionParameters] = {200.0, 200.0, 1000.0, 1.0};
// Standard errors below these count as determined whatever the value (the
// identification's tolerances: 0.1 N, 0.5 N s/m, 1 mm/s).
const double kDeterminedFloor[kDirectionParameters] = {0.1, 0.1, 0.5, 1e-3};

using Block = std::array<double, kDirectionParameters>;

Block Pack(const StribeckParams& p) {
  return {p.static_force_N, p.dynamic_force_N, p.viscous_N_s_per_m, p.stribeck_velocity_m_per_s};
}

StribeckParams Unpack(const Block& b) { return {b[0], b[1], b[2], b[3]}; }

template <typename T>
StribeckCoefficients<T> Coefficients(const T* theta) {
  return {theta[0], theta[1], theta[2], theta[3]};
}

// One stretch of a stroke log: starts stuck, ends a few samples into the next
// stuck phase (or at the log's end).
struct Segment {
  const std::vector<double>* force_N;
  const std::vector<double>* position_m;
  std::size_t begin, end;  // samples [begin, end)
  double period_s;         // of its log
  double initial_position_m;
  int direction;  // of the slide: +1, -1, or 0 (stays stuck)
  // A slide that ends in a logged arrest is replayed from both of its ends:
  // forward from the start up to `split` (its fastest sample), backward from
  // the arrest after it; the arrest time is a nuisance parameter.
  bool two_sided = false;
  std::size_t split = 0;
  double stop_position_m = 0, stop_time_guess_s = 0, stop_time_min_s = 0, stop_time_max_s = 0;
  // Where the logged slide starts and (two-sided) stops, for the weights.
  std::size_t slide_begin = 0, arrest = 0;
  // 1 / (expected residual std) per sample of the segment: the position
  // noise, and the drift that the force's noise integrated twice adds with
  // the distance from the nearest exactly known state (stuck, v = 0).
  std::vector<double> weight;
};

RodReplayInput ReplayOf(const Segment& s, double mass_kg, int substeps) {
  RodReplayInput replay;
  replay.force_N = s.force_N->data() + s.begin;
  replay.samples = s.end - s.begin;
  replay.period_s = s.period_s;
  replay.mass_kg = mass_kg;
  replay.initial_position_m = s.initial_position_m;
  replay.substeps = substeps;
  return replay;
}

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

using Runs = std::vector<std::pair<std::size_t, std::size_t>>;

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

// Runs [begin, end) of at least `min_samples` samples whose values stay
// within `band` of each other, and whose motion over the run's first four
// fifths (the last samples may already be the slide) is that of a rod at
// rest: slope below `max_speed` [per sample] and curvature below `max_accel`
// [per sample^2], or within 4 x what the position noise gives. At a high
// sample rate a slow slide stays inside the band for many samples, and the
// apex of a reversal without stick looks still for a while: neither is stuck.
Runs StuckRuns(const std::vector<double>& x, double band, int min_samples, double max_speed,
               double max_accel, double sigma) {
  Runs runs;
  std::size_t begin = 0;
  while (begin < x.size()) {
    double low = x[begin], high = x[begin];
    std::size_t end = begin + 1;
    while (end < x.size() && std::max(high, x[end]) - std::min(low, x[end]) <= band) {
      low = std::min(low, x[end]);
      high = std::max(high, x[end]);
      ++end;
    }
    const std::size_t length = end - begin;
    bool still = static_cast<int>(length) >= min_samples;
    if (still) {
      const std::size_t fitted = std::max<std::size_t>(3, length * 4 / 5);
      const auto [slope, curvature] = SlopeAndCurvature(x, begin, begin + fitted);
      const auto [slope_noise, curvature_noise] =
          SlopeAndCurvatureNoise(sigma, static_cast<double>(fitted));
      still = std::fabs(slope) <= std::max(max_speed, 4 * slope_noise) &&
              std::fabs(curvature) <= std::max(max_accel, 4 * curvature_noise);
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

// Everything the Ceres problem reads: per stroke log its driving force and
// position, and the segments cut from them.
struct StrokeData {
  std::vector<std::vector<double>> force_N, position_m;
  std::vector<Segment> segments;
  std::vector<internal::SlideCluster> clusters;  // smooth slides no segment covers
  // Breakaway forces (magnitudes) of stuck phases at the stroke ends, which
  // start no segment: positive direction first.
  std::vector<double> end_breakaway_N[2];
  int excluded = 0;
  std::string skipped;  // logs that could not be used, why
};

// While the rod sticks the chamber volumes are constant and the force varies
// smoothly (the valve filling a closed chamber), so its noise is averaged out
// by a quadratic fit over the last `window` samples of each stuck run. That
// matters at breakaway: the first crossing of Fs by the raw noisy force comes
// early, and a replay driven by it would bias Fs.
void SmoothStuckForce(const Runs& runs, std::size_t window, std::vector<double>* force) {
  for (const auto& [begin, end] : runs) {
    // The first samples of a run still carry the arrest's pressure transient.
    const std::size_t first =
        end - std::min(window, end - begin - std::min<std::size_t>(3, end - begin));
    const std::size_t n = end - 1 - first;  // the run's last sample may already move
    if (n < 8) continue;
    Eigen::MatrixXd design(n, 3);
    Eigen::VectorXd y(n);
    const double centre = 0.5 * static_cast<double>(first + end - 1);
    for (std::size_t i = 0; i < n; ++i) {
      const double s = (static_cast<double>(first + i) - centre) / static_cast<double>(n);
      for (int power = 0; power < 3; ++power) design(i, power) = std::pow(s, power);
      y(i) = (*force)[first + i];
    }
    const Eigen::Vector3d c = design.colPivHouseholderQr().solve(y);
    for (std::size_t i = first; i < end; ++i) {
      const double s = (static_cast<double>(i) - centre) / static_cast<double>(n);
      (*force)[i] = c(0) + s * (c(1) + s * c(2));
    }
  }
}

double UniformPeriod(const std::vector<double>& t) {
  if (t.size() < 2) return 0;
  const double period = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (std::fabs(t[i] - t[i - 1] - period) > 0.01 * period) return 0;
  }
  return period;
}

// Residual weights of `s`: a sample n intervals from the last known state
// (the breakaway forward, the arrest backward) carries the position noise and
// a drift of variance (sigma_F h^2 / M)^2 n^3 / 3 from the force's noise.
void SetWeights(double sigma_x_m, double drift_m, Segment* s) {
  s->weight.assign(s->end - s->begin, 1.0 / sigma_x_m);
  for (std::size_t i = s->begin; i < s->end; ++i) {
    double n = i > s->slide_begin ? static_cast<double>(i - s->slide_begin) : 0.0;
    if (s->two_sided && i > s->split) {
      n = s->arrest > i ? static_cast<double>(s->arrest - i) : 0.0;
    }
    const double variance = sigma_x_m * sigma_x_m + drift_m * drift_m * n * n * n / 3.0;
    s->weight[i - s->begin] = 1.0 / std::sqrt(variance);
  }
}

// The slide of `s` ends in the stuck run `next`: where it stopped, when
// (a guess and bounds for the nuisance parameter), and its fastest sample.
void MarkArrest(const std::vector<double>& x, std::size_t slide_begin,
                std::pair<std::size_t, std::size_t> next, double period_s, Segment* s) {
  const auto [arrest, next_end] = next;
  std::size_t split = slide_begin - 1;
  for (std::size_t j = slide_begin - 1; j + 1 < arrest; ++j) {
    if (std::fabs(x[j + 1] - x[j]) > std::fabs(x[split + 1] - x[split])) split = j;
  }
  if (split + 2 >= s->end || split < s->begin + 1) return;
  const std::size_t settled_end = std::min(next_end, arrest + 21);
  s->stop_position_m = std::accumulate(x.begin() + arrest + 1, x.begin() + settled_end, 0.0) /
                       static_cast<double>(settled_end - arrest - 1);
  s->split = split;
  s->stop_time_min_s = (static_cast<double>(split - s->begin) + 0.05) * period_s;
  s->stop_time_max_s = static_cast<double>(s->end - 1 - s->begin) * period_s;
  s->stop_time_guess_s = std::clamp((static_cast<double>(arrest - s->begin) - 0.5) * period_s,
                                    s->stop_time_min_s, s->stop_time_max_s);
  s->two_sided = settled_end > arrest + 1;
  s->arrest = arrest;
}

double Median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

// Where the rod may touch an end stop: within `contact_m` of either end.
// +1 at the extended end, -1 at the retracted one, 0 elsewhere.
int EndContact(double x, double half_stroke_m, double contact_m) {
  if (x > half_stroke_m - contact_m) return +1;
  if (x < -half_stroke_m + contact_m) return -1;
  return 0;
}

void CutSegments(const std::vector<double>& force, const std::vector<double>& x, const Runs& runs,
                 double band, double half_stroke_m, double contact_m, double period_s,
                 double sigma_x_m, double drift_m, const FrictionFitOptions& options,
                 StrokeData* data) {
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const auto [stuck_begin, stuck_end] = runs[k];
    Segment s{};
    s.force_N = &force;
    s.position_m = &x;
    s.period_s = period_s;
    s.begin = std::max(stuck_begin + 1,
                       stuck_end - std::min<std::size_t>(stuck_end, options.max_stuck_samples));
    // A rod stuck at an end may rest on the stop, and the pressures there
    // change faster than a replay between samples follows (the chamber at
    // the end is nearly its dead volume): no segment starts there. Its
    // breakaway force still tells Fs.
    if (EndContact(x[stuck_end - 1], half_stroke_m, contact_m) != 0) {
      const std::size_t after = std::min(x.size() - 1, stuck_end + options.min_stuck_samples);
      const double travel = x[after] - x[stuck_end - 1];
      if (std::fabs(travel) > band) {
        const int direction = travel > 0 ? +1 : -1;
        // The breakaway: the last sample still within 3 sigma of where the
        // rod rested (the band's edge is crossed later, at a higher force).
        std::vector<double> rest(x.begin() + stuck_begin, x.begin() + stuck_end);
        const double rested = Median(rest);
        std::size_t at = stuck_end - 1;
        while (at > stuck_begin && std::fabs(x[at] - rested) > 3 * sigma_x_m) --at;
        data->end_breakaway_N[direction > 0 ? 0 : 1].push_back(direction * force[at]);
      }
      ++data->excluded;
      continue;
    }
    // The run's last sample may already be the first of the slide.
    const std::size_t settled_end = std::max(s.begin + 1, stuck_end - 1);
    s.initial_position_m = std::accumulate(x.begin() + s.begin, x.begin() + settled_end, 0.0) /
                           static_cast<double>(settled_end - s.begin);
    s.end = k + 1 < runs.size()
                ? runs[k + 1].first + std::min<std::size_t>(options.arrest_samples,
                                                            runs[k + 1].second - runs[k + 1].first)
                : stuck_end;
    // The slide ends where the rod may touch a stop (end-stop forces are not
    // friction): the segment is cut there and loses its arrest.
    // A replay over a long slide integrates any bias of the force twice: the
    // rest of such a slide is left to the force balance (friction_slides.h).
    const std::size_t max_slide = std::max<std::size_t>(
        options.min_stuck_samples, static_cast<std::size_t>(options.max_slide_s / period_s));
    bool cut = false;
    if (s.end > stuck_end + max_slide) {
      s.end = stuck_end + max_slide;
      cut = true;
    }
    for (std::size_t i = stuck_end; i < s.end; ++i) {
      if (EndContact(x[i], half_stroke_m, contact_m) != 0) {
        s.end = i;
        cut = true;
        break;
      }
    }
    if (s.end < stuck_end + options.min_stuck_samples) {
      ++data->excluded;
      continue;
    }
    const double travel = x[s.end - 1] - s.initial_position_m;
    s.direction = travel > band ? +1 : (travel < -band ? -1 : 0);
    s.slide_begin = stuck_end - 1;
    if (s.direction != 0 && k + 1 < runs.size() && !cut)
      MarkArrest(x, stuck_end, runs[k + 1], period_s, &s);
    SetWeights(sigma_x_m, drift_m, &s);
    data->segments.push_back(s);
  }
}

StrokeData PrepareStrokes(const Unit& unit, const FrictionFitOptions& options, double band,
                          double sigma_x_m) {
  const RigConstants& rig = unit.manifest.rig;
  const double force_sigma_N = std::hypot(unit.manifest.DeclaredSigma("p1", 0.0) * rig.area_1_m2(),
                                          unit.manifest.DeclaredSigma("p2", 0.0) * rig.area_2_m2());
  const double weight_N =
      rig.orientation == Orientation::kVertical ? rig.load_mass_kg * kStandardGravity_m_per_s2 : 0;
  StrokeData data;
  std::size_t count = 0;
  for (const Experiment& e : unit.experiments) {
    if (e.entry.kind == ExperimentKind::kStroke) ++count;
  }
  // Segments point into these vectors: reserve so that they never move.
  data.force_N.reserve(count);
  data.position_m.reserve(count);
  for (const Experiment& e : unit.experiments) {
    if (e.entry.kind != ExperimentKind::kStroke) continue;
    const double period = UniformPeriod(e.column("t"));
    if (period <= 0) {
      data.skipped += e.entry.id + " (not uniformly sampled) ";
      continue;
    }
    const auto &p1 = e.column("p1"), &p2 = e.column("p2");
    std::vector<double> force(p1.size());
    for (std::size_t i = 0; i < force.size(); ++i) {
      force[i] = PneumaticAndGravityForce(p1[i], p2[i], rig.atmospheric_pressure_Pa,
                                          rig.area_1_m2(), rig.area_2_m2(), weight_N);
    }
    const auto& x = e.column("x");
    const int min_samples = std::max(options.min_stuck_samples,
                                     static_cast<int>(std::ceil(options.min_stuck_s / period)));
    const Runs runs =
        StuckRuns(x, band, min_samples, options.max_stuck_speed_m_per_s * period,
                  options.max_stuck_acceleration_m_per_s2 * period * period, sigma_x_m);
    SmoothStuckForce(runs, options.stuck_force_samples, &force);
    data.force_N.push_back(std::move(force));
    data.position_m.push_back(x);
    const double drift_m = force_sigma_N * period * period / rig.load_mass_kg;
    const std::size_t first_segment = data.segments.size();
    CutSegments(data.force_N.back(), data.position_m.back(), runs, band, 0.5 * rig.stroke_m,
                options.end_margin_m + 4 * sigma_x_m, period, sigma_x_m, drift_m, options, &data);
    if (!options.force_balance) continue;
    std::vector<bool> covered(x.size(), false);
    for (const auto& [begin, end] : runs)
      std::fill(covered.begin() + begin, covered.begin() + end, true);
    for (std::size_t k = first_segment; k < data.segments.size(); ++k) {
      const Segment& segment = data.segments[k];
      std::fill(covered.begin() + segment.begin, covered.begin() + segment.end, true);
    }
    internal::SlideSampling sampling;
    sampling.period_s = period;
    sampling.mass_kg = rig.load_mass_kg;
    sampling.sigma_x_m = sigma_x_m;
    sampling.sigma_force_N = std::max(force_sigma_N, 1e-3);
    sampling.half_stroke_m = 0.5 * rig.stroke_m;
    sampling.end_zone_m = options.end_margin_m + 4 * sigma_x_m;
    sampling.window_s = options.smoothing_window_s;
    for (auto& cluster :
         internal::SlidingSamples(data.position_m.back(), data.force_N.back(), covered, sampling)) {
      data.clusters.push_back(std::move(cluster));
    }
  }
  return data;
}

// Median over the slides of `direction` of the force on the last sample
// before the rod has covered a quarter of the segment's travel: about where
// it broke away, a starting point for Fs; without three such slides, the
// median breakaway force at the stroke ends.
double BreakawayMedian(const StrokeData& data, int direction, double fallback) {
  std::vector<double> forces;
  for (const Segment& s : data.segments) {
    if (s.direction != direction) continue;
    std::size_t i = s.begin;
    while (i + 1 < s.end && std::fabs((*s.position_m)[i + 1] - s.initial_position_m) <
                                std::fabs((*s.position_m)[s.end - 1] - s.initial_position_m) / 4) {
      ++i;
    }
    forces.push_back(direction * (*s.force_N)[i]);
  }
  if (forces.size() >= 3) return Median(forces);
  const std::vector<double>& at_ends = data.end_breakaway_N[direction > 0 ? 0 : 1];
  return at_ends.size() >= 3 ? Median(at_ends) : fallback;
}

int SegmentsOf(const StrokeData& data, int direction) {
  return static_cast<int>(
      std::count_if(data.segments.begin(), data.segments.end(),
                    [direction](const Segment& s) { return s.direction == direction; }));
}

int ClustersOf(const StrokeData& data, int direction) {
  return static_cast<int>(std::count_if(
      data.clusters.begin(), data.clusters.end(),
      [direction](const internal::SlideCluster& c) { return c.direction == direction; }));
}

// The Ceres problem over the segments: friction blocks shared, one arrest
// time per two-sided segment.
struct SegmentProblem {
  ceres::Problem problem;
  std::vector<int> rows;  // residuals per segment
  // Per segment (unused when one-sided); kept from one pass to the next.
  std::vector<double>* stop_time_s = nullptr;
};

void BuildProblem(const StrokeData& data, double mass_kg, const FrictionFitOptions& options,
                  const std::vector<double>& huber_scale, Block* positive, Block* negative,
                  SegmentProblem* p) {
  for (std::size_t k = 0; k < data.segments.size(); ++k) {
    const Segment& s = data.segments[k];
    const RodReplayInput replay = ReplayOf(s, mass_kg, options.substeps);
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
  }
  for (Block* block : {positive, negative}) {
    for (int i = 0; i < kDirectionParameters; ++i) {
      p->problem.SetParameterLowerBound(block->data(), i, kLowerBounds[i]);
      p->problem.SetParameterUpperBound(block->data(), i, kUpperBounds[i]);
    }
  }
}

ceres::Solver::Summary Solve(const FrictionFitOptions& options, ceres::Problem* problem) {
  ceres::Solver::Options solver_options;
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

// Per segment: its residuals, the Jacobian's friction columns (the free
// blocks, positive first) and its arrest-time column (empty when one-sided),
// robust loss applied.
struct SegmentJacobian {
  Eigen::VectorXd residuals;
  Eigen::MatrixXd friction;
  Eigen::VectorXd stop_time;
};

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

// Mean squared residual of each segment (residuals only: cheap).
bool SegmentMeanSquares(SegmentProblem* p, std::vector<double>* out) {
  std::vector<double> r;
  if (!p->problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, &r, nullptr, nullptr)) {
    return false;
  }
  out->clear();
  std::size_t row = 0;
  for (const int n : p->rows) {
    double squares = 0;
    for (int i = 0; i < n; ++i, ++row) squares += r[row] * r[row];
    out->push_back(squares / n);
  }
  return true;
}

// The information J'J of the friction columns and the sum of the clusters'
// score outer products (J_k' r_k)(J_k' r_k)', segments and force-balance
// slides being the clusters and each arrest time eliminated inside its own
// segment (the Schur complement): the bread and meat of the cluster-robust
// covariance (J'J)^-1 meat (J'J)^-1.
void Information(const std::vector<SegmentJacobian>& segments, Eigen::MatrixXd* information,
                 Eigen::MatrixXd* meat) {
  const Eigen::Index m = segments.front().friction.cols();
  *information = Eigen::MatrixXd::Zero(m, m);
  *meat = Eigen::MatrixXd::Zero(m, m);
  for (const SegmentJacobian& j : segments) {
    Eigen::MatrixXd a = j.friction;
    Eigen::VectorXd r = j.residuals;
    const double norm = j.stop_time.size() ? j.stop_time.squaredNorm() : 0.0;
    if (norm > 0) {
      a -= j.stop_time * (j.stop_time.transpose() * a) / norm;
      r -= j.stop_time * (j.stop_time.dot(r) / norm);
    }
    *information += a.transpose() * a;
    const Eigen::VectorXd score = a.transpose() * r;
    *meat += score * score.transpose();
  }
}

std::string ColumnName(int column) {
  return std::string(column < kDirectionParameters ? "positive." : "negative.") +
         kParameterNames[column % kDirectionParameters];
}

std::array<double, kDirectionParameters> PriorSigmas(const FrictionFitOptions& options) {
  return {options.prior_static_sigma_N, options.prior_dynamic_sigma_N,
          options.prior_viscous_sigma_N_s_per_m, options.prior_stribeck_log_sigma};
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

// Fd, b, vs of one direction from its force-balance samples with Fs given
// (the breakaways): for each vs on a log grid (1 mm/s to 0.1 m/s) the
// magnitude Fs e + Fd (1 - e) + b v, e = exp(-(v/vs)^2), is linear in
// (Fd, b); the grid point that fits best, Fd in [0, Fs] and b >= 0. Leaves
// `block` as it is with fewer than 20 samples.
void ForceBalanceStart(const StrokeData& data, int direction, Block* block) {
  std::size_t samples = 0;
  for (const auto& c : data.clusters) {
    if (c.direction == direction) samples += c.speed_m_per_s.size();
  }
  if (samples < 20) return;
  const double fs = (*block)[0];
  double best = HUGE_VAL;
  for (int g = 0; g <= 24; ++g) {
    const double vs = 1e-3 * std::pow(100.0, g / 24.0);
    Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
    Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
    const auto each = [&](const auto& use) {
      for (const auto& c : data.clusters) {
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
    theta(0) = std::clamp(theta(0), 0.0, fs);
    double cost = 0;
    each([&](const Eigen::Vector2d& x, double y, double w) {
      cost += w * std::pow(y - x.dot(theta), 2);
    });
    if (cost < best) best = cost, *block = {fs, theta(0), theta(1), vs};
  }
}

}  // namespace

bool FrictionFitOptions::IsValid(std::string* error) const {
  const auto fail = [error](const char* what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (!(stuck_band_m > 0)) return fail("stuck_band_m must be > 0");
  if (min_stuck_samples < 2) return fail("min_stuck_samples must be >= 2");
  if (max_stuck_samples < 2) return fail("max_stuck_samples must be >= 2");
  if (arrest_samples < 0) return fail("arrest_samples must be >= 0");
  if (stuck_force_samples < 3) return fail("stuck_force_samples must be >= 3");
  if (!(end_margin_m >= 0)) return fail("end_margin_m must be >= 0");
  if (substeps < 1) return fail("substeps must be >= 1");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(outlier_ratio > 1)) return fail("outlier_ratio must be > 1");
  if (!(identifiable_relative_error > 0)) return fail("identifiable_relative_error must be > 0");
  if (!(prior_static_sigma_N > 0) || !(prior_dynamic_sigma_N > 0) ||
      !(prior_viscous_sigma_N_s_per_m > 0) || !(prior_stribeck_log_sigma > 0))
    return fail("prior_*_sigma must be > 0");
  if (!(min_stuck_s >= 0)) return fail("min_stuck_s must be >= 0");
  if (!(max_stuck_speed_m_per_s > 0)) return fail("max_stuck_speed_m_per_s must be > 0");
  if (!(max_stuck_acceleration_m_per_s2 > 0))
    return fail("max_stuck_acceleration_m_per_s2 must be > 0");
  if (!(max_slide_s > 0)) return fail("max_slide_s must be > 0");
  return true;
}

FrictionFitResult FitFriction(const Unit& unit, const FrictionParams& prior,
                              const FrictionFitOptions& options) {
  FrictionFitResult result;
  result.positive.params = prior.positive;
  result.negative.params = prior.negative;
  const double sigma_m = unit.manifest.DeclaredSigma("x", 1e-5);
  const double band = options.stuck_band_m + 6.0 * sigma_m;
  const StrokeData data = PrepareStrokes(unit, options, band, sigma_m);
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
    result.note = "no slide found in the stroke logs " + data.skipped + "; the prior is kept";
    return result;
  }
  // Starts from the data: Fs from the breakaways, Fd, b, vs from the force
  // balance of the smooth slides; the prior where the logs give none.
  const Block prior_blocks[2] = {Pack(prior.positive), Pack(prior.negative)};
  Block positive = prior_blocks[0], negative = prior_blocks[1];
  positive[0] = BreakawayMedian(data, +1, positive[0]);
  negative[0] = BreakawayMedian(data, -1, negative[0]);
  ForceBalanceStart(data, +1, &positive);
  ForceBalanceStart(data, -1, &negative);
  Block* const blocks[2] = {&positive, &negative};
  const double mass_kg = unit.manifest.rig.load_mass_kg;
  // Held coefficients (columns 0-3 positive, 4-7 negative) with why: a
  // direction without slides keeps the prior whole.
  std::array<std::string, 2 * kDirectionParameters> held;
  for (int d = 0; d < 2; ++d) {
    const DirectionFit& fit = d == 0 ? result.positive : result.negative;
    if (fit.segments + fit.smooth_slides > 0) continue;
    for (int i = 0; i < kDirectionParameters; ++i)
      held[d * kDirectionParameters + i] = "no slide this way";
    *blocks[d] = prior_blocks[d];
  }
  std::vector<double> stop_time_s;
  for (const Segment& s : data.segments) stop_time_s.push_back(s.stop_time_guess_s);
  std::vector<SegmentJacobian> jacobians;
  std::vector<double> huber_scale;  // empty: plain least squares
  std::vector<int> free;            // the columns fitted in the last round
  Eigen::MatrixXd covariance;
  const std::array<double, kDirectionParameters> sigma = PriorSigmas(options);
  // One fit of every coefficient of a direction with slides (the weak prior
  // keeps it regular); what it finds undetermined is then reported as held,
  // its value the regularised one or the prior's (held_at_prior). A refit
  // with them held at the prior's distorted the determined ones (Fd 0.19 for
  // 0.29 on a heavy unit whose one fit gave 0.292), so there is none.
  for (int round = 0; round < 1; ++round) {
    free.clear();
    std::vector<double*> free_blocks;
    std::vector<int> columns;  // of the free blocks, in Evaluate's order
    for (int d = 0; d < 2; ++d) {
      bool any = false;
      for (int i = 0; i < kDirectionParameters; ++i)
        any = any || held[d * kDirectionParameters + i].empty();
      if (!any) continue;
      free_blocks.push_back(blocks[d]->data());
      for (int i = 0; i < kDirectionParameters; ++i)
        columns.push_back(d * kDirectionParameters + i);
    }
    for (int c : columns) {
      if (held[c].empty()) free.push_back(c);
    }
    if (free.empty()) break;
    for (int pass = 0; pass < 2; ++pass) {
      SegmentProblem problem;
      problem.stop_time_s = &stop_time_s;
      BuildProblem(data, mass_kg, options, huber_scale, &positive, &negative, &problem);
      for (int d = 0; d < 2; ++d) {
        double* block = blocks[d]->data();
        if (std::find(free_blocks.begin(), free_blocks.end(), block) == free_blocks.end()) {
          problem.problem.SetParameterBlockConstant(block);
          continue;
        }
        problem.problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<PriorResidual, kDirectionParameters,
                                            kDirectionParameters>(
                new PriorResidual{prior_blocks[d], sigma}),
            nullptr, block);
        std::vector<int> constant;
        for (int i = 0; i < kDirectionParameters; ++i) {
          if (!held[d * kDirectionParameters + i].empty()) constant.push_back(i);
        }
        if (!constant.empty()) {
          problem.problem.SetManifold(block,
                                      new ceres::SubsetManifold(kDirectionParameters, constant));
        }
      }
      const ceres::Solver::Summary summary = Solve(options, &problem.problem);
      if (round == 0 && pass == 0) result.initial_cost = summary.initial_cost;
      result.final_cost = summary.final_cost;
      result.iterations += static_cast<int>(summary.iterations.size());
      const auto failed = [&] {
        result.note = "Ceres did not converge (" + summary.message + "); the prior is kept";
        return result;
      };
      if (!summary.IsSolutionUsable()) return failed();
      if (round == 0 && pass == 0) {
        // Segments far worse than the typical one (a disturbed stroke, a
        // bump on the rod): refit with each segment's influence bounded.
        std::vector<double> mean_squares;
        if (!SegmentMeanSquares(&problem, &mean_squares)) return failed();
        const double typical = Median(mean_squares);
        result.outlier_segments =
            static_cast<int>(std::count_if(mean_squares.begin(), mean_squares.end(), [&](double m) {
              return m > options.outlier_ratio * typical;
            }));
        if (result.outlier_segments > 0) {
          for (int n : problem.rows) huber_scale.push_back(options.outlier_ratio * typical * n);
          continue;  // the Jacobians are taken after the refit
        }
      }
      if (!Evaluate(data, free_blocks, &problem, &jacobians)) return failed();
      break;
    }
    // The robust covariance of the free columns: the data's information plus
    // the prior's in the bread, the clusters' scores and the prior (one more
    // independent observation of each coefficient) in the meat, so that
    // where the logs say nothing the error is the prior's, not zero.
    Eigen::MatrixXd information, meat;
    Information(jacobians, &information, &meat);
    const double clusters = static_cast<double>(jacobians.size());
    meat *= clusters / std::max(clusters - 1.0, 1.0);
    std::vector<Eigen::Index> index;  // of each free column in `columns`
    for (int c : free) {
      index.push_back(std::find(columns.begin(), columns.end(), c) - columns.begin());
    }
    const Eigen::Index m = static_cast<Eigen::Index>(free.size());
    Eigen::MatrixXd bread(m, m), score(m, m);
    for (Eigen::Index a = 0; a < m; ++a) {
      for (Eigen::Index b = 0; b < m; ++b) {
        bread(a, b) = information(index[a], index[b]);
        score(a, b) = meat(index[a], index[b]);
      }
      const int i = free[a] % kDirectionParameters;
      const double value = (*blocks[free[a] / kDirectionParameters])[i];
      const double slope = i == 3 ? 1.0 / (value * sigma[i]) : 1.0 / sigma[i];  // vs: ln scale
      bread(a, a) += slope * slope;
      score(a, a) += slope * slope;
    }
    const Eigen::MatrixXd inverse = bread.inverse();
    covariance = inverse * score * inverse;
    // What the logs determine (determination.h); vs means something only
    // through the Stribeck drop Fs - Fd, so it goes with an undetermined Fs.
    bool held_any = false;
    for (Eigen::Index a = 0; a < m; ++a) {
      const int c = free[a], i = c % kDirectionParameters;
      const double value = (*blocks[c / kDirectionParameters])[i];
      const double error = std::sqrt(std::max(covariance(a, a), 0.0));
      if (internal::IsDetermined(value, error, kDeterminedFloor[i],
                                 options.identifiable_relative_error)) {
        continue;
      }
      char why[200];
      std::snprintf(why, sizeof(why), "not determined by these logs (%.4g +- %.2g); %s", value,
                    error,
                    options.held_at_prior ? "held at the prior" : "regularised toward the prior");
      held[c] = why;
      held_any = true;
    }
    for (int d = 0; d < 2; ++d) {
      const int fs = d * kDirectionParameters, vs = fs + 3;
      if (!held[fs].empty() && held[vs].empty() && held[fs] != "no slide this way") {
        held[vs] = std::string(
                       "not determined by these logs: Fs, which sets the Stribeck drop, "
                       "is not; ") +
                   (options.held_at_prior ? "held at the prior" : "regularised toward the prior");
        held_any = true;
      }
    }
    if (!held_any) break;
    for (int c = 0; c < 2 * kDirectionParameters; ++c) {
      if (!held[c].empty() && options.held_at_prior) {
        (*blocks[c / kDirectionParameters])[c % kDirectionParameters] =
            prior_blocks[c / kDirectionParameters][c % kDirectionParameters];
      }
    }
    std::vector<int> still;  // the columns the logs determine
    for (int c : free) {
      if (held[c].empty()) still.push_back(c);
    }
    Eigen::MatrixXd kept(still.size(), still.size());
    for (std::size_t a = 0; a < still.size(); ++a) {
      for (std::size_t b = 0; b < still.size(); ++b) {
        kept(a, b) = covariance(std::find(free.begin(), free.end(), still[a]) - free.begin(),
                                std::find(free.begin(), free.end(), still[b]) - free.begin());
      }
    }
    free = still;
    covariance = kept;
  }
  result.segments = static_cast<int>(data.segments.size());
  double squares = 0;
  for (std::size_t k = 0; k < data.segments.size(); ++k) {
    const Eigen::VectorXd& r = jacobians[k].residuals;
    result.samples += static_cast<int>(r.size());
    for (Eigen::Index i = 0; i < r.size(); ++i) {
      squares += std::pow(r(i) / data.segments[k].weight[i + 1], 2);
    }
  }
  result.position_rms_m = std::sqrt(squares / std::max(result.samples, 1));
  result.fitted = true;
  for (int d = 0; d < 2; ++d) {
    DirectionFit& fit = d == 0 ? result.positive : result.negative;
    fit.params = Unpack(*blocks[d]);
    for (int i = 0; i < kDirectionParameters; ++i) {
      const int c = d * kDirectionParameters + i;
      if (!held[c].empty()) {
        fit.held[kParameterNames[i]] = held[c];
        continue;
      }
      const auto at = std::find(free.begin(), free.end(), c) - free.begin();
      fit.standard_errors[kParameterNames[i]] = std::sqrt(std::max(covariance(at, at), 0.0));
    }
    fit.fitted = !fit.standard_errors.empty();
  }
  for (std::size_t a = 0; a < free.size(); ++a) {
    for (std::size_t b = a + 1; b < free.size(); ++b) {
      result.correlations[ColumnName(free[a]) + "," + ColumnName(free[b])] =
          covariance(a, b) / std::sqrt(covariance(a, a) * covariance(b, b));
    }
  }
  if (!data.skipped.empty()) result.note = "not used: " + data.skipped;
  return result;
}

std::string FrictionFitResult::BriefReport() const {
  std::ostringstream out;
  out << "Friction fit: ";
  if (!fitted) {
    out << "not fitted (" << note << ")\n";
    return out.str();
  }
  char line[320];
  std::snprintf(line, sizeof(line),
                "%d segments (%d samples, %d near the stroke ends left out, %d outliers), %d "
                "force-balance samples, cost %.4g -> %.4g in %d iterations, position RMS %.3g mm\n",
                segments, samples, excluded_segments, outlier_segments, smooth_samples,
                initial_cost, final_cost, iterations, position_rms_m * 1e3);
  out << line;
  const char* const units[] = {"N", "N", "N s/m", "m/s"};
  for (const auto& [name, fit] :
       {std::make_pair("positive", &positive), std::make_pair("negative", &negative)}) {
    std::snprintf(line, sizeof(line), "  %s: %d slides replayed, %d smooth slides;", name,
                  fit->segments, fit->smooth_slides);
    out << line;
    const double values[] = {fit->params.static_force_N, fit->params.dynamic_force_N,
                             fit->params.viscous_N_s_per_m, fit->params.stribeck_velocity_m_per_s};
    for (int i = 0; i < kDirectionParameters; ++i) {
      const auto error = fit->standard_errors.find(kParameterNames[i]);
      if (error == fit->standard_errors.end()) {
        std::snprintf(line, sizeof(line), " %s %.4g %s (held)", kParameterNames[i], values[i],
                      units[i]);
      } else {
        std::snprintf(line, sizeof(line), " %s %.4g +- %.2g %s", kParameterNames[i], values[i],
                      error->second, units[i]);
      }
      out << line << (i + 1 < kDirectionParameters ? "," : "\n");
    }
    for (const auto& [coefficient, why] : fit->held) {
      if (why != "no slide this way" || coefficient == "Fs")
        out << "    held " << coefficient << ": " << why << "\n";
    }
  }
  for (const auto& [pair, r] : correlations) {
    if (std::fabs(r) > 0.95) out << "  poorly separable: " << pair << " correlation " << r << "\n";
  }
  if (!note.empty()) out << "  " << note << "\n";
  return out.str();
}

}  // namespace pneumaid
