// Issue-4 target: the whole friction fit (segmentation, output-error stage,
// covariance) from 10^5 stroke samples in 1 s or less on one core. The logs
// are synthetic (the paper's truth, the stroke part of protocol-full with its
// instruments): units of seeds 1, 2, ..., three cycles per level, merged until
// the stroke logs hold at least 10^5 samples (four units, 108 840 samples).
#include <benchmark/benchmark.h>

#include <filesystem>

#include "../ident/friction_test_util.h"
#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/io/rig_writer.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid {
namespace {

Unit StrokeUnit() {
  const Protocol protocol = testing::StrokeProtocol(3);
  const std::string dir = std::string(PNEUMAID_BINARY_DIR) + "/friction_bench_unit";
  Unit merged;
  std::size_t samples = 0;
  for (std::uint64_t seed = 1; samples < 100'000; ++seed) {
    const std::string unit_dir = dir + std::to_string(seed);
    std::filesystem::remove_all(unit_dir);  // a previous run's
    WriteDirectoryAtomically(unit_dir, UnitFiles(Synthesize(Parameters{}, protocol, seed, "B")));
    Unit unit = ReadUnit(unit_dir);
    if (seed == 1)
      merged = unit;
    else
      merged.experiments.insert(merged.experiments.end(), unit.experiments.begin(),
                                unit.experiments.end());
    for (const auto& e : unit.experiments) samples += e.samples();
  }
  return merged;
}

void BM_FrictionFit100kSamples(benchmark::State& state) {
  static const Unit unit = StrokeUnit();
  std::size_t samples = 0;
  for (const auto& e : unit.experiments) samples += e.samples();
  const FrictionParams prior = testing::ThirtyPercentOff(Parameters{}.friction);
  FrictionFitResult fit;
  for (auto _ : state) {
    fit = FitFriction(unit, prior, FrictionFitOptions{});
    // Not the double itself: see refine_bench.cpp.
    benchmark::DoNotOptimize(&fit);
  }
  state.counters["samples"] = static_cast<double>(samples);
  state.counters["segments"] = fit.segments;
  state.counters["iterations"] = fit.iterations;
}
BENCHMARK(BM_FrictionFit100kSamples)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace pneumaid
