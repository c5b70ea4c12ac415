// Issue-15 targets: a unit's report in under 1 s (datasets/paper-rig: 12
// experiments at 1 kHz; its simulations included, no fit) and the fleet's
// report from its batch results in under 3 s (datasets/fleet, 14 units,
// identified once before timing).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "../report/fleet_results_util.h"
#include "pneumaid/batch/batch.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/report/report.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;
const std::string kSource = PNEUMAID_SOURCE_DIR;

void BM_UnitReport(benchmark::State& state) {
  const Parameters params = LoadParams(kSource + "/datasets/paper-rig/truth.yaml");
  std::size_t bytes = 0;
  for (auto _ : state) {
    const Unit unit = ReadUnit(kSource + "/datasets/paper-rig");
    bytes = UnitReportHtml(params, unit, ReportOptions{}).size();
  }
  state.counters["MB"] = bytes / 1e6;
}
BENCHMARK(BM_UnitReport)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_FleetReport(benchmark::State& state) {
  const std::string results =
      testing::IdentifyBundledFleet(fs::path(PNEUMAID_BINARY_DIR) / "report_bench_fleet", "bench");
  std::size_t bytes = 0;
  for (auto _ : state) {
    bytes = FleetReportHtml(MergeResults({results}), ReportOptions{}).size();
  }
  state.counters["MB"] = bytes / 1e6;
}
BENCHMARK(BM_FleetReport)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
}  // namespace pneumaid
