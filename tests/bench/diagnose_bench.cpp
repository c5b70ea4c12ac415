// Issue-13 target: `diagnose` on one unit with two validation runs (the
// paper's step, about 2 s, and the rich profile, about 4.5 s, at 1 kHz) and
// all 8 candidates in at most 60 s on one core and 35 s with two threads.
// The unit is datasets/hidden/pipeline-lag (synthetic, the rig's mismatch on)
// diagnosed with configs/paper-no-tube.yaml, so that pipeline_lag is a
// candidate too; one effect is named, then a second iteration finds nothing.
#include <benchmark/benchmark.h>

#include <string>

#include "pneumaid/diagnose/diagnose.h"
#include "pneumaid/io/params_yaml.h"

namespace pneumaid {
namespace {

void BM_DiagnoseTwoRunsEightCandidates(benchmark::State& state) {
  const std::string root = PNEUMAID_SOURCE_DIR;
  const Unit unit = ReadUnit(root + "/datasets/hidden/pipeline-lag");
  const Parameters params = LoadParams(root + "/configs/paper-no-tube.yaml");
  DiagnoseOptions options;
  options.threads = static_cast<int>(state.range(0));
  DiagnoseResult result;
  for (auto _ : state) {
    result = Diagnose(params, unit, options);
    benchmark::DoNotOptimize(&result);
  }
  state.counters["candidates"] = static_cast<double>(result.iterations.front().ranking.size());
  state.counters["named"] = static_cast<double>(result.named_effects.size());
  state.counters["iterations"] = static_cast<double>(result.iterations.size());
}
BENCHMARK(BM_DiagnoseTwoRunsEightCandidates)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace pneumaid
