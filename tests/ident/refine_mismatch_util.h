// The heavy horizontal unit that the refinement's screen and robust-refit
// tests write with model mismatch, the friction tolerances, and what
// the refinement tests share (the default spec, a parameter's value by path).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "../synth/synth_test_util.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/parameter_table.h"
#include "refine_test_util.h"

namespace pneumaid::testing {

// The default fit spec, as `identify --refine` uses it.
inline const std::string kDefaultFitSpec =
    std::string(PNEUMAID_SOURCE_DIR) + "/configs/fit-default.yaml";

// configs/paper-horizontal.yaml with a 1.4 kg load: the truth of the
// mismatch tests (their friction is each test's).
inline Parameters HeavyHorizontalTruth() {
  Parameters truth =
      LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper-horizontal.yaml");
  truth.cylinder.load_mass_kg = 1.4;
  return truth;
}

// configs/paper-horizontal.yaml with `load_kg` and the friction given.
inline Parameters HorizontalTruth(double load_kg, const StribeckParams& positive,
                                  const StribeckParams& negative) {
  Parameters truth = HeavyHorizontalTruth();
  truth.cylinder.load_mass_kg = load_kg;
  truth.friction.positive = positive;
  truth.friction.negative = negative;
  return truth;
}

// One stroke cycle at 0.5, 0.7 and 0.9 V, written with model mismatch:
// smooth stick (creep below 0.1 mm/s), the rig integrated at rtol 1e-8;
// synthetic, from `truth` and `seed`, through the test's temporary `dir`.
inline Unit MismatchedStrokes(const Parameters& truth, std::uint64_t seed, const std::string& id,
                              const std::string& dir) {
  Protocol protocol = RefinementProtocol({0.5, 0.7, 0.9}, false);
  protocol.mismatch.regularized_friction = true;
  protocol.mismatch.stick_velocity_m_per_s = 1e-4;
  protocol.mismatch.relative_tolerance = 1e-8;
  return WriteAndReadUnit(Synthesize(truth, protocol, seed, id), dir);
}

// Strokes at `levels`, `cycles` of them, that stop 5 mm short of the ends,
// logged at 500 Hz, the rig integrated at rtol 1e-8: a light rod sticks and
// slips all along, and reverses where no stop resets a slide's error.
inline Protocol ShortStrokesAt500Hz(std::vector<double> levels, int cycles) {
  Protocol protocol = RefinementProtocol(std::move(levels), false);
  protocol.stroke_cycles = cycles;
  protocol.stroke_margin_m = 0.005;
  protocol.sample_rate_Hz = 500;
  protocol.mismatch.relative_tolerance = 1e-8;
  return protocol;
}

// A refinement test's truth, start and unit.
struct RefineCase {
  Parameters truth, start;
  Unit unit;
};

inline double ParameterValue(const Parameters& p, const std::string& path) {
  double value = NAN;
  EXPECT_TRUE(GetParameter(p, path, &value)) << path;
  return value;
}

// Issue 12's tolerances on every friction coefficient: Fs, Fd 5 % or 0.1 N;
// b 15 % or 0.5 N s/m; vs 25 % or 1 mm/s.
inline void ExpectFrictionWithinTolerance(const Parameters& fit, const Parameters& truth) {
  for (const char* direction : {"positive", "negative"}) {
    const std::string p = std::string("friction.") + direction + ".";
    const auto near = [&](const char* name, double fraction, double floor) {
      const double t = ParameterValue(truth, p + name);
      EXPECT_NEAR(ParameterValue(fit, p + name), t, std::max(fraction * t, floor)) << p + name;
    };
    near("Fs", 0.05, 0.1);
    near("Fd", 0.05, 0.1);
    near("b", 0.15, 0.5);
    near("vs", 0.25, 1e-3);
  }
}

}  // namespace pneumaid::testing
