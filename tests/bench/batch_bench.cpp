// Issue-14 target: units per minute of `batch` at -j 1 and -j 2 (scaling at
// least 1.8x): 100 synthetic units identified, 20 identified and refined.
// The fleet is made once per process with the synthetic rig
// (configs/protocol-fleet.yaml, the paper's truth with 5-15 % spread, seeds
// 1000+i) under the build directory.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "pneumaid/batch/batch.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/protocol.h"
#include "pneumaid/io/rig_writer.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;
const std::string kSource = PNEUMAID_SOURCE_DIR;

std::string Fleet(int units) {
  const fs::path dir =
      fs::path(PNEUMAID_BINARY_DIR) / ("batch_bench_fleet_" + std::to_string(units));
  if (fs::exists(dir / "done")) return dir.string();
  fs::remove_all(dir);
  fs::create_directories(dir);
  const Parameters truth = LoadParams(kSource + "/configs/paper.yaml");
  const Protocol protocol = LoadProtocol(kSource + "/configs/protocol-fleet.yaml");
  for (int i = 0; i < units; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "BENCH-%04d", i);
    Parameters unit = truth;
    unit.unit = name;
    const double wobble = 1.0 + 0.05 * std::sin(1.7 * i);  // deterministic spread
    unit.friction.positive.static_force_N *= wobble;
    unit.friction.negative.dynamic_force_N *= 2.0 - wobble;
    unit.valve.increasing.q_max_kg_per_s *= 1.0 + 0.03 * std::cos(2.3 * i);
    WriteDirectoryAtomically((dir / name).string(),
                             UnitFiles(Synthesize(unit, protocol, 1000 + i, name)));
  }
  std::ofstream(dir / "done") << "made\n";
  return dir.string();
}

void RunBatchBench(benchmark::State& state, int units, bool refine) {
  const std::string fleet = Fleet(units);
  BatchOptions options;
  options.prior = LoadParams(kSource + "/configs/paper.yaml");
  options.identify.tool_version = "bench";
  options.refine = refine;
  if (refine) options.spec = LoadFitSpec(kSource + "/configs/fit-default.yaml");
  options.jobs = static_cast<int>(state.range(0));
  int failed = 0;
  for (auto _ : state) {
    const fs::path results = fs::path(PNEUMAID_BINARY_DIR) / "batch_bench_results";
    fs::remove_all(results);
    const BatchSummary summary = RunBatch(fleet, results.string(), options);
    failed = summary.failed();
    benchmark::DoNotOptimize(&summary);
  }
  state.counters["units"] = units;
  state.counters["failed"] = failed;
  state.counters["units_per_min"] = benchmark::Counter(
      60.0 * units * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_BatchIdentify100Units(benchmark::State& state) { RunBatchBench(state, 100, false); }
BENCHMARK(BM_BatchIdentify100Units)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

void BM_BatchRefine20Units(benchmark::State& state) { RunBatchBench(state, 20, true); }
BENCHMARK(BM_BatchRefine20Units)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace pneumaid
