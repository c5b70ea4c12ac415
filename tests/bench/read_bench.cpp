// Issue-3 target: reading a 10^6-row stroke CSV (file to SI columns, all
// checks included) at 50 MB/s or more on one core.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "pneumaid/io/files.h"
#include "pneumaid/io/rig_data.h"

namespace pneumaid {
namespace {

// A stroke log as a rig writes it: 7 columns, 7 significant digits.
std::string MakeStrokeLog(int rows) {
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::string text =
      "# benchmark log\nt [s],u [V],x [mm],p1 [bar_g],p2 [bar_g],q1 [l/min],q2 [l/min]\n";
  char line[160];
  for (int i = 0; i < rows; ++i) {
    const double t = i * 1e-3;
    std::snprintf(line, sizeof(line), "%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g\n", t, 0.6,
                  25.0 + 24.0 * std::sin(t), 2.0 + 0.01 * noise(rng), 1.0 + 0.01 * noise(rng),
                  3.0 * std::cos(t), -2.0 * std::cos(t));
    text += line;
  }
  return text;
}

void BM_ReadStrokeCsv(benchmark::State& state) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "pneumaid_read_bench.csv").string();
  const std::string text = MakeStrokeLog(static_cast<int>(state.range(0)));
  std::ofstream(path, std::ios::binary) << text;
  Manifest manifest;
  manifest.rig.position_origin = PositionOrigin::kRetracted;
  ExperimentEntry entry;
  entry.id = "bench";
  entry.kind = ExperimentKind::kStroke;
  for (auto _ : state) {
    const Experiment experiment = ParseExperiment(ReadTextFile(path, "CSV"), path, entry, manifest);
    benchmark::DoNotOptimize(experiment.columns.size());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) *
                          static_cast<int64_t>(text.size()));
  state.counters["rows"] = static_cast<double>(state.range(0));
  std::filesystem::remove(path);
}
// Real time: the hash runs on a second thread, so CPU time of this one would flatter.
BENCHMARK(BM_ReadStrokeCsv)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace pneumaid
