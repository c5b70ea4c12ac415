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

// A poor prior: every coefficient 30 % off the truth, in the direction that
// makes breakaway later and sliding friction different.
inline FrictionParams ThirtyPercentOff(const FrictionParams& truth) {
  FrictionParams prior = truth;
  for (StribeckParams* p : {&prior.positive, &prior.negative}) {
    p->static_force_N *= 1.3;
    p->dynamic_force_N *= 0.7;
    p->viscous_N_s_per_m *= 1.3;
    p->stribeck_velocity_m_per_s *= 0.7;
  }
  return prior;
}

}  // namespace pneumaid::testing
