#include <filesystem>
#include <iostream>
#include <string>

#include "commands.h"
#include "pneumaid/batch/batch.h"
#include "pneumaid/diagnose/diagnose.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/report/report.h"

namespace pneumaid::cli {
namespace {

struct ReportArgs {
  std::string params_path, unit_dir, diagnose_dir, results_dir, out_path;
};

// A diagnose output directory (report.md, params.yaml, report.json) read back,
// the runs simulated with the set diagnosed and with the augmented one.
DiagnoseReportInput ReadDiagnoseOutput(const std::string& dir, const Parameters& before,
                                       const Unit& unit) {
  namespace fs = std::filesystem;
  for (const char* name : kDiagnoseOutputFiles) {
    if (!fs::exists(fs::path(dir) / name)) {
      throw InputError(dir, 0, 0, std::string("not a diagnose output directory: no ") + name);
    }
  }
  DiagnoseReportInput input;
  input.markdown = ReadTextFile(dir + "/report.md", "a diagnose report (Markdown)");
  input.before_params = before;
  input.after_params = LoadParams(dir + "/params.yaml");
  input.named_effects = ReadNamedEffects(dir + "/report.json", unit.manifest.unit);
  ValidationOptions runs;
  runs.experiment_ids = SimulableRuns(unit);
  input.before = ValidateUnit(input.before_params, unit, runs);
  input.after = ValidateUnit(input.after_params, unit, runs);
  return input;
}

int RunReport(const ReportArgs& args) {
  std::vector<std::string> inputs = {args.params_path, args.unit_dir, args.results_dir};
  if (!args.diagnose_dir.empty()) {
    for (const char* name : kDiagnoseOutputFiles) inputs.push_back(args.diagnose_dir + "/" + name);
  }
  RefuseOverwritingInputs({args.out_path}, inputs);
  std::string html;
  if (!args.results_dir.empty()) {
    if (!args.unit_dir.empty() || !args.params_path.empty() || !args.diagnose_dir.empty())
      throw InputError("--results", 0, 0, "a fleet report takes no unit, --params or --diagnose");
    html = FleetReportHtml(MergeResults({args.results_dir}), ReportOptions{});
  } else {
    if (args.unit_dir.empty() || args.params_path.empty())
      throw InputError("report", 0, 0, "expected a unit directory and --params (or --results)");
    const Parameters params = LoadParams(args.params_path);
    const Unit unit = ReadUnit(args.unit_dir);
    html = args.diagnose_dir.empty()
               ? UnitReportHtml(params, unit, ReportOptions{})
               : DiagnoseReportHtml(ReadDiagnoseOutput(args.diagnose_dir, params, unit), unit,
                                    ReportOptions{});
  }
  WriteHtml(args.out_path, html);
  return kSuccess;
}

}  // namespace

CommandRunner AddReportCommand(CLI::App* app) {
  auto args = std::make_shared<ReportArgs>();
  app->add_option("unit", args->unit_dir, "unit directory");
  app->add_option("--params", args->params_path, "parameter set (params-v1)");
  app->add_option("--diagnose", args->diagnose_dir,
                  "a diagnose output directory of this unit and parameter set: its report");
  app->add_option("--results", args->results_dir, "a batch results directory: the fleet report");
  app->add_option("--out", args->out_path, "the report (one self-contained HTML file)")
      ->required()
      ->check(InExistingDirectory);
  return [args]() { return RunReport(*args); };
}

void AddHtmlOption(CLI::App* app, std::string* path) {
  // Checked before the command runs: a page that cannot be written must not
  // leave the command's other outputs behind.
  app->add_option("--html", *path, "also write a self-contained HTML report here")
      ->check(InExistingDirectory);
}

void WriteHtml(const std::string& path, const std::string& html) {
  if (path.empty()) return;
  WriteFileAtomically(path, html);
  std::cout << "wrote " << path << " (" << html.size() / 1024 << " KiB)\n";
}

}  // namespace pneumaid::cli
