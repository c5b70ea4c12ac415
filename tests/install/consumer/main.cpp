// Loads the installed paper set, simulates the paper's step and exports the
// set as a C header: the library works when linked from its installation.
#include <cstdio>

#include "pneumaid/io/export.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/sim/command.h"
#include "pneumaid/sim/simulate.h"

int main() {
  using namespace pneumaid;
  const Parameters params = LoadParams(PAPER);
  Trajectory run;
  const SimulationSummary summary = Simulate(params, StepCommand({{0.0, 1.0}}), InitialState{},
                                             UniformTimes(0, 1.0, 100), SimulationOptions{}, &run);
  if (!summary.ok()) return 1;
  ExportOptions options;
  options.format = ExportFormat::kCHeader;
  const bool exported =
      ExportParameters(params, options).find("PNEUMAID_UNIT_ID") != std::string::npos;
  std::printf("x(1 s) = %.4f m, %s\n", run.x_m.back(), exported ? "exported" : "no export");
  return exported && run.x_m.back() > 0 ? 0 : 1;
}
