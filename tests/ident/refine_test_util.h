// Synthetic units for the refinement's tests and benchmark.
#pragma once

#include <filesystem>
#include <string>

#include "pneumaid/io/protocol.h"
#include "pneumaid/io/rig_writer.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid::testing {

// configs/protocol-full.yaml's instruments with one stroke cycle at each of
// `levels` (an experiment each, about 2 s at the levels used here), the valve
// and tube tests the component fits need when `with_bench_tests`, and the
// paper's step and the richer profile as the held-out validation runs.
inline Protocol RefinementProtocol(std::vector<double> levels, bool with_bench_tests) {
  Protocol protocol =
      LoadProtocol(std::string(PNEUMAID_SOURCE_DIR) + "/configs/protocol-full.yaml");
  protocol.stroke_levels_V = std::move(levels);
  protocol.stroke_cycles = 1;
  protocol.valve = with_bench_tests;
  if (!with_bench_tests) protocol.tube_lengths_m.clear();
  return protocol;
}

// The ten levels of the refinement benchmark: ten experiments of about 2 s.
inline std::vector<double> TenLevels() {
  return {0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95, 1.0};
}

}  // namespace pneumaid::testing
