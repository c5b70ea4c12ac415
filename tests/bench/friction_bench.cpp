// Issue-4 target: the whole friction fit (segmentation, output-error stage,
// covariance) from 10^5 stroke samples in 1 s or less on one core. The logs
// are synthetic (the paper's truth, the stroke part of protocol-full with its
// instruments): five units of seeds 1..5, three cycles per level, merged into
// one unit of about 10^5 samples.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/io/rig_writer.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid {
namespace {

Unit StrokeUnit() {
  Protocol protocol;
  protocol.stroke_levels_V = {0.3, 0.45, 0.6, 0.8, 1.0};
  protocol.stroke_cycles = 3;
  protocol.stroke_max_leg_s = 2.0;
  protocol.sensors["x"] = {5e-6, 0.0, 1e-5, true};
  protocol.sensors["p1"] = {300, 0.0, 0.0, true};
  protocol.sensors["p2"] = {300, 0.0, 0.0, true};
  const std::string dir = std::string(PNEUMAID_BINARY_DIR) + "/friction_bench_unit";
  Unit merged;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const std::string unit_dir = dir + std::to_string(seed);
    std::filesystem::remove_all(unit_dir);  // a previous run's
    WriteDirectoryAtomically(unit_dir, UnitFiles(Synthesize(Parameters{}, protocol, seed, "B")));
    Unit unit = ReadUnit(unit_dir);
    if (seed == 1)
      merged = unit;
    else
      merged.experiments.insert(merged.experiments.end(), unit.experiments.begin(),
                                unit.experiments.end());
  }
  return merged;
}

void BM_FrictionFit100kSamples(benchmark::State& state) {
  static const Unit unit = StrokeUnit();
  std::size_t samples = 0;
  for (const auto& e : unit.experiments) samples += e.samples();
  FrictionParams prior;  // 30 % off the truth
  for (StribeckParams* p : {&prior.positive, &prior.negative}) {
    p->static_force_N *= 1.3;
    p->dynamic_force_N *= 0.7;
    p->viscous_N_s_per_m *= 1.3;
    p->stribeck_velocity_m_per_s *= 0.7;
  }
  FrictionFitResult fit;
  for (auto _ : state) {
    fit = FitFriction(unit, prior, FrictionFitOptions{});
    benchmark::DoNotOptimize(fit.final_cost);
  }
  state.counters["samples"] = static_cast<double>(samples);
  state.counters["segments"] = fit.segments;
  state.counters["iterations"] = fit.iterations;
}
BENCHMARK(BM_FrictionFit100kSamples)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace pneumaid
