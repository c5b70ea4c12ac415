// What the CVODE callbacks of a run share (internal to src/sim/): the model's
// layout and coefficients, the motion mode, and the stick/slip and end-stop
// switching surfaces, templated so that the event sensitivities can
// differentiate them.
#pragma once

#include <ceres/jet.h>

#include <cmath>
#include <memory>
#include <string>
#include <type_traits>

#include "pneumaid/model/actuator.h"
#include "pneumaid/sim/simulate.h"

// For the right-hand-side callbacks: inline everything they call. GCC 12
// leaves the Jet arithmetic as calls into Eigen otherwise (-11 % instructions
// with 10 sensitivities). Off under the sanitizers, where the instrumented,
// flattened Jet code takes GCC minutes and gigabytes per file.
#if defined(__SANITIZE_ADDRESS__)
#define PNEUMAID_FLATTEN
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PNEUMAID_FLATTEN
#endif
#endif
#ifndef PNEUMAID_FLATTEN
#define PNEUMAID_FLATTEN [[gnu::flatten]]
#endif

namespace pneumaid::internal {

using JetN = ceres::Jet<double, kMaxStates>;

inline double Value(double x) { return x; }
template <int N>
inline double Value(const ceres::Jet<double, N>& x) {
  return x.a;
}

class ParameterJets;  // parameter_jets.h: the model's derivatives in the free parameters

// Everything the CVODE callbacks need. The command changes between segments;
// the layout and coefficients are fixed for the run.
struct ModelData {
  ActuatorLayout layout;
  ActuatorCoefficients<double> coefficients;
  ActuatorCoefficients<JetN> jet_coefficients;
  ValveCommand command;
  MotionMode motion = MotionMode::kRegularized;
  double supply_pressure_Pa = 0.0;
  double breakaway_margin_N = 0.0;
  // A sliding rod counts as stopped once v has crossed zero by this much:
  // right after a restart v is only known to within its tolerance.
  double reversal_velocity_m_per_s = 0.0;
  std::string last_solver_message;
  FrictionUse friction_use;  // what the run read of the friction so far
  // Parameter sensitivities: how many (0: none), and the model's
  // derivatives with respect to each (null without).
  int parameter_count = 0;
  std::unique_ptr<const ParameterJets> parameter_jets;
};

// Within a nanometre of an end stop: a rod resting there is set exactly on
// it, this margin only absorbs round-off.
constexpr double kAtStop_m = 1e-9;

inline bool AtExtendedStop(const ModelData& data, double position_m) {
  return position_m >= data.coefficients.end_stop.half_stroke_m - kAtStop_m;
}
inline bool AtRetractedStop(const ModelData& data, double position_m) {
  return position_m <= -data.coefficients.end_stop.half_stroke_m + kAtStop_m;
}

// Notes in `use` the breakaway tests of a rod at rest at position x under
// the driving force `force_N` (each side's unless an end stop holds it that
// way), with the friction's pressure scale `scale`.
inline void NoteBreakawayTests(const ModelData& data, double force_N, double scale, double x,
                               FrictionUse* use) {
  if (!(scale > 0) || !std::isfinite(force_N)) {  // no test to read: count both sides as read
    use->NoteSliding(0);
    use->NoteSliding(1);
    return;
  }
  const double margin = data.breakaway_margin_N;
  if (!AtExtendedStop(data, x)) use->NoteBreakawayTest(0, (force_N - margin) / scale);
  if (!AtRetractedStop(data, x)) use->NoteBreakawayTest(1, (-force_N - margin) / scale);
}

// Stick/slip and end-stop switching surfaces. Stuck: the driving force
// reaches the breakaway force plus a margin (the switching hysteresis) in a
// direction the rod can move. Sliding: the velocity returns to zero (g0) or
// the rod reaches the end of the stroke (g1). Templated so that the event
// sensitivities can differentiate them. With `use` (double only), a stuck
// rod's breakaway tests are noted there (SimulationOptions::
// record_friction_use); the plain root function passes none, and the test
// folds away where it is inlined.
template <typename T>
void SwitchingValues(const ModelData& data, const ActuatorCoefficients<T>& c, const T* y, T* g,
                     FrictionUse* use = nullptr) {
  const T half_stroke = c.end_stop.half_stroke_m;
  const T margin(data.breakaway_margin_N);
  const T reversal(data.reversal_velocity_m_per_s);
  switch (data.motion) {
    case MotionMode::kStuck: {
      const ChamberPressures<T> p = DecodeChambers(c, y);
      const T force = DrivingForce(c, y, p);
      const double x = Value(y[kPosition]);
      g[0] = AtExtendedStop(data, x) ? T(-1.0) : force - BreakawayForce(c, p, +1.0) - margin;
      g[1] = AtRetractedStop(data, x) ? T(1.0) : force + BreakawayForce(c, p, -1.0) + margin;
      if constexpr (std::is_same_v<T, double>) {
        if (use != nullptr) NoteBreakawayTests(data, force, FrictionScale(c, p), x, use);
      }
      break;
    }
    case MotionMode::kSlidingPositive:
      g[0] = y[kVelocity] + reversal;
      g[1] = half_stroke - y[kPosition];
      break;
    case MotionMode::kSlidingNegative:
      g[0] = y[kVelocity] - reversal;
      g[1] = y[kPosition] + half_stroke;
      break;
    case MotionMode::kRegularized:
      g[0] = g[1] = T(1.0);
      break;
  }
}

}  // namespace pneumaid::internal
