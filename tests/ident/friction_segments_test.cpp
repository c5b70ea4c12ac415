// How the friction fit cuts stroke logs into replay segments
// (src/ident/friction_segments.h): where a slide breaks away, which slides
// are replayed from their arrest, and the weights of a forward replay. On
// logs the fitted model did not make (smooth stick, tight tolerances).
#include "../../src/ident/friction_segments.h"
#include "../../src/ident/friction_starts.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "../synth/synth_test_util.h"
#include "friction_test_util.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid {
namespace {

using friction_internal::BreakawayMedian;
using friction_internal::PrepareStrokes;
using friction_internal::Segment;
using friction_internal::StrokeData;
using friction_internal::StuckBand;

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

StrokeData Prepare(const Unit& unit, const FrictionFitOptions& options) {
  const double sigma_m = unit.manifest.DeclaredSigma("x", 1e-5);
  return PrepareStrokes(unit, options, StuckBand(options, sigma_m), sigma_m);
}

// A slide replayed backward from its arrest must arrive there in its own
// direction; one that turned back on the way is replayed forward only.
TEST(FrictionSegmentsTest, ASlideThatTurnsBackBeforeItStopsIsReplayedForwardOnly) {
  const Unit unit = TurningStrokes(2000, 0.44);
  const FrictionFitOptions options;
  const StrokeData data = Prepare(unit, options);
  const double band = StuckBand(options, unit.manifest.DeclaredSigma("x", 1e-5));
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
  Parameters truth;  // vertical
  truth.cylinder.load_mass_kg = 1.15;
  truth.friction.positive = {19.9, 1.12, 12.2, 0.0045};
  truth.friction.negative = {10.7, 0.67, 7.3, 0.0022};
  Protocol protocol = testing::StrokeProtocol(2);
  protocol.sample_rate_Hz = 500;
  protocol.stroke_levels_V = {0.5, 0.7, 0.9};
  protocol.stroke_margin_m = 0.005;
  protocol.mismatch.regularized_friction = true;
  protocol.mismatch.stick_velocity_m_per_s = 1e-4;
  protocol.mismatch.relative_tolerance = 1e-8;
  const Unit unit =
      testing::WriteAndReadUnit(Synthesize(truth, protocol, 3, "B"), "friction_segments_breakaway");
  const StrokeData data = Prepare(unit, FrictionFitOptions{});
  // Within 15 % (the rod escapes while the force still rises, for a sample
  // or two at 500 Hz: 12.2 N for 10.7).
  EXPECT_NEAR(BreakawayMedian(data, +1, 0.0), 19.9, 0.15 * 19.9);
  EXPECT_NEAR(BreakawayMedian(data, -1, 0.0), 10.7, 0.15 * 10.7);
}

// A forward replay's weights fall with the time since breakaway faster when
// the breakaway's timing error counts, the more so at a low sample rate;
// the backward half of a two-sided segment is left as it was.
TEST(FrictionSegmentsTest, TheBreakawaysTimingErrorWidensOnlyTheForwardReplay) {
  const Unit unit = TurningStrokes(500, 0.44);
  FrictionFitOptions untimed;
  untimed.breakaway_timing_per_s = 0;
  const StrokeData with = Prepare(unit, FrictionFitOptions{});
  const StrokeData without = Prepare(unit, untimed);
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

}  // namespace
}  // namespace pneumaid
