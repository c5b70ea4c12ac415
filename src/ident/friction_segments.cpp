#include "friction_segments.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <tuple>

#include "meter_lag.h"
#include "pneumaid/io/channel_noise.h"
#include "pneumaid/io/log_notes.h"
#include "pneumaid/model/load.h"
#include "pneumaid/validate/logged_run.h"
#include "uniform_clock.h"

namespace pneumaid::friction_internal {

RodReplayInput ReplayOf(const Segment& s, double mass_kg, const FrictionFitOptions& options) {
  RodReplayInput replay;
  replay.force_N = s.force_N->data() + s.begin;
  replay.samples = s.end - s.begin;
  replay.period_s = s.period_s;
  if (s.time_s != nullptr) replay.time_s = s.time_s->data() + s.begin;
  replay.mass_kg = mass_kg;
  replay.initial_position_m = s.initial_position_m;
  // The 1e-9 keeps an interval of exactly k steps from rounding up to k + 1.
  const double steps = std::ceil(s.period_s / options.replay_step_s - 1e-9);
  replay.substeps = static_cast<int>(std::clamp(steps, 1.0, double(options.max_substeps)));
  if (s.time_s != nullptr) {  // each logged interval in steps of at most replay_step_s
    replay.step_s = options.replay_step_s;
    replay.max_substeps = options.max_substeps;
  }
  return replay;
}

namespace {

// Residual weights of `s`: a sample n intervals from the last known state
// (the breakaway forward, the arrest backward) carries the position noise, a
// drift of variance (sigma_F h^2 / M)^2 n^3 / 3 from the force's noise and,
// replayed forward, the breakaway's velocity error times n h.
void SetWeights(double sigma_x_m, double drift_m, double escape_error_m_per_s, Segment* s) {
  s->weight.assign(s->end - s->begin, 1.0 / sigma_x_m);
  for (std::size_t i = s->begin; i < s->end; ++i) {
    const bool backward = s->two_sided && i > s->split;
    double n = i > s->slide_begin ? static_cast<double>(i - s->slide_begin) : 0.0;
    if (backward) n = s->arrest > i ? static_cast<double>(s->arrest - i) : 0.0;
    double escape_m = backward ? 0.0 : escape_error_m_per_s * n * s->period_s;
    if (!backward && s->time_s != nullptr && i > s->slide_begin)  // the time since, as logged
      escape_m = escape_error_m_per_s * ((*s->time_s)[i] - (*s->time_s)[s->slide_begin]);
    const double variance =
        sigma_x_m * sigma_x_m + drift_m * drift_m * n * n * n / 3.0 + escape_m * escape_m;
    s->weight[i - s->begin] = 1.0 / std::sqrt(variance);
  }
}

// A replay that ran through a gap in the log ran on the forces interpolated
// across it: the samples in the gap and every sample its replay reaches after
// it (forward: later, backward from the arrest: earlier) weigh nothing.
// (Twelve gaps of 21 rows, four per stroke log, once left a fit not
// converged at 2.7 times its cost, its position RMS 0.10 mm for 0.009.)
void LeaveOutWhatFollowsAGap(const std::vector<bool>& in_gap, Segment* s) {
  const std::size_t forward_end = s->two_sided ? s->split + 1 : s->end;
  bool after_gap = false;
  for (std::size_t i = s->begin; i < forward_end; ++i) {
    after_gap = after_gap || in_gap[i];
    if (after_gap) s->weight[i - s->begin] = 0;
  }
  after_gap = false;
  for (std::size_t i = s->end; i-- > forward_end;) {
    after_gap = after_gap || in_gap[i];
    if (after_gap) s->weight[i - s->begin] = 0;
  }
}

// The time from the first sample of `s` to sample `whole` + `fraction` (in
// [-1, 1]) of its log, the interval there taken as linear.
double SinceBegin(const Segment& s, std::size_t whole, double fraction) {
  if (s.time_s == nullptr) return (static_cast<double>(whole - s.begin) + fraction) * s.period_s;
  const std::vector<double>& t = *s.time_s;
  const double interval = fraction >= 0 ? t[std::min(whole + 1, t.size() - 1)] - t[whole]
                                        : t[whole] - t[whole > 0 ? whole - 1 : 0];
  return t[whole] + fraction * interval - t[s.begin];
}

// The slide of `s` ends in the stuck run `next`: where it stopped, when
// (a guess and bounds for the nuisance parameter), and its fastest sample.
// A slide that turned back before it stopped (beyond `band`) arrives in the
// other direction, which a backward replay in the slide's direction cannot
// follow: it stays one-sided, replayed forward through its reversal.
void MarkArrest(const std::vector<double>& x, std::size_t slide_begin, internal::Run next,
                double band, Segment* s) {
  const auto [arrest, next_end] = next;
  double farthest = s->direction * x[arrest];
  for (std::size_t j = slide_begin; j < arrest; ++j)
    farthest = std::max(farthest, s->direction * x[j]);
  if (farthest - s->direction * x[arrest] > band) return;
  // The step of most speed: by index on a uniform clock, per logged interval
  // otherwise (a longer interval is no faster step).
  const auto step = [&](std::size_t j) {
    const double moved = std::fabs(x[j + 1] - x[j]);
    return s->time_s == nullptr ? moved : moved / ((*s->time_s)[j + 1] - (*s->time_s)[j]);
  };
  std::size_t split = slide_begin - 1;
  for (std::size_t j = slide_begin - 1; j + 1 < arrest; ++j) {
    if (step(j) > step(split)) split = j;
  }
  if (split + 2 >= s->end || split < s->begin + 1) return;
  const std::size_t settled_end = std::min(next_end, arrest + 21);
  s->stop_position_m = std::accumulate(x.begin() + arrest + 1, x.begin() + settled_end, 0.0) /
                       static_cast<double>(settled_end - arrest - 1);
  s->split = split;
  s->stop_time_min_s = SinceBegin(*s, split, 0.05);
  s->stop_time_max_s = SinceBegin(*s, s->end - 1, 0.0);
  s->stop_time_guess_s =
      std::clamp(SinceBegin(*s, arrest, -0.5), s->stop_time_min_s, s->stop_time_max_s);
  s->two_sided = settled_end > arrest + 1;
  s->arrest = arrest;
}

}  // namespace

namespace {

// Where the rod may touch an end stop: within `contact_m` of either end.
// +1 at the extended end, -1 at the retracted one, 0 elsewhere.
int EndContact(double x, double half_stroke_m, double contact_m) {
  if (x > half_stroke_m - contact_m) return +1;
  if (x < -half_stroke_m + contact_m) return -1;
  return 0;
}

// The velocity error a forward replay carries from its breakaway on
// (FrictionFitOptions::breakaway_timing_per_s): a timing error tau leaves the
// velocity wrong by the rod's acceleration after breakaway times tau, read
// off the log over the first 4 ms of the slide (at least 2 samples).
double EscapeVelocityError(const std::vector<double>& x, const std::vector<double>* time_s,
                           std::size_t at, std::size_t end, double period_s, double timing_per_s) {
  if (!(timing_per_s > 0) || at + 2 >= end) return 0.0;
  const std::size_t samples =
      std::max<std::size_t>(2, static_cast<std::size_t>(std::lround(0.004 / period_s)));
  const std::size_t j = std::min(at + samples, end - 1);
  const double t =
      time_s == nullptr ? static_cast<double>(j - at) * period_s : (*time_s)[j] - (*time_s)[at];
  const double acceleration = 2.0 * std::fabs(x[j] - x[at]) / (t * t);
  return acceleration * timing_per_s * period_s * period_s;
}

// One stroke log as CutSegments reads it.
struct StrokeLog {
  const std::vector<double>& force_N;  // smoothed where stuck (SmoothStuckForce)
  const std::vector<double>& x;
  double period_s;                    // the median interval when irregular
  const std::vector<double>* time_s;  // the sample times when irregular, else null
  internal::StuckRule stuck;  // its noise: internal::PositionNoise, times the lag inverse's gain
  double half_stroke_m;       // the stroke ends at +-half_stroke_m
  double contact_m;           // within this of an end the rod may touch the stop
  double drift_m;             // the force noise's drift per sample^2 (SetWeights)
};

// A rod stuck at an end may rest on the stop, whose force is not friction:
// its segment starts once the force points away from the stop, and only a
// slide that leaves the stop is replayed, over its first end_slide_m (the
// chamber at the stop is near its dead volume, and its pressure falls faster
// than a replay between samples follows). Records the run's breakaway and
// departure from the stop either way; false when no segment starts here.
bool StartAtStop(const StrokeLog& log, const Runs& runs, std::size_t k, int contact,
                 const std::array<bool, 2>& from_stops, Segment* s, StrokeData* data) {
  const std::size_t stuck_end = runs[k].second;
  // Which way the rod first moves beyond the band (a heavy rod moves off
  // slowly), before it sticks again.
  const std::size_t next_stuck = k + 1 < runs.size() ? runs[k + 1].first : log.x.size();
  int leaving = 0;
  for (std::size_t i = stuck_end; i < next_stuck && leaving == 0; ++i) {
    const double travel = log.x[i] - log.x[stuck_end - 1];
    if (std::fabs(travel) > log.stuck.band_m) leaving = travel > 0 ? +1 : -1;
  }
  if (leaving != 0) {
    data->end_breakaway_N[leaving > 0 ? 0 : 1].push_back(
        leaving * log.force_N[internal::BreakawaySample(log.x, runs[k], log.stuck)]);
  }
  if (leaving == -contact) ++data->stop_departures[leaving > 0 ? 0 : 1];
  std::size_t free_from = s->begin;  // after the last sample pushing into the stop
  for (std::size_t i = s->begin; i < stuck_end; ++i) {
    if (contact * log.force_N[i] >= 0) free_from = i + 1;
  }
  if (leaving != -contact || !from_stops[leaving > 0 ? 0 : 1] || free_from + 2 > stuck_end)
    return false;
  s->begin = free_from;
  return true;
}

// Where the replay of the slide from `stuck_end` ends: a few samples into the
// next stuck run, or cut (true) after max_slide_s (a replay over a long slide
// integrates any bias of the force twice: the rest of such a slide is left
// to the force balance, friction_slides.h), where the rod may touch a stop
// (end-stop forces are not friction), or, from a stop (`contact`), once it
// is end_slide_m away.
std::pair<std::size_t, bool> EndOfSlide(const StrokeLog& log, const Runs& runs, std::size_t k,
                                        int contact, std::size_t min_slide,
                                        const FrictionFitOptions& options, const Segment& s) {
  const std::size_t stuck_end = runs[k].second;
  std::size_t end =
      k + 1 < runs.size()
          ? runs[k + 1].first + std::min<std::size_t>(options.arrest_samples,
                                                      runs[k + 1].second - runs[k + 1].first)
          : stuck_end;
  const std::size_t max_slide = std::max<std::size_t>(
      options.min_stuck_samples, static_cast<std::size_t>(options.max_slide_s / log.period_s));
  bool cut = false;
  if (end > stuck_end + max_slide) {
    end = stuck_end + max_slide;
    cut = true;
  }
  bool left_stop = false;  // a slide from a stop has left its contact zone
  for (std::size_t i = stuck_end; i < end; ++i) {
    const int touches = EndContact(log.x[i], log.half_stroke_m, log.contact_m);
    const bool far_from_stop = contact != 0 && i >= stuck_end + min_slide &&
                               std::fabs(log.x[i] - s.initial_position_m) > options.end_slide_m;
    if ((touches != 0 && (touches != contact || left_stop)) || far_from_stop) return {i, true};
    left_stop = left_stop || touches == 0;
  }
  return {end, cut};
}

// The replay segments of one log: each stuck run starts one (its last
// max_stuck_samples at most) that runs through the following slide into the
// next stuck run (EndOfSlide); runs at a stop as StartAtStop says.
void CutSegments(const StrokeLog& log, const Runs& runs, const FrictionFitOptions& options,
                 const std::array<bool, 2>& from_stops, StrokeData* data) {
  const std::vector<double>& x = log.x;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const auto [stuck_begin, stuck_end] = runs[k];
    Segment s{};
    s.force_N = &log.force_N;
    s.position_m = &x;
    s.period_s = log.period_s;
    s.time_s = log.time_s;
    s.begin = std::max(stuck_begin + 1,
                       stuck_end - std::min<std::size_t>(stuck_end, options.max_stuck_samples));
    const int contact = EndContact(x[stuck_end - 1], log.half_stroke_m, log.contact_m);
    if (contact != 0 && !StartAtStop(log, runs, k, contact, from_stops, &s, data)) {
      ++data->excluded;
      continue;
    }
    // The run's last sample may already be the first of the slide.
    const std::size_t settled_end = std::max(s.begin + 1, stuck_end - 1);
    s.initial_position_m = std::accumulate(x.begin() + s.begin, x.begin() + settled_end, 0.0) /
                           static_cast<double>(settled_end - s.begin);
    // A slide from a stop keeps at least two samples after its breakaway.
    const std::size_t min_slide = contact != 0 ? 2 : options.min_stuck_samples;
    bool cut = false;
    std::tie(s.end, cut) = EndOfSlide(log, runs, k, contact, min_slide, options, s);
    if (s.end < stuck_end + min_slide) {
      ++data->excluded;
      continue;
    }
    // A slide from a stop goes the way the rod was seen leaving it, also when
    // its first end_slide_m stay inside the band.
    const double travel = x[s.end - 1] - s.initial_position_m;
    s.direction = contact != 0                ? -contact
                  : travel > log.stuck.band_m ? +1
                                              : (travel < -log.stuck.band_m ? -1 : 0);
    s.slide_begin = stuck_end - 1;
    double escape_error_m_per_s = 0;
    if (s.direction != 0) {
      const std::size_t at = internal::BreakawaySample(x, runs[k], log.stuck);
      s.breakaway_force_N = s.direction * log.force_N[at];
      escape_error_m_per_s = EscapeVelocityError(x, log.time_s, at, s.end, log.period_s,
                                                 options.breakaway_timing_per_s);
    }
    if (s.direction != 0 && k + 1 < runs.size() && !cut)
      MarkArrest(x, stuck_end, runs[k + 1], log.stuck.band_m, &s);
    SetWeights(log.stuck.sigma_x_m, log.drift_m, escape_error_m_per_s, &s);
    data->segments.push_back(s);
  }
}

}  // namespace

StrokeData PrepareStrokes(const Unit& unit, const FrictionFitOptions& options,
                          const StrokeSelection& selection, const std::array<bool, 2>& from_stops) {
  const RigConstants& rig = unit.manifest.rig;
  // A reading's noise per sample at a log's sampling interval: grown by the
  // inverse of its declared lag (PlanLagInverse). A drift over a slide is the
  // reading's: the inverse passes a constant as it is, and its sum over many
  // samples keeps the reading's noise.
  const auto gain = [&](const char* column, double period_s) {
    return internal::PlanLagInverse(period_s, unit.manifest.DeclaredTau(column, 0.0)).noise_gain;
  };
  const double reading_sigma_x_m = internal::PositionNoise(unit);
  // A transducer's zero that the rests at the stops show: x is read less it,
  // as the refinement and validation read it, so that the stops, the end
  // zones and the replays from a stop are where the rod was.
  const double zero_m = ReadPositionZero(unit).offset_m;
  const double p1_sigma_N = NoiseSigma(unit, "p1") * rig.area_1_m2();
  const double p2_sigma_N = NoiseSigma(unit, "p2") * rig.area_2_m2();
  const double reading_sigma_N = std::hypot(p1_sigma_N, p2_sigma_N);
  const double weight_N =
      rig.orientation == Orientation::kVertical ? rig.load_mass_kg * kStandardGravity_m_per_s2 : 0;
  const auto selected = [&selection](const Experiment& e) {
    if (selection.runs.empty()) return e.entry.kind == ExperimentKind::kStroke;
    return std::find(selection.runs.begin(), selection.runs.end(), e.entry.id) !=
               selection.runs.end() &&
           !e.column("x").empty() && !e.column("p1").empty() && !e.column("p2").empty();
  };
  const std::array<bool, 2> replay_stops = {options.end_slide_m > 0 && from_stops[0],
                                            options.end_slide_m > 0 && from_stops[1]};
  StrokeData data;
  std::size_t count = 0;
  for (const Experiment& e : unit.experiments) count += selected(e);
  // Segments point into these vectors: reserve so that they never move.
  data.force_N.reserve(count);
  data.position_m.reserve(count);
  data.time_s.reserve(count);
  for (const Experiment& logged : unit.experiments) {
    if (!selected(logged)) continue;
    const Experiment* log = &logged;
    double period = UniformPeriod(logged.column("t"));
    bool irregular = false;  // replayed from sample to sample at the logged times
    // Samples interpolated across rows the logger lost (a uniform clock), or
    // either end of a gap (irregular).
    std::vector<bool> in_gap;
    if (period <= 0 && IrregularClock(logged.column("t"))) {
      period = MedianInterval(logged.column("t"));
      irregular = true;
      for (std::size_t j : SamplingGaps(logged.column("t"))) {
        in_gap.resize(logged.column("t").size(), false);
        in_gap[j] = in_gap[j + 1] = true;
      }
    } else if (period <= 0) {  // read on a uniform clock instead
      data.resampled.push_back(internal::ResampledUniformly(logged, &in_gap));
      log = data.resampled.back().get();
      period = UniformPeriod(log->column("t"));
    }
    if (period <= 0) {
      data.skipped += logged.entry.id + " (too few samples) ";
      continue;
    }
    // A lag the manifest declares for a reading the replays read: undone.
    if (auto undone = internal::WithLagsUndone(*log, unit.manifest, {"x", "p1", "p2"})) {
      data.resampled.push_back(std::move(undone));
      log = data.resampled.back().get();
    }
    const Experiment& e = *log;
    const double sigma_x_m = reading_sigma_x_m * gain("x", period);
    std::vector<double> x = e.column("x");
    const internal::StuckRule stuck =
        internal::StuckRuleOf(options, sigma_x_m, internal::PositionQuantum(x), period);
    const auto &p1 = e.column("p1"), &p2 = e.column("p2");
    std::vector<double> force(p1.size());
    for (std::size_t i = 0; i < force.size(); ++i) {
      force[i] = PneumaticAndGravityForce(p1[i], p2[i], rig.atmospheric_pressure_Pa,
                                          rig.area_1_m2(), rig.area_2_m2(), weight_N);
    }
    for (double& value : x) value -= zero_m;
    const Runs runs = internal::StuckRuns(x, stuck);
    const double force_sigma_N = std::max(
        std::hypot(p1_sigma_N * gain("p1", period), p2_sigma_N * gain("p2", period)), 1e-3);
    data.time_s.push_back(irregular ? e.column("t") : std::vector<double>{});
    const std::vector<double>* time_s = irregular ? &data.time_s.back() : nullptr;
    internal::SmoothStuckForce(runs, options.stuck_force_samples, force_sigma_N, data.time_s.back(),
                               &force);
    data.force_N.push_back(std::move(force));
    data.position_m.push_back(x);
    data.experiments.push_back(&e);
    const double drift_m = reading_sigma_N * period * period / rig.load_mass_kg;
    const std::size_t first_segment = data.segments.size();
    const StrokeLog stroke_log{data.force_N.back(),
                               data.position_m.back(),
                               period,
                               time_s,
                               stuck,
                               0.5 * rig.stroke_m,
                               options.end_margin_m + 4 * sigma_x_m,
                               drift_m};
    CutSegments(stroke_log, runs, options, replay_stops, &data);
    for (std::size_t k = first_segment; k < data.segments.size() && !in_gap.empty(); ++k)
      LeaveOutWhatFollowsAGap(in_gap, &data.segments[k]);
    if (!options.force_balance) continue;
    // Nor is a smooth slide read off the line drawn across a gap (or,
    // irregular, a window across one).
    std::vector<bool> covered = in_gap.empty() ? std::vector<bool>(x.size(), false) : in_gap;
    for (const auto& [begin, end] : runs)
      std::fill(covered.begin() + begin, covered.begin() + end, true);
    for (std::size_t k = first_segment;
         k < data.segments.size() && !selection.slides_under_segments; ++k) {
      const Segment& segment = data.segments[k];
      std::fill(covered.begin() + segment.begin, covered.begin() + segment.end, true);
    }
    internal::SlideSampling sampling;
    sampling.period_s = period;
    sampling.time_s = time_s;
    sampling.mass_kg = rig.load_mass_kg;
    sampling.sigma_x_m = sigma_x_m;
    sampling.sigma_force_N = force_sigma_N;
    sampling.half_stroke_m = 0.5 * rig.stroke_m;
    sampling.end_zone_m = options.end_margin_m + 4 * sigma_x_m;
    sampling.window_s = options.smoothing_window_s;
    for (auto& cluster :
         internal::SlidingSamples(data.position_m.back(), data.force_N.back(), covered, sampling)) {
      cluster.log = static_cast<int>(data.experiments.size()) - 1;
      data.clusters.push_back(std::move(cluster));
    }
  }
  return data;
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

}  // namespace pneumaid::friction_internal

namespace pneumaid {

std::vector<FrictionMapSample> FrictionVelocityMap(const Unit& unit,
                                                   const FrictionFitOptions& options) {
  using namespace friction_internal;
  FrictionFitOptions with_slides = options;
  with_slides.force_balance = true;
  StrokeSelection every_slide;
  every_slide.slides_under_segments = true;
  const StrokeData data = PrepareStrokes(unit, with_slides, every_slide);
  std::vector<FrictionMapSample> map;
  for (const internal::SlideCluster& c : data.clusters) {
    for (std::size_t i = 0; i < c.speed_m_per_s.size(); ++i)
      map.push_back({c.direction, c.speed_m_per_s[i], c.friction_N[i]});
  }
  return map;
}

}  // namespace pneumaid
