// Synthetic stroke logs for the friction fit's tests and benchmark.
#pragma once

#include <string>

#include "pneumaid/io/protocol.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid::testing {

// The stroke part of configs/protocol-full.yaml (its levels, legs and
// instruments), with `cycles` cycles per level.
inline Protocol StrokeProtocol(int cycles) {
  Protocol protocol =
      LoadProtocol(std::string(PNEUMAID_SOURCE_DIR) + "/configs/protocol-full.yaml");
  protocol.valve = false;
  protocol.tube_lengths_m.clear();
  protocol.paper_step = protocol.rich_profile = false;
  protocol.stroke_cycles = cycles;
  return protocol;
}

// StrokeProtocol at `levels`, written with model mismatch: stick as a
// smooth law (creep below 0.1 mm/s), the rig integrated at rtol 1e-8.
inline Protocol MismatchedStrokeProtocol(int cycles, std::vector<double> levels) {
  Protocol protocol = StrokeProtocol(cycles);
  protocol.stroke_levels_V = std::move(levels);
  protocol.mismatch.regularized_friction = true;
  protocol.mismatch.stick_velocity_m_per_s = 1e-4;
  protocol.mismatch.relative_tolerance = 1e-8;
  return protocol;
}

// Every coefficient `fraction` off the truth, in the direction that makes
// breakaway later and sliding friction different.
inline FrictionParams FractionOff(const FrictionParams& truth, double fraction) {
  FrictionParams off = truth;
  for (StribeckParams* p : {&off.positive, &off.negative}) {
    p->static_force_N *= 1 + fraction;
    p->dynamic_force_N *= 1 - fraction;
    p->viscous_N_s_per_m *= 1 + fraction;
    p->stribeck_velocity_m_per_s *= 1 - fraction;
  }
  return off;
}

// A poor prior: every coefficient 30 % off the truth.
inline FrictionParams ThirtyPercentOff(const FrictionParams& truth) {
  return FractionOff(truth, 0.3);
}

}  // namespace pneumaid::testing
