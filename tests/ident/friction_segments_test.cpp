// How the friction fit cuts stroke logs into replay segments
// (src/ident/friction_segments.h): where a slide breaks away, which slides
// are replayed from their arrest, and the weights of a forward replay. On
// logs the fitted model did not make (smooth stick, tight tolerances).
#include "../../src/ident/friction_segments.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "../../src/ident/friction_starts.h"
#include "../synth/synth_test_util.h"
#include "friction_test_util.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid {
namespace {

using friction_internal::PrepareStrokes;
using friction_internal::ReadOffLogs;
using friction_internal::Segment;
using friction_internal::StrokeData;

// A horizontal rod at 2 kHz whose positive slides overshoot and turn back
// before they stop (a strong drop, Fs 15 N to Fd 3 N, little viscous
// friction), logged as the synthetic rig writes it with smooth stick.
Unit TurningStrokes(double rate_Hz, double mass_kg) {
  Parameters truth =
      LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper-horizontal.yaml");
  truth.cylinder.load_mass_kg = mass_kg;
  truth.friction.positive = {15.1, 3.0, 1.4, 0.0027};
  truth.friction.negative = {3.5, 0.87, 12.4, 0.0034};
  for (KvpBranchParams* branch : {&truth.valve.increasing, &truth.valve.decreasing}) {
    branch->q_max_kg_per_s *= 0.952;
    branch->u_sat_V = 0.80;
  }
  truth.pipeline.delta_per_s = 4.8;
  Protocol protocol = testing::StrokeProtocol(2);
  protocol.sample_rate_Hz = rate_Hz;
  protocol.stroke_levels_V = {0.61, 0.36, 0.9};
  protocol.stroke_margin_m = 0.001;
  protocol.mismatch.relative_tolerance = 1e-8;
  return testing::WriteAndReadUnit(Synthesize(truth, protocol, 4, "S"),
                                   "friction_segments_" + std::to_string(int(rate_Hz)));
}

// The paper's vertical cylinder with `mass_kg` and this friction.
Parameters VerticalTruth(double mass_kg, const StribeckParams& positive,
                         const StribeckParams& negative) {
  Parameters truth;  // vertical
  truth.cylinder.load_mass_kg = mass_kg;
  truth.friction.positive = positive;
  truth.friction.negative = negative;
  return truth;
}

// `cycles` of strokes at `levels`, logged at `rate_Hz`, `margin_m` short of the stops.
Protocol Strokes(int cycles, double rate_Hz, std::vector<double> levels, double margin_m) {
  Protocol protocol = testing::StrokeProtocol(cycles);
  protocol.sample_rate_Hz = rate_Hz;
  protocol.stroke_levels_V = std::move(levels);
  protocol.stroke_margin_m = margin_m;
  return protocol;
}

// A unit's stroke logs and their cuts (which point into the unit: moved,
// never copied).
struct CutLogs {
  CutLogs(Unit u, StrokeData d) : unit(std::move(u)), data(std::move(d)) {}
  CutLogs(const CutLogs&) = delete;
  CutLogs& operator=(const CutLogs&) = delete;
  CutLogs(CutLogs&&) = default;
  Unit unit;
  StrokeData data;
};

// `protocol`'s strokes of `truth` as a rig with smooth stick (creep below
// 0.1 mm/s) integrated at rtol 1e-8 writes them (seed 3, experiment tag
// `tag`), cut as the friction fit cuts them.
CutLogs SmoothStickStrokes(const Parameters& truth, Protocol protocol, const char* tag) {
  protocol.mismatch.regularized_friction = true;
  protocol.mismatch.stick_velocity_m_per_s = 1e-4;
  protocol.mismatch.relative_tolerance = 1e-8;
  CutLogs logs{testing::WriteAndReadUnit(Synthesize(truth, protocol, 3, tag),
                                         std::string("friction_segments_") + tag),
               {}};
  logs.data = PrepareStrokes(logs.unit, FrictionFitOptions{});
  return logs;
}

// A slide replayed backward from its arrest must arrive there in its own
// direction; one that turned back on the way is replayed forward only.
TEST(FrictionSegmentsTest, ASlideThatTurnsBackBeforeItStopsIsReplayedForwardOnly) {
  const Unit unit = TurningStrokes(2000, 0.44);
  const FrictionFitOptions options;
  const StrokeData data = PrepareStrokes(unit, options);
  const double band =
      internal::StuckRuleOf(options, internal::PositionNoise(unit), 0, 1 / 2000.0).band_m;
  int turning = 0, two_sided = 0;
  for (const Segment& s : data.segments) {
    if (s.direction == 0) continue;
    // Where the segment ends (in the next stuck phase, or cut) against the
    // farthest the slide went.
    const std::vector<double>& x = *s.position_m;
    double farthest = s.direction * x[s.end - 1];
    for (std::size_t j = s.slide_begin; j < s.end; ++j)
      farthest = std::max(farthest, s.direction * x[j]);
    const bool turned = farthest - s.direction * x[s.end - 1] > band;
    turning += turned;
    two_sided += s.two_sided;
    EXPECT_FALSE(turned && s.two_sided) << "segment at sample " << s.begin;
  }
  // The logs hold both kinds.
  EXPECT_GT(turning, 3);
  EXPECT_GT(two_sided, 3);
}

// The start of Fs is the force where the rod leaves its rest. Read a quarter
// of the way along a slide, as before, it was the force after a long slide
// had begun to empty the driving chamber (a heavy vertical rod at 500 Hz:
// -3.8 N for 19.9 N).
TEST(FrictionSegmentsTest, TheBreakawayIsReadWhereTheRodLeavesItsRest) {
  const CutLogs logs =
      SmoothStickStrokes(VerticalTruth(1.15, {19.9, 1.12, 12.2, 0.0045}, {10.7, 0.67, 7.3, 0.0022}),
                         Strokes(2, 500, {0.5, 0.7, 0.9}, 0.005), "B");
  // Within 15 % (the rod escapes while the force still rises, for a sample
  // or two at 500 Hz: 12.2 N for 10.7).
  EXPECT_NEAR(ReadOffLogs(logs.data, +1, {}).value[0], 19.9, 0.15 * 19.9);
  EXPECT_NEAR(ReadOffLogs(logs.data, -1, {}).value[0], 10.7, 0.15 * 10.7);
}

// A light vertical rod (0.11 kg) logged at 250 Hz from stop to stop: leaving
// the bottom stop, the chamber at its dead volume fills within two samples
// (the force from -1 to 10 N) and the rod breaks away between them. The
// stuck force's smoothing (a quadratic over the run's last samples) cut that
// rise short: the breakaways read 3.3 N for 15.6, and the replays from the
// stop broke away there (robustness sweep, seed 77, unit 01: positive Fs
// 0.97 +- 0.49 N, negative 7.8 N for 3.4). A run whose force the quadratic
// does not follow keeps its samples: a breakaway is at least the force the
// rod held at rest, 9.6 N here.
TEST(FrictionSegmentsTest, AForceRisingFasterThanTheSamplingIsNotSmoothedAway) {
  const CutLogs logs =
      SmoothStickStrokes(VerticalTruth(0.11, {15.6, 0.14, 12.9, 0.0047}, {3.4, 0.13, 11.5, 0.0038}),
                         Strokes(1, 250, {0.54, 0.67, 0.93}, 0.0), "F");
  // Smoothed: 3.3 N and 8.4 N. The positive breakaway lies between samples
  // still: bounded by the force held at rest, not read.
  const double positive = ReadOffLogs(logs.data, +1, {}).value[0];
  EXPECT_GT(positive, 0.6 * 15.6);
  EXPECT_LT(positive, 1.05 * 15.6);
  EXPECT_NEAR(ReadOffLogs(logs.data, -1, {}).value[0], 3.4, 0.15 * 3.4);
}

// A forward replay's weights fall with the time since breakaway faster when
// the breakaway's timing error counts, the more so at a low sample rate;
// the backward half of a two-sided segment is left as it was.
TEST(FrictionSegmentsTest, TheBreakawaysTimingErrorWidensOnlyTheForwardReplay) {
  const Unit unit = TurningStrokes(500, 0.44);
  FrictionFitOptions untimed;
  untimed.breakaway_timing_per_s = 0;
  const StrokeData with = PrepareStrokes(unit, FrictionFitOptions{});
  const StrokeData without = PrepareStrokes(unit, untimed);
  ASSERT_EQ(with.segments.size(), without.segments.size());
  int widened = 0;
  for (std::size_t k = 0; k < with.segments.size(); ++k) {
    const Segment& a = with.segments[k];
    const Segment& b = without.segments[k];
    ASSERT_EQ(a.weight.size(), b.weight.size());
    for (std::size_t i = 0; i < a.weight.size(); ++i) {
      const std::size_t sample = a.begin + i;
      EXPECT_LE(a.weight[i], b.weight[i]);
      const bool backward = a.two_sided && sample > a.split;
      if (backward || sample <= a.slide_begin) {
        EXPECT_EQ(a.weight[i], b.weight[i]);
      }
    }
    widened += a.direction != 0 && a.weight.back() < 0.5 * b.weight.back() && !a.two_sided;
  }
  EXPECT_GT(widened, 0);
}

// Strokes from stop to stop: a segment that starts at a stop starts where the
// force no longer pushes into it, goes the way the rod leaves, and ends once
// the rod has travelled end_slide_m; with end_slide_m = 0 none starts there.
TEST(FrictionSegmentsTest, ASlideFromAStopIsReplayedFromWhereTheForceLeavesTheStop) {
  const Parameters truth = VerticalTruth(0.75, {11.3, 0.2, 14.7, 0.018}, {15.2, 4.4, 8.8, 0.004});
  const Protocol protocol = Strokes(1, 2000, {0.45, 0.95}, 0.0);
  const Unit unit =
      testing::WriteAndReadUnit(Synthesize(truth, protocol, 3, "E"), "friction_segments_stops");
  const double sigma_m = internal::PositionNoise(unit);
  const FrictionFitOptions options;
  const double zone = options.end_margin_m + 4 * sigma_m, half = 0.5 * truth.cylinder.stroke_m;
  const StrokeData data = PrepareStrokes(unit, options, {}, {true, true});
  int from_stops = 0;
  for (const Segment& s : data.segments) {
    const std::vector<double>& x = *s.position_m;
    const std::vector<double>& force = *s.force_N;
    const int contact =
        x[s.slide_begin] > half - zone ? +1 : (x[s.slide_begin] < zone - half ? -1 : 0);
    if (contact == 0) continue;
    ++from_stops;
    EXPECT_EQ(s.direction, -contact);
    for (std::size_t i = s.begin; i <= s.slide_begin; ++i) EXPECT_LT(contact * force[i], 0) << i;
    for (std::size_t i = s.slide_begin + 3; i < s.end; ++i) {
      EXPECT_LE(std::fabs(x[i] - s.initial_position_m), options.end_slide_m) << i;
    }
  }
  EXPECT_GE(from_stops, 2);
  FrictionFitOptions no_stops;
  no_stops.end_slide_m = 0;
  for (const Segment& s : PrepareStrokes(unit, no_stops, {}, {true, true}).segments) {
    EXPECT_LT(std::fabs((*s.position_m)[s.slide_begin]), half - zone);
  }
}

}  // namespace
}  // namespace pneumaid
