// The friction fit (friction_fit.h), its data: the stroke logs cut into
// stuck-to-arrest segments for the rod replay (stuck phases that move like a
// rod at rest, slides cut where they reach an end zone or run long), and the
// smooth slides no segment covers for the force balance (friction_slides.h).
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "friction_slides.h"
#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/ident/rod_replay.h"
#include "pneumaid/io/rig_data.h"
#include "stuck_phases.h"

namespace pneumaid::friction_internal {

constexpr int kDirectionParameters = 4;  // Fs, Fd, b, vs
// params-v1 names (friction.<direction>.<name>).
inline const char* const kParameterNames[kDirectionParameters] = {"Fs", "Fd", "b", "vs"};
// Lower bounds: forces and damping are magnitudes; vs > 0 keeps Eq. 12 defined.
inline const double kLowerBounds[kDirectionParameters] = {0.0, 0.0, 0.0, 1e-4};
// Upper bounds: configs/fit-default.yaml's, so that refinement can start
// from whatever the fit gives (a vs of 1.9 m/s once came out of a unit whose
// slides never slowed down).
inline const double kUpperBounds[kDirectionParameters] = {200.0, 200.0, 1000.0, 1.0};
// Standard errors below these count as determined whatever the value (the
// identification's tolerances: 0.1 N, 0.5 N s/m, 1 mm/s).
inline const double kDeterminedFloor[kDirectionParameters] = {0.1, 0.1, 0.5, 1e-3};

using Block = std::array<double, kDirectionParameters>;

inline Block Pack(const StribeckParams& p) {
  return {p.static_force_N, p.dynamic_force_N, p.viscous_N_s_per_m, p.stribeck_velocity_m_per_s};
}

inline StribeckParams Unpack(const Block& b) { return {b[0], b[1], b[2], b[3]}; }

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
  double period_s;         // of its log (the median interval when irregular)
  // The times of its log's samples when they are irregular (else null): the
  // replays step from sample to sample as logged.
  const std::vector<double>* time_s = nullptr;
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
  // The force magnitude at the slide's breakaway (the last sample at rest).
  double breakaway_force_N = 0;
  // 1 / (expected residual std) per sample of the segment: the position
  // noise, the drift that the force's noise integrated twice adds with the
  // distance from the nearest exactly known state (stuck, v = 0), and in a
  // forward replay the velocity error of the breakaway's timing times the
  // time since (FrictionFitOptions::breakaway_timing_per_s).
  std::vector<double> weight;
};

using Runs = internal::Runs;

// Everything the Ceres problem reads: per stroke log its driving force and
// position, and the segments cut from them.
struct StrokeData {
  std::vector<std::vector<double>> force_N, position_m;
  // Per log its sample times when irregular (IrregularClock), else empty.
  std::vector<std::vector<double>> time_s;
  std::vector<const Experiment*> experiments;  // the log of each
  // Logs read otherwise than written: a uniform clock that lost rows on that
  // clock (ResampledUniformly), with the declared lags of x, p1 and p2 undone
  // (WithLagsUndone).
  std::vector<std::shared_ptr<const Experiment>> resampled;
  std::vector<Segment> segments;
  std::vector<internal::SlideCluster> clusters;  // smooth slides no segment covers
  // Breakaway forces (magnitudes) of stuck phases at the stroke ends,
  // positive direction first.
  std::vector<double> end_breakaway_N[2];
  // Slides that leave a stop, replayed or not (positive direction first).
  int stop_departures[2] = {0, 0};
  int excluded = 0;
  std::string skipped;  // logs that could not be used, why
};

// Which logs PrepareStrokes reads, and what its force balance leaves out.
struct StrokeSelection {
  // Experiment ids (any kind that logs x, p1 and p2); empty: the stroke logs.
  std::vector<std::string> runs;
  // Every smooth slide enters the force balance, also where a replay segment
  // covers it (the friction-velocity map; no fit replays those segments).
  bool slides_under_segments = false;
};

// Per log its driving force and position, the replay segments cut from them
// and the force-balance slides no segment covers (`SlideCluster::log` indexes
// `experiments`). Declared lags of x, p1 and p2 are undone (meter_lag.h); the
// position noise (internal::PositionNoise, grown by the lag inverse's gain at
// the log's interval) sets each log's StuckRule, end zones and replay weights.
// Slides that leave an end stop are replayed in the directions `from_stops`
// names (positive first; FrictionFitOptions::end_slide_m > 0).
StrokeData PrepareStrokes(const Unit& unit, const FrictionFitOptions& options,
                          const StrokeSelection& selection = {},
                          const std::array<bool, 2>& from_stops = {false, false});

// Replayed segments and force-balance slides of one direction.
int SegmentsOf(const StrokeData& data, int direction);

int ClustersOf(const StrokeData& data, int direction);

// The replay of a segment, in RK4 steps as FrictionFitOptions::replay_step_s
// and max_substeps say.
RodReplayInput ReplayOf(const Segment& s, double mass_kg, const FrictionFitOptions& options);

// Force-balance samples a direction needs before its slides say anything.
constexpr std::size_t kMinSlideSamples = 20;

}  // namespace pneumaid::friction_internal
