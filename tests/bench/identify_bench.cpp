// Issue-4 target: the whole `identify` on datasets/paper-rig as bundled
// (reading every log included: valve, pipeline and friction fits) in 2 s or
// less on one core.
#include <benchmark/benchmark.h>

#include "pneumaid/ident/identify.h"
#include "pneumaid/io/rig_data.h"

namespace pneumaid {
namespace {

void BM_IdentifyPaperRig(benchmark::State& state) {
  const std::string dir = std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig";
  for (auto _ : state) {
    const Unit unit = ReadUnit(dir);
    IdentifyReport report;
    const Parameters p = Identify(unit, Parameters{}, IdentifyOptions{}, &report);
    benchmark::DoNotOptimize(&p);  // not the double: see refine_bench.cpp
  }
}
BENCHMARK(BM_IdentifyPaperRig)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace pneumaid
