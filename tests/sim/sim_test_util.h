// Helpers shared by the simulator tests.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>

#include "pneumaid/sim/simulate.h"

namespace pneumaid::testing {

// Simulates and fails the test on any solver problem or non-positive pressure.
inline Trajectory MustSimulate(const Parameters& params, const CommandSignal& command,
                               const InitialState& initial, const std::vector<double>& times,
                               const SimulationOptions& options = SimulationOptions{}) {
  Trajectory run;
  const SimulationSummary summary = Simulate(params, command, initial, times, options, &run);
  EXPECT_TRUE(summary.ok()) << summary.BriefReport();
  EXPECT_EQ(run.size(), summary.ok() ? times.size() : run.size());
  if (run.size() > 0) {
    EXPECT_GT(*std::min_element(run.p1_Pa.begin(), run.p1_Pa.end()), 0.0);
    EXPECT_GT(*std::min_element(run.p2_Pa.begin(), run.p2_Pa.end()), 0.0);
  }
  return run;
}

}  // namespace pneumaid::testing
